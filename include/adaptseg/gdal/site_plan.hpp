#pragma once
/// @file
/// The plan of a survey that respects its site: the lawnmower inside the site's polygon
/// (survey_site), a take-off point on the site, a minimum height above the ground, the terrain
/// followed from a DEM (follow_terrain), the site's polygon as the geofence (site_fence) with
/// every leg kept inside it (FenceRouter: legs that would cut a concave corner or cross a hole
/// fly through via points), the flight split into sorties that fit a battery
/// (split_into_sorties), and the warnings a person should read before flying it: where the site
/// is, how large, how long. What adaptseg_plan runs; it writes the files. CMake target
/// adaptseg::gdal.
///
/// @code
/// const adaptseg::SurveySite site = adaptseg::load_survey_site("site.geojson");
/// adaptseg::SitePlanOptions options;
/// options.gsd_cm = 10.0;
/// options.home = adaptseg::GeoPoint{25.2003, 55.3004, 0.0};
/// options.max_flight_s = 15 * 60.0;
/// const adaptseg::SitePlan plan = adaptseg::plan_site(site, options);
/// for (const auto& w : plan.warnings) std::fprintf(stderr, "warning: %s\n", w.c_str());
/// @endcode

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/gdal/elevation_model.hpp>
#include <adaptseg/gdal/site_fence.hpp>
#include <adaptseg/gdal/site_lawnmower.hpp>
#include <adaptseg/gdal/survey_site.hpp>
#include <adaptseg/geo/fence_route.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/geo/mission_export.hpp>
#include <adaptseg/geo/sorties.hpp>
#include <adaptseg/vision/detail/number_text.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

/// Settings of plan_site(), validated once there.
struct SitePlanOptions {
  double gsd_cm = 0.0;         ///< GSD of the survey [cm/px]; required
  SiteSurveyOptions survey{};  ///< overlap and inside margin (its start_xy is set from the home point)
  CameraParams camera{};
  TimingParams timing{};
  double hold_s = 1.0;  ///< hold at every waypoint [s] (the mission files' NAV_WAYPOINT param1)
  /// The take-off and home point (latitude, longitude; altitude unused): it must lie on the
  /// site, inside the geofence. Empty: the ground under the first waypoint.
  std::optional<GeoPoint> home;
  /// The lowest a waypoint may fly above the ground [m] (with a DEM: above the highest ground
  /// under its footprint and along every leg). 10 m clears people, vehicles and most crops; a
  /// survey below it is refused, naming the GSD that flies at it.
  double min_altitude_m = 10.0;
  /// The longest sortie [s] from take-off to landing (a battery's usable flight time, less a
  /// reserve); empty: one sortie.
  std::optional<double> max_flight_s;
  /// The geofence's vertex limit (the firmware's, firmware_fence_vertex_limit); the outline is
  /// simplified by at most half the inside margin to fit. Empty: no limit.
  std::optional<std::size_t> fence_max_vertices;
  // Thresholds of the warnings (not errors): a plan beyond them is flown as planned.
  std::size_t warn_waypoints = 1000;  ///< more waypoints than this
  double warn_flight_s = 2 * 3600.0;  ///< more flight, all sorties together [s]
  double warn_sortie_s = 30 * 60.0;   ///< one unsplit sortie longer than this [s]: longer than batteries last
  double warn_min_area_m2 = 100.0;    ///< a site smaller than this [m^2]: a footprint or two
  double warn_max_area_m2 = 10e6;     ///< a site larger than this [m^2] (10 km^2)

  /// @throws std::invalid_argument naming the first invalid member.
  void validate() const {
    detail::require_positive(gsd_cm, "SitePlanOptions: gsd_cm");
    survey.validate();
    (void)CameraModel(camera);
    (void)TimingModel(timing);
    detail::require(std::isfinite(hold_s) && hold_s >= 0.0, "SitePlanOptions: hold_s must be finite and >= 0", hold_s);
    detail::require(std::isfinite(min_altitude_m) && min_altitude_m >= 0.0,
                    "SitePlanOptions: min_altitude_m must be finite and >= 0", min_altitude_m);
    detail::require(!max_flight_s || (std::isfinite(*max_flight_s) && *max_flight_s > 0.0),
                    "SitePlanOptions: max_flight_s must be finite and > 0", max_flight_s.value_or(0.0));
    detail::require(!home || (std::isfinite(home->latitude_deg) && std::abs(home->latitude_deg) <= 90.0 &&
                              std::isfinite(home->longitude_deg) && std::abs(home->longitude_deg) <= 180.0),
                    "SitePlanOptions: home must have a latitude in [-90, 90] and a longitude in [-180, 180]; latitude",
                    home ? home->latitude_deg : 0.0);
  }
};

/// A point a sortie flies through: a survey waypoint (its image) or a via point.
struct RoutePoint {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();  ///< site frame [m], z above home
  std::optional<std::size_t> image;  ///< its index in SiteSurvey::waypoints; empty: a via point (no hold, no image)
};

/// A site's plan: what to fly, in how many sorties, and what to read first.
struct SitePlan {
  SiteSurvey survey;      ///< the waypoints (z: above home; with a DEM, following the terrain) and the coverage
  double height_m = 0.0;  ///< the height above the ground the GSD flies at [m]
  Eigen::Vector2d home_xy = Eigen::Vector2d::Zero();  ///< take-off point in the site frame [m]
  GeoPoint home;                                      ///< take-off point in WGS84, at the site frame's altitude
  bool home_given = false;                            ///< false: home is the ground under the first waypoint
  std::optional<TerrainFollowing> terrain;            ///< with a DEM
  std::vector<Sortie> sorties;  ///< one, or as many as the flight-time limit needs (over survey.waypoints)
  /// Per sortie, what it flies between the take-off (straight up at home) and the return (the
  /// autopilot's RTL, straight home from the last point): its waypoints and the via points that
  /// keep every leg inside the geofence.
  std::vector<std::vector<RoutePoint>> routes;
  std::size_t via_points = 0;  ///< via points of all routes
  double survey_s = 0.0;       ///< between the waypoints (straight) and their holds, no take-off or return [s]
  double flight_s = 0.0;       ///< every sortie from home and back, along its route [s]
  SiteFence fence;             ///< the geofence in the site frame
  std::vector<GeoFencePolygon> geofence;  ///< the same in WGS84: outer rings inclusion, holes exclusion polygons
  std::vector<std::string> warnings;      ///< one line each, for a person to read before flying

  /// Sortie `k`'s route as a path to export: its waypoints and via points, home and the geofence.
  [[nodiscard]] ExportPath sortie_path(std::size_t k, const SurveySite& site) const {
    std::vector<Waypoint> points;
    for (const RoutePoint& p : routes.at(k)) {
      Waypoint w = p.image ? survey.waypoints[*p.image] : Waypoint{};
      w.position = p.position;
      points.push_back(w);
    }
    ExportPath path = make_export_path(points, GeoReference(site.geo), site.name);
    for (std::size_t i = 0; i < points.size(); ++i) path.waypoints[i].via = !routes[k][i].image.has_value();
    path.home = home;
    path.geofence = geofence;
    return path;
  }
};

namespace detail {

inline std::string where_text(const GeoPoint& g) {
  std::string s(1, '(');  // not "(" + ...: GCC 12's -Wrestrict misfires on it
  s += format_fixed(g.latitude_deg, 6);
  s += ", ";
  s += format_fixed(g.longitude_deg, 6);
  s += ')';
  return s;
}

}  // namespace detail

namespace detail {

/// plan_site's height above the ground for the GSD; refused below the minimum altitude.
inline double site_plan_height(const CameraModel& camera, const SitePlanOptions& options) {
  const double height_m = camera.altitude_m(options.gsd_cm);
  if (height_m < options.min_altitude_m)
    throw std::invalid_argument("the survey would fly " + format_fixed(height_m, 2) + " m above the ground at " +
                                format_fixed(options.gsd_cm, 2) + " cm/px, below the minimum altitude " +
                                format_fixed(options.min_altitude_m, 1) + " m: with this camera fly at least " +
                                format_fixed(std::ceil(camera.gsd_cm(options.min_altitude_m) * 100.0) / 100.0, 2) +
                                " cm/px");
  return height_m;
}

/// plan_site's take-off point given by the user: on the site, or refused with a hint why not
/// (swapped coordinates, too far, off the outline). Sets the plan's home and the lawnmower's
/// start.
inline void place_given_home(const SurveySite& site, const GeoPoint& given, const GeoReference& frame, SitePlan& plan,
                             SiteSurveyOptions& survey) {
  plan.home_given = true;
  plan.home = {given.latitude_deg, given.longitude_deg, site.geo.altitude_m};
  const double from_centre = geodesic_distance_m(site.centre(), plan.home);
  if (looks_swapped(site, plan.home, 1000.0))
    throw std::invalid_argument("the take-off point " + where_text(plan.home) + " lies " +
                                format_fixed(from_centre / 1000.0, 0) + " km from the site, whose centre is " +
                                where_text(site.centre()) +
                                "; swapped, it would lie on the site: are the site's latitude and longitude swapped "
                                "(GeoJSON and KML list longitude first), or the take-off point's (LAT,LON)?");
  if (from_centre > site.radius_m() + 10e3)
    throw std::invalid_argument("the take-off point " + where_text(plan.home) + " lies " +
                                format_fixed(from_centre / 1000.0, 1) + " km from the site, whose centre is " +
                                where_text(site.centre()) + ": take off on the site");
  plan.home_xy = frame.to_field(plan.home).head<2>();
  if (!site.contains(plan.home_xy))
    throw std::invalid_argument("the take-off point " + where_text(plan.home) + " lies " +
                                format_fixed(site.distance_to_edge_m(plan.home_xy), 1) +
                                " m off the site (outside its outline or in a hole): take off on the site, inside the "
                                "geofence the plan carries");
  survey.start_xy = plan.home_xy;
}

/// plan_site's terrain: the waypoints follow `dem`, refused where the DEM lies elsewhere (with
/// the swapped-coordinates hint) or a waypoint flies below the minimum altitude.
inline void follow_site_terrain(const SurveySite& site, const SitePlanOptions& options, const GeoReference& frame,
                                const ElevationModel& dem, SitePlan& plan) {
  if (!dem.elevation_m(plan.home.latitude_deg, plan.home.longitude_deg) &&
      looks_swapped(site, dem.centre(), dem.radius_m()))
    throw std::invalid_argument("the DEM '" + dem.file().string() + "' covers " +
                                format_fixed(dem.radius_m() / 1000.0, 1) + " km around " + where_text(dem.centre()) +
                                ", " + format_fixed(geodesic_distance_m(site.centre(), dem.centre()) / 1000.0, 0) +
                                " km from the site, whose centre is " + where_text(site.centre()) +
                                "; swapped, the site would lie on it: are the site's latitude and longitude swapped "
                                "(GeoJSON and KML list longitude first)?");
  std::vector<Waypoint>& path = plan.survey.waypoints;
  plan.terrain = follow_terrain(path, frame, plan.home_xy, dem, plan.height_m);
  for (std::size_t i = 0; i < path.size(); ++i)
    if (plan.terrain->clearance_m[i] < options.min_altitude_m)
      throw std::invalid_argument("waypoint " + std::to_string(i) + " flies " +
                                  format_fixed(plan.terrain->clearance_m[i], 1) +
                                  " m above the highest ground under its footprint (DEM), below the minimum altitude " +
                                  format_fixed(options.min_altitude_m, 1) + " m: fly a coarser GSD");
}

/// plan_site's legs inside the geofence: the via points of every leg (between waypoints, from
/// home, home), computed once each, and the times along them (every point a stop, the timing
/// model's; holds at the waypoints only).
class SiteLegs {
 public:
  SiteLegs(const SitePlan& plan, const FenceRouter& router, const TimingModel& timing, double margin)
      : path_(plan.survey.waypoints),
        home_xy_(plan.home_xy),
        router_(router),
        timing_(timing),
        margin_(margin),
        home3_(plan.home_xy.x(), plan.home_xy.y(), 0.0),
        legs_(path_.size()),
        out_vias_(path_.size()),
        back_vias_(path_.size()) {
    // Via points between waypoints i - 1 and i, z along the leg.
    for (std::size_t i = 1; i < path_.size(); ++i) {
      const Eigen::Vector3d a = path_[i - 1].position, b = path_[i].position;
      const auto vias =
          route2d(a.head<2>(), b.head<2>(), "from waypoint " + std::to_string(i - 1) + " to " + std::to_string(i));
      double total = 0.0, run = 0.0;
      Eigen::Vector2d prev = a.head<2>();
      for (const auto& v : vias) total += (v - prev).norm(), prev = v;
      total += (b.head<2>() - prev).norm();
      prev = a.head<2>();
      for (const auto& v : vias) {
        run += (v - prev).norm(), prev = v;
        legs_[i].emplace_back(v.x(), v.y(), a.z() + (b.z() - a.z()) * (total > 0.0 ? run / total : 0.0));
      }
    }
  }

  /// Via points from the waypoint before `i` to `i`.
  [[nodiscard]] const std::vector<Eigen::Vector3d>& leg(std::size_t i) const { return legs_[i]; }
  /// Via points from home to waypoint `i`, at its altitude.
  [[nodiscard]] std::vector<Eigen::Vector3d> outbound(std::size_t i) {
    if (!out_vias_[i])
      out_vias_[i] =
          route2d(home_xy_, path_[i].position.head<2>(), "from the take-off to waypoint " + std::to_string(i));
    return at_z(*out_vias_[i], path_[i].position.z());
  }
  /// Via points from waypoint `i` home, at its altitude.
  [[nodiscard]] std::vector<Eigen::Vector3d> back(std::size_t i) {
    if (!back_vias_[i])
      back_vias_[i] = route2d(path_[i].position.head<2>(), home_xy_, "from waypoint " + std::to_string(i) + " home");
    return at_z(*back_vias_[i], path_[i].position.z());
  }
  /// Time from `from` through `vias` to `to`.
  [[nodiscard]] double through(Eigen::Vector3d from, const std::vector<Eigen::Vector3d>& vias,
                               const Eigen::Vector3d& to) const {
    double t = 0.0;
    for (const auto& v : vias) t += timing_.segment_time_s(from, v), from = v;
    return t + timing_.segment_time_s(from, to);
  }
  /// Home on the ground.
  [[nodiscard]] const Eigen::Vector3d& home() const { return home3_; }
  /// Above home at `z`.
  [[nodiscard]] Eigen::Vector3d above_home(double z) const { return {home3_.x(), home3_.y(), z}; }

 private:
  std::vector<Eigen::Vector2d> route2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b,
                                       const std::string& what) const {
    try {
      return router_.route(a, b);
    } catch (const std::invalid_argument&) {
      throw std::invalid_argument("no route inside the geofence " + what + " keeps " + format_fixed(0.5 * margin_, 1) +
                                  " m from its edges: the site is too narrow there for the inside margin");
    }
  }
  static std::vector<Eigen::Vector3d> at_z(const std::vector<Eigen::Vector2d>& vias, double z) {
    std::vector<Eigen::Vector3d> out;
    for (const auto& v : vias) out.emplace_back(v.x(), v.y(), z);
    return out;
  }

  const std::vector<Waypoint>& path_;
  Eigen::Vector2d home_xy_;
  const FenceRouter& router_;
  const TimingModel& timing_;
  double margin_;
  Eigen::Vector3d home3_;
  std::vector<std::vector<Eigen::Vector3d>> legs_;
  std::vector<std::optional<std::vector<Eigen::Vector2d>>> out_vias_, back_vias_;
};

/// plan_site's sorties and their routes along `legs`, the flight and survey times.
inline void route_sorties(const SitePlanOptions& options, const TimingModel& timing, SiteLegs& legs, SitePlan& plan) {
  const std::vector<Waypoint>& path = plan.survey.waypoints;
  plan.sorties = split_into_sorties(
      path.size(), options.max_flight_s,
      [&](std::size_t i) {
        const double z = path[i].position.z();
        return timing.segment_time_s(legs.home(), legs.above_home(z)) +
               legs.through(legs.above_home(z), legs.outbound(i), path[i].position) + options.hold_s;
      },
      [&](std::size_t i) { return legs.through(path[i - 1].position, legs.leg(i), path[i].position) + options.hold_s; },
      [&](std::size_t i) {
        const double z = path[i].position.z();
        return legs.through(path[i].position, legs.back(i), legs.above_home(z)) +
               timing.segment_time_s(legs.above_home(z), legs.home());
      });
  for (const Sortie& s : plan.sorties) {
    plan.flight_s += s.flight_s;
    auto& route = plan.routes.emplace_back();
    for (const auto& v : legs.outbound(s.first)) route.push_back({v, std::nullopt});
    for (std::size_t i = s.first; i < s.end; ++i) {
      if (i > s.first)
        for (const auto& v : legs.leg(i)) route.push_back({v, std::nullopt});
      route.push_back({path[i].position, i});
    }
    for (const auto& v : legs.back(s.end - 1)) route.push_back({v, std::nullopt});
    for (const auto& p : route) plan.via_points += p.image ? 0 : 1;
  }
  plan.survey_s = options.hold_s * static_cast<double>(path.size());
  for (std::size_t k = 1; k < path.size(); ++k)
    plan.survey_s += timing.segment_time_s(path[k - 1].position, path[k].position);
}

/// plan_site's check of every leg a sortie flies over the DEM: up at home, along its route; the
/// return is the autopilot's (at its RTL altitude: a warning).
inline void check_leg_clearance(const SitePlanOptions& options, const GeoReference& frame, const ElevationModel& dem,
                                const SiteLegs& legs, const SitePlan& plan) {
  for (std::size_t k = 0; k < plan.sorties.size(); ++k) {
    const auto& route = plan.routes[k];
    std::vector<Eigen::Vector3d> legs3{legs.above_home(route.front().position.z())};
    for (const auto& p : route) legs3.push_back(p.position);
    std::size_t at = 0;
    const double low = lowest_leg_clearance_m(legs3, frame, dem, plan.terrain->home_ground_m, 2.0, &at);
    if (low < options.min_altitude_m) {
      const auto name = [&](std::size_t r) {
        return route[r].image ? "waypoint " + std::to_string(*route[r].image) : std::string("a via point");
      };
      throw std::invalid_argument(
          (at == 0 ? "the leg from the take-off to " + name(0) : "the leg from " + name(at - 1) + " to " + name(at)) +
          " passes " + format_fixed(low, 1) + " m above the ground (DEM), below the minimum altitude " +
          format_fixed(options.min_altitude_m, 1) + " m: fly a coarser GSD");
    }
  }
}

/// What a person should read before flying the plan.
inline std::vector<std::string> site_plan_warnings(const SurveySite& site, const SitePlanOptions& options,
                                                   const SitePlan& plan) {
  std::vector<std::string> warn;
  const std::size_t waypoints = plan.survey.waypoints.size();
  const double area = site.area_m2();
  if (area < options.warn_min_area_m2 || area > options.warn_max_area_m2)
    warn.push_back("the site's area is " + format_fixed(area, 0) + " m^2 (" + format_fixed(area / 1e4, 2) +
                   " ha), outside " + format_fixed(options.warn_min_area_m2, 0) + " m^2 .. " +
                   format_fixed(options.warn_max_area_m2 / 1e6, 0) +
                   " km^2: is it the polygon you meant, in the units you meant?");
  if (waypoints > options.warn_waypoints)
    warn.push_back("the plan has " + std::to_string(waypoints) + " waypoints, more than " +
                   std::to_string(options.warn_waypoints) + ": check the GSD (" + format_fixed(options.gsd_cm, 2) +
                   " cm/px) against the site's " + format_fixed(area / 1e4, 1) + " ha");
  if (plan.flight_s > options.warn_flight_s)
    warn.push_back("the plan flies " + format_fixed(plan.flight_s / 3600.0, 1) + " h in " +
                   std::to_string(plan.sorties.size()) + " sortie(s), more than " +
                   format_fixed(options.warn_flight_s / 3600.0, 1) + " h");
  if (!options.max_flight_s && plan.flight_s > options.warn_sortie_s)
    warn.push_back("its one sortie flies " + format_fixed(plan.flight_s / 60.0, 0) + " min, longer than " +
                   format_fixed(options.warn_sortie_s / 60.0, 0) +
                   " min: split it into sorties that fit a battery (a flight-time limit)");
  if (plan.terrain && plan.terrain->highest_rise_m > 0.0)
    warn.push_back("the ground under the survey rises " + format_fixed(plan.terrain->highest_rise_m, 1) +
                   " m above home: set the autopilot's return altitude (PX4 RTL_RETURN_ALT, ArduPilot RTL_ALT) above " +
                   format_fixed(plan.terrain->highest_rise_m + options.min_altitude_m, 1) + " m");
  if (geodesic_distance_m(site.centre(), GeoPoint{0.0, 0.0, 0.0}) < 10e3)
    warn.push_back("the site lies at latitude and longitude (0, 0), in the Gulf of Guinea: are its coordinates unset?");
  return warn;
}

}  // namespace detail

/// The plan of `site` at `options.gsd_cm`, with the terrain of `dem` if given. In order:
/// - the height the GSD flies at, refused below `min_altitude_m`;
/// - the home point: `options.home` on the site (refused off it, with a hint where the site's
///   or the point's latitude and longitude look swapped, looks_swapped), or the ground under the
///   first waypoint; the lawnmower starts in the grid corner nearest it;
/// - the lawnmower inside the site (survey_site, `options.survey`'s margin);
/// - with `dem`: the terrain followed (follow_terrain), refused where a waypoint flies below
///   `min_altitude_m` above the highest ground under its footprint or a leg (take-off leg
///   included) passes lower over the DEM, and where the DEM does not cover the site (with the
///   same hint);
/// - the geofence: the site's polygon (site_fence: outer rings included, holes excluded),
///   simplified by at most a quarter of the inside margin to fit `fence_max_vertices`, checked to
///   hold home and every waypoint;
/// - every leg kept half the inside margin inside the fence (FenceRouter): a leg from the
///   take-off, between two waypoints, or home (the RTL flies straight) that would cut a concave
///   corner or cross a hole flies through via points instead;
/// - the sorties (split_into_sorties with `max_flight_s`, times along the routes) and the
///   flight time;
/// - the warnings: area, waypoints, hours, a long unsplit sortie, the ground rising above home
///   (the return altitude must clear it), a site at latitude and longitude (0, 0).
/// @throws std::invalid_argument for invalid options, and for each refusal above, one line
///         naming the numbers.
[[nodiscard]] inline SitePlan plan_site(const SurveySite& site, const SitePlanOptions& options,
                                        const ElevationModel* dem = nullptr) {
  options.validate();
  const CameraModel camera(options.camera);
  const TimingModel timing(options.timing);
  const GeoReference frame(site.geo);
  SitePlan plan;
  plan.height_m = detail::site_plan_height(camera, options);
  SiteSurveyOptions survey = options.survey;
  if (options.home) detail::place_given_home(site, *options.home, frame, plan, survey);
  plan.survey = survey_site(site, camera, options.gsd_cm, survey);
  if (plan.survey.waypoints.empty())
    throw std::invalid_argument("no waypoint lies " + detail::format_fixed(survey.inside_margin_m, 1) +
                                " m inside the site: it is narrower than twice the inside margin");
  if (!options.home) {
    plan.home_xy = plan.survey.waypoints.front().position.head<2>();
    plan.home = frame.to_wgs84(Eigen::Vector3d(plan.home_xy.x(), plan.home_xy.y(), 0.0));
    plan.home.altitude_m = site.geo.altitude_m;
  }
  if (dem != nullptr) detail::follow_site_terrain(site, options, frame, *dem, plan);

  // The geofence (simplified by at most a quarter of the margin, so waypoints stay 3/4 of it
  // inside) and the router that keeps legs half the margin inside it.
  const double margin = survey.inside_margin_m;
  plan.fence =
      site_fence(site, options.fence_max_vertices.value_or(std::numeric_limits<std::size_t>::max()), 0.25 * margin);
  plan.geofence = plan.fence.wgs84(site.geo);
  const FenceRouter router(plan.fence.rings, plan.fence.inclusion, 0.5 * margin);
  if (!router.inside(plan.home_xy))
    throw std::invalid_argument(
        "the take-off point lies off the simplified geofence: take off farther inside the site");
  const std::vector<Waypoint>& path = plan.survey.waypoints;
  for (std::size_t i = 0; i < path.size(); ++i)
    if (!router.inside(path[i].position.head<2>()))
      throw std::invalid_argument("waypoint " + std::to_string(i) +
                                  " lies off the simplified geofence: simplify the site's outline yourself");
  detail::SiteLegs legs(plan, router, timing, margin);
  detail::route_sorties(options, timing, legs, plan);
  if (dem != nullptr) detail::check_leg_clearance(options, frame, *dem, legs, plan);
  plan.warnings = detail::site_plan_warnings(site, options, plan);
  return plan;
}

}  // namespace adaptseg
