#pragma once
// adaptseg_live's vehicle over MAVLink (docs/flying.md): the site's fence checked before
// take-off, each planner waypoint flown by guided reposition and waited for, the camera
// triggered, and the pose measured there brought back into the flight frame. Everything that
// commands the vehicle is adaptseg::mavlink::VehicleLink's; this file only converts between the
// planner's frame and WGS84 and decides the tolerances. Not part of the library.

#include "common/camera_source.hpp"

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/mavlink.hpp>
#include <adaptseg/vision/adaptive_options.hpp>

#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <future>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::examples {

/// How near a waypoint counts as there, derived from the finest footprint a mission may fly
/// (the smallest image, whose neighbours lie one footprint side apart): a fraction of its
/// smaller side [m]. The replay's --pose-tolerance-m takes 0.4 (a recorded pose nearer its own
/// waypoint than any other waypoint's, whatever the GNSS error below that), the vehicle's
/// arrival 0.1 (an image at most a tenth of a footprint off the plan: no seam wider than that).
inline double footprint_tolerance_m(const CameraModel& camera, const std::vector<double>& candidate_gsd_cm,
                                    double top_gsd_cm, double fraction) {
  double finest = top_gsd_cm;
  for (double g : candidate_gsd_cm) finest = std::min(finest, g);
  const Extent fp = camera.footprint_at_gsd(finest);
  return fraction * std::min(fp.width_m, fp.height_m);
}

/// (-180, 180]
inline double wrap_deg(double a) {
  a = std::remainder(a, 360.0);
  return a == -180.0 ? 180.0 : a;
}

/// The fence the vehicle is never sent outside: a polygon in the flight frame [m] and in WGS84
/// (with the altitude band: mavlink::SiteLimits).
struct Fence {
  std::vector<Eigen::Vector2d> ring;  ///< the polygon in the flight frame [m]
  mavlink::SiteLimits limits;         ///< the same in WGS84, with the ceiling above home
  double margin_m = 0.0;              ///< how far it was grown beyond the site
};

namespace detail_vehicle {

/// The pixels of `mask` (255: the site) grown by `margin_m` as one polygon in the frame of a
/// map of `gsd_cm` whose row 0 is the top (y max): the outline of the grown pixels, within a
/// pixel (a larger one, for a mask of over 4 Mpx).
inline std::vector<Eigen::Vector2d> grown_outline(const cv::Mat& mask, double gsd_cm, double margin_m) {
  const double height_m = mask.rows * gsd_cm / 100.0, width_m = mask.cols * gsd_cm / 100.0;
  cv::Mat m = mask > 0;
  const double scale = std::max(1.0, std::sqrt(static_cast<double>(mask.total()) / 4e6));
  if (scale > 1.0) {
    cv::resize(
        m, m,
        cv::Size(std::max(1, static_cast<int>(mask.cols / scale)), std::max(1, static_cast<int>(mask.rows / scale))), 0,
        0, cv::INTER_AREA);
    m = m > 0;  // any site in a cell: the cell is site
  }
  const double cell_x = width_m / m.cols, cell_y = height_m / m.rows;
  const double cell = std::max(cell_x, cell_y);
  // One more cell than the margin: the outline runs through the border cells' centres.
  const int pad = static_cast<int>(std::ceil(margin_m / cell)) + 2;
  cv::copyMakeBorder(m, m, pad, pad, pad, pad, cv::BORDER_CONSTANT, cv::Scalar(0));
  cv::Mat outside = m == 0, distance;
  cv::distanceTransform(outside, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const cv::Mat grown = distance <= margin_m / cell + 1.0;
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(grown, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  if (contours.size() != 1)
    throw std::invalid_argument("the site is " + std::to_string(contours.size()) +
                                " separate parts at --fence-margin-m " + fmt(margin_m, 1) +
                                ": fly each as its own site, or grow the fence until they join");
  std::vector<cv::Point> poly;
  cv::approxPolyDP(contours.front(), poly, 1.0, true);  // within the extra cell
  if (poly.size() < 3) poly = contours.front();
  std::vector<Eigen::Vector2d> ring;
  for (const cv::Point& p : poly) ring.emplace_back((p.x - pad + 0.5) * cell_x, height_m - (p.y - pad + 0.5) * cell_y);
  return ring;
}

/// Distance [m] from `p` to the polygon `ring`'s boundary.
inline double distance_to_ring(const Eigen::Vector2d& p, const std::vector<Eigen::Vector2d>& ring) {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0, j = ring.size() - 1; i < ring.size(); j = i++) {
    const Eigen::Vector2d a = ring[j], ab = ring[i] - ring[j];
    const double t = ab.squaredNorm() > 0.0 ? std::clamp((p - a).dot(ab) / ab.squaredNorm(), 0.0, 1.0) : 0.0;
    best = std::min(best, (a + t * ab - p).norm());
  }
  return best;
}

}  // namespace detail_vehicle

/// The fence: the site's outline (`site_mask`: the --area polygon rasterised on the map grid of
/// `map_gsd_cm`) or else the area's rectangle, grown by `margin_m`, with the altitude band
/// (0, `ceiling_m`] above home, in `frame`.
/// @throws std::invalid_argument for a negative margin or a site that falls apart.
inline Fence make_fence(const Area& area, const cv::Mat& site_mask, double map_gsd_cm, double margin_m,
                        const GeoReference& frame, double ceiling_m) {
  if (!(std::isfinite(margin_m) && margin_m >= 0.0))
    throw std::invalid_argument("--fence-margin-m must be finite and >= 0 (got " + fmt(margin_m, 2) + ")");
  std::vector<Eigen::Vector2d> ring;
  if (!site_mask.empty()) {
    ring = detail_vehicle::grown_outline(site_mask, map_gsd_cm, margin_m);
  } else {
    const double m = margin_m;
    ring = {{area.x_min_m - m, area.y_min_m - m},
            {area.x_max_m + m, area.y_min_m - m},
            {area.x_max_m + m, area.y_max_m + m},
            {area.x_min_m - m, area.y_max_m + m}};
  }
  std::vector<mavlink::LatLon> polygon;
  for (const Eigen::Vector2d& p : ring) {
    const GeoPoint g = frame.to_wgs84({p.x(), p.y(), 0.0});
    polygon.push_back({g.latitude_deg, g.longitude_deg});
  }
  return {std::move(ring), mavlink::SiteLimits(std::move(polygon), ceiling_m, 0.0), margin_m};
}

/// The target of flight-frame position `p` (z: the altitude above home).
inline mavlink::LatLonAlt to_target(const GeoReference& frame, const Eigen::Vector3d& p) {
  const GeoPoint g = frame.to_wgs84({p.x(), p.y(), 0.0});
  return {g.latitude_deg, g.longitude_deg, p.z()};
}

/// Throws, before anything is sent, unless every waypoint the planner may hand out
/// (`waypoints`: AdaptivePlanner::reachable_waypoints) lies inside the fence; the message names
/// how many do not, the farthest, and the margin that would take them in.
inline void check_fence(const Fence& fence, const std::vector<Waypoint>& waypoints, const GeoReference& frame) {
  std::size_t outside = 0;
  double farthest = 0.0;
  Eigen::Vector3d worst = Eigen::Vector3d::Zero();
  std::string why;
  for (const Waypoint& w : waypoints) {
    const auto v = fence.limits.violation(to_target(frame, w.position));
    if (!v) continue;
    ++outside;
    const double d = fence.limits.contains(to_target(frame, w.position).lat_deg, to_target(frame, w.position).lon_deg)
                         ? 0.0
                         : detail_vehicle::distance_to_ring(w.position.head<2>(), fence.ring);
    if (why.empty() || d > farthest) farthest = d, worst = w.position, why = *v;
  }
  if (outside == 0) return;
  char buf[160];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f) m at %.1f m", worst.x(), worst.y(), worst.z());
  std::string msg = std::to_string(outside) + " of the " + std::to_string(waypoints.size()) +
                    " waypoints the planner may fly are outside the site's fence (e.g. " + buf + ": " + why + ")";
  if (farthest > 0.0)
    msg += "; the farthest lies " + fmt(farthest, 2) + " m beyond it: give --fence-margin-m " +
           fmt(std::ceil((fence.margin_m + farthest) * 10.0 + 1.0) / 10.0, 1) +
           " to let the vehicle fly that far beyond the site's edge, or lay the grid on the site (--grid centred)";
  throw std::invalid_argument(msg + "; nothing was sent to the vehicle");
}

/// What the vehicle loop needs to be told.
struct VehicleSettings {
  std::string connection;            ///< --mavlink
  mavlink::ArrivalCriteria arrival;  ///< the tolerance and the settled speed
  bool trigger = true;               ///< command the autopilot's camera at each waypoint
  mavlink::LinkOptions link;         ///< timeouts
};

/// The vehicle flown over MAVLink: connect, fly to each waypoint, trigger, measure, and at the
/// end return to launch. After any error it commands nothing (VehicleLink's rule): the caller
/// writes what was flown and leaves the vehicle to its failsafe.
class MavlinkVehicle {
 public:
  MavlinkVehicle(const VehicleSettings& s, mavlink::SiteLimits limits, const FieldGeo& frame)
      : link_(mavlink::open_transport(s.connection), std::move(limits), s.link), frame_(frame), settings_(s) {}

  /// Connects (heartbeat, streams, 3-D fix) and checks that the vehicle is armed and flying.
  /// @throws mavlink::VehicleLinkError, std::invalid_argument for a vehicle on the ground.
  void connect() {
    const mavlink::VehicleInfo& v = link_.connect();
    const mavlink::VehiclePosition& p = link_.position();
    std::printf("vehicle: %s system %d on %s, %s, mode %s, at %s, %.1f m above home\n",
                mavlink::to_string(v.firmware()).c_str(), int{v.system_id}, link_.description().c_str(),
                v.armed() ? "armed" : "disarmed", v.mode().c_str(), mavlink::to_string(p.lat_lon_alt()).c_str(),
                p.rel_alt_m);
    if (!v.armed() || p.rel_alt_m < 2.0)
      throw std::invalid_argument("connect: the vehicle is " + std::string(v.armed() ? "armed but" : "disarmed and") +
                                  " " + fmt(p.rel_alt_m, 1) +
                                  " m above home: arm it and take off (2 m or more) before the live loop; it never "
                                  "arms or takes off itself");
    std::fflush(stdout);
  }

  /// Flies to `w` (guided reposition), waits until it is there and settled, triggers the
  /// camera (if asked) and returns the pose measured then, in the flight frame.
  CameraPose fly_to(const Waypoint& w, CameraSource& camera) {
    const mavlink::LatLonAlt target = to_target(frame_, w.position);
    link_.go_to(target);
    link_.wait_arrival(target, settings_.arrival);
    if (!first_arrival_s_) first_arrival_s_ = link_.now();
    camera.before_trigger();
    if (settings_.trigger) link_.trigger_camera();
    last_ = link_.position();
    return pose_of(last_);
  }

  /// Seconds since the first waypoint was reached (the mission's real clock); 0 before.
  [[nodiscard]] double elapsed_s() const { return first_arrival_s_ ? link_.now() - *first_arrival_s_ : 0.0; }

  /// Runs `work` on another thread while this one keeps the link alive (heartbeats, link-loss
  /// detection); returns its result or rethrows its exception, after it has finished.
  template <typename Work>
  auto while_busy(Work&& work) {
    auto done = std::async(std::launch::async, std::forward<Work>(work));
    try {
      while (done.wait_for(std::chrono::milliseconds(0)) != std::future_status::ready) link_.poll(link_.now() + 0.05);
    } catch (...) {
      done.wait();  // the work ends before its captures go out of scope
      throw;
    }
    return done.get();
  }

  /// Waits `seconds`, keeping the link alive.
  void idle(double seconds) { link_.poll(link_.now() + seconds); }

  /// Sends the vehicle home (NAV_RETURN_TO_LAUNCH, acknowledged).
  void return_to_launch() { link_.return_to_launch(); }

  /// The position measured at the last shot.
  [[nodiscard]] const mavlink::VehiclePosition& last_position() const { return last_; }
  [[nodiscard]] const mavlink::VehicleLink& link() const { return link_; }

  /// `p` in the flight frame: x, y from WGS84, z its altitude above home, the yaw of the image
  /// x axis from the vehicle's heading (a camera whose image top points at the nose; the plan's
  /// heading, yaw 0, where the autopilot reports none).
  [[nodiscard]] CameraPose pose_of(const mavlink::VehiclePosition& p) const {
    Eigen::Vector3d x = frame_.to_field({p.lat_deg, p.lon_deg, frame_.geo().altitude_m});
    x.z() = p.rel_alt_m;
    const double yaw = std::isfinite(p.heading_deg) ? wrap_deg(frame_.geo().heading_deg - 90.0 - p.heading_deg) : 0.0;
    return {x, yaw};
  }

 private:
  mavlink::VehicleLink link_;
  GeoReference frame_;
  VehicleSettings settings_;
  std::optional<double> first_arrival_s_;
  mavlink::VehiclePosition last_;
};

}  // namespace adaptseg::examples
