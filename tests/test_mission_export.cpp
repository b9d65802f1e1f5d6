#include "test_support.hpp"

#include <adaptseg/geo/fence_route.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/geo/mission_export.hpp>
#include <adaptseg/geo/sorties.hpp>

#include <GeographicLib/Geodesic.hpp>
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <random>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

using adaptseg::ExportPath;
using adaptseg::Field;
using adaptseg::FieldGeo;
using adaptseg::GeoPoint;
using adaptseg::GeoReference;
using adaptseg::MissionItem;
namespace t = adaptseg::test;

namespace {

/// Distance [m] and azimuth [deg clockwise from north] from a to b on the WGS84 ellipsoid.
std::pair<double, double> geodesic(const GeoPoint& a, const GeoPoint& b) {
  double s12 = 0.0, azi1 = 0.0, azi2 = 0.0, m12 = 0.0, M12 = 0.0, M21 = 0.0, S12 = 0.0;
  GeographicLib::Geodesic::WGS84().Inverse(a.latitude_deg, a.longitude_deg, b.latitude_deg, b.longitude_deg, s12, azi1,
                                           azi2, m12, M12, M21, S12);
  return {s12, azi1};
}

/// Angle difference folded into (-180, 180].
double angle_diff(double a, double b) { return std::remainder(a - b, 360.0); }

bool same_number(double a, double b, double tol) { return (std::isnan(a) && std::isnan(b)) || std::abs(a - b) <= tol; }

void check_same_items(const std::vector<MissionItem>& got, const std::vector<MissionItem>& want) {
  REQUIRE(got.size() == want.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    CAPTURE(i);
    CHECK(got[i].command == want[i].command);
    CHECK(got[i].frame == want[i].frame);
    CHECK(got[i].autocontinue == want[i].autocontinue);
    for (std::size_t k = 0; k < 7; ++k) {
      CAPTURE(k);
      CHECK(same_number(got[i].params[k], want[i].params[k], k == 4 || k == 5 ? 1e-7 : 0.01));
    }
  }
}

void check_same_home(const GeoPoint& got, const GeoPoint& want) {
  CHECK(std::abs(got.latitude_deg - want.latitude_deg) <= 1e-7);
  CHECK(std::abs(got.longitude_deg - want.longitude_deg) <= 1e-7);
  CHECK(std::abs(got.altitude_m - want.altitude_m) <= 0.01);
}

const FieldGeo kGeo{50.7, 7.2, 60.0, 90.0};  // a field near Bonn, +x east

/// A field-frame lawnmower over 40 m x 30 m, plus a descent: levels 0 and 1.
ExportPath sample_path(const FieldGeo& g = kGeo) {
  const adaptseg::LawnmowerPlanner planner(adaptseg::CameraModel{});
  std::vector<adaptseg::Waypoint> path = planner.plan({0.0, 0.0, 40.0, 30.0}, 3.0);
  const auto sub = planner.plan(path[0].footprint, 1.5, path[0].position.head<2>());
  std::vector<int> levels(path.size(), 0);
  path.insert(path.begin() + 1, sub.begin(), sub.end());
  levels.insert(levels.begin() + 1, sub.size(), 1);
  return adaptseg::make_export_path(path, levels, GeoReference(g), "sample");
}

}  // namespace

TEST_CASE("geo: field -> WGS84 -> field is exact to well below 1 mm") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> xy(-500.0, 1500.0), z(0.0, 120.0);
  for (const FieldGeo g : {kGeo, FieldGeo{-33.9, 151.2, 20.0, 0.0}, FieldGeo{78.2, 15.6, 5.0, 237.5, 12.0, -40.0},
                           FieldGeo{0.0, 179.999, 0.0, -45.0}, FieldGeo{-89.0, -179.9, 2800.0, 1e3}}) {
    const GeoReference geo(g);
    for (int i = 0; i < 200; ++i) {
      const Eigen::Vector3d p(xy(rng), xy(rng), z(rng));
      const GeoPoint w = geo.to_wgs84(p);
      CHECK(w.longitude_deg >= -180.0);
      CHECK(w.longitude_deg <= 180.0);
      const Eigen::Vector3d back = geo.to_field(w);
      CAPTURE(g.latitude_deg);
      CHECK((back - p).norm() < 1e-3);
      CHECK((geo.enu_to_field(geo.field_to_enu(p)) - p).norm() < 1e-9);
    }
  }
}

TEST_CASE("geo: the heading is the compass bearing of +x, and +y lies 90 degrees counter-clockwise") {
  struct Case {
    double heading, azimuth_x, azimuth_y;
  };
  // heading 90: +x east, +y north; 0: +x north, +y west; 30: +x at 30, +y at -60; 180: +x south, +y east.
  for (const Case c : {Case{90.0, 90.0, 0.0}, Case{0.0, 0.0, -90.0}, Case{30.0, 30.0, -60.0}, Case{180.0, 180.0, 90.0},
                       Case{-90.0, -90.0, 180.0}}) {
    CAPTURE(c.heading);
    // At the ellipsoid's surface (altitude 0): geodesic distances are measured there.
    const FieldGeo g{kGeo.latitude_deg, kGeo.longitude_deg, 0.0, c.heading};
    const GeoReference geo(g);
    const GeoPoint origin = geo.to_wgs84({0.0, 0.0, 0.0});
    CHECK(origin.latitude_deg == doctest::Approx(g.latitude_deg).epsilon(1e-12));
    CHECK(origin.longitude_deg == doctest::Approx(g.longitude_deg).epsilon(1e-12));
    CHECK(origin.altitude_m == doctest::Approx(g.altitude_m));
    const auto [dx, ax] = geodesic(origin, geo.to_wgs84({100.0, 0.0, 0.0}));
    CHECK(dx == doctest::Approx(100.0).epsilon(1e-6));
    CHECK(std::abs(angle_diff(ax, c.azimuth_x)) < 1e-6);
    const auto [dy, ay] = geodesic(origin, geo.to_wgs84({0.0, 100.0, 0.0}));
    CHECK(dy == doctest::Approx(100.0).epsilon(1e-6));
    CHECK(std::abs(angle_diff(ay, c.azimuth_y)) < 1e-6);
  }
  // A grid's scale (a GeoTIFF field's frame is in grid metres): 100 grid metres are 100 / k on
  // the ground, in the same directions, and the round trip stays exact.
  for (const double k : {0.9996, 1.0004}) {
    CAPTURE(k);
    const FieldGeo g{kGeo.latitude_deg, kGeo.longitude_deg, 0.0, 30.0, 0.0, 0.0, k};
    const GeoReference geo(g);
    const GeoPoint origin = geo.to_wgs84({0.0, 0.0, 0.0});
    const auto [dx, ax] = geodesic(origin, geo.to_wgs84({100.0, 0.0, 0.0}));
    CHECK(dx == doctest::Approx(100.0 / k).epsilon(1e-7));
    CHECK(std::abs(angle_diff(ax, 30.0)) < 1e-6);
    const auto [dy, ay] = geodesic(origin, geo.to_wgs84({0.0, 100.0, 0.0}));
    CHECK(dy == doctest::Approx(100.0 / k).epsilon(1e-7));
    CHECK(std::abs(angle_diff(ay, -60.0)) < 1e-6);
    const Eigen::Vector3d p(250.0, -40.0, 12.0);
    CHECK((geo.to_field(geo.to_wgs84(p)) - p).norm() < 1e-6);
  }
  CHECK_THROWS_WITH_AS(GeoReference(FieldGeo{0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0}), doctest::Contains("scale"),
                       std::invalid_argument);
  // The local frame directly: heading 90 is the identity on (x, y).
  const GeoReference east(kGeo);
  CHECK((east.field_to_enu({3.0, 4.0, 5.0}) - Eigen::Vector3d(3.0, 4.0, 5.0)).norm() < 1e-12);
  // z is the height above the field plane.
  CHECK(east.to_wgs84({0.0, 0.0, 30.0}).altitude_m == doctest::Approx(kGeo.altitude_m + 30.0));
}

TEST_CASE("geo: field.yaml's geo section loads, and a sub-field keeps every point's WGS84 position") {
  t::TempDir tmp;
  cv::Mat labels(4, 6, CV_8UC1, cv::Scalar(0));
  t::write_field(
      tmp.path(), labels,
      std::string(t::kWeedYaml) + "geo: {latitude_deg: 50.7, longitude_deg: 7.2, altitude_m: 60, heading_deg: 30}\n");
  const Field f = Field::load(tmp.path());
  REQUIRE(f.geo().has_value());
  CHECK(*f.geo() == FieldGeo{50.7, 7.2, 60.0, 30.0, 0.0, 0.0});
  CHECK_FALSE(f.with_geo(std::nullopt).geo().has_value());
  const GeoReference geo(f);
  // Pixel (row 2, col 4) of the field is pixel (row 1, col 1) of the sub-field rows 1..2, cols 3..5.
  const Field sub = f.sub_field({0.5, 0.25, 1.0, 0.75});
  REQUIRE(sub.width_px() == 3);
  REQUIRE(sub.height_px() == 2);
  const GeoReference sub_geo(sub);
  const Eigen::Vector3d in_field(4.5 * 0.01, (4 - 2 - 0.5) * 0.01, 12.0);
  const Eigen::Vector3d in_sub(1.5 * 0.01, (2 - 1 - 0.5) * 0.01, 12.0);
  const GeoPoint a = geo.to_wgs84(in_field), b = sub_geo.to_wgs84(in_sub);
  CHECK(std::abs(a.latitude_deg - b.latitude_deg) < 1e-12);
  CHECK(std::abs(a.longitude_deg - b.longitude_deg) < 1e-12);
  CHECK(a.altitude_m == doctest::Approx(b.altitude_m));
  CHECK((sub_geo.to_field(a) - in_sub).norm() < 1e-6);
  // A sub-field of a sub-field too.
  const Field subsub = sub.sub_field({0.0, 0.5, 1.0, 1.0});
  const GeoPoint c = GeoReference(subsub).to_wgs84({1.5 * 0.01, 0.5 * 0.01, 12.0});
  CHECK(std::abs(a.latitude_deg - c.latitude_deg) < 1e-12);
  CHECK(std::abs(a.longitude_deg - c.longitude_deg) < 1e-12);
  // No geo section: no geo-reference, and GeoReference says why.
  CHECK_THROWS_WITH_AS(GeoReference(Field("plain", 1.0, labels, t::soil_crop_weed(), {1})),
                       doctest::Contains("no geo-reference"), std::invalid_argument);
}

TEST_CASE("geo: bad geo sections and values are rejected, naming the file and key") {
  t::TempDir tmp;
  int n = 0;
  const auto expect_error = [&](const std::string& geo, const std::string& fragment) {
    const auto dir = tmp.path() / std::to_string(n++);
    t::write_field(dir, cv::Mat(4, 6, CV_8UC1, cv::Scalar(0)), std::string(t::kWeedYaml) + geo);
    CAPTURE(geo);
    CHECK_THROWS_WITH_AS(Field::load(dir), doctest::Contains("field.yaml"), std::invalid_argument);
    CHECK_THROWS_WITH_AS(Field::load(dir), doctest::Contains(fragment.c_str()), std::invalid_argument);
  };
  expect_error("geo: {latitude_deg: 91, longitude_deg: 7, altitude_m: 0, heading_deg: 0}\n", "geo.latitude_deg");
  expect_error("geo: {latitude_deg: 50, longitude_deg: -180.5, altitude_m: 0, heading_deg: 0}\n", "geo.longitude_deg");
  expect_error("geo: {latitude_deg: 50, longitude_deg: 7, altitude_m: .inf, heading_deg: 0}\n", "geo.altitude_m");
  expect_error("geo: {latitude_deg: 50, longitude_deg: 7, altitude_m: 0, heading_deg: .nan}\n", "geo.heading_deg");
  expect_error("geo: {latitude_deg: north, longitude_deg: 7, altitude_m: 0, heading_deg: 0}\n",
               "'geo.latitude_deg' must be a finite number (got 'north')");
  expect_error("geo: {latitude_deg: 50, longitude_deg: 7, altitude_m: 0}\n", "missing key 'geo.heading_deg'");
  expect_error("geo: {latitude_deg: 50, longitude_deg: 7, altitude_m: 0, heading_deg: 0, datum: wgs84}\n",
               "unknown key 'geo.datum' (known: latitude_deg, longitude_deg, altitude_m, heading_deg)");
  expect_error("geo: [50, 7, 0, 0]\n", "'geo' must be a mapping");
  expect_error("geo: {latitude_deg: [50], longitude_deg: 7, altitude_m: 0, heading_deg: 0}\n",
               "'geo.latitude_deg' must be a finite number");
  const cv::Mat labels(4, 6, CV_8UC1, cv::Scalar(0));
  const Field f("f", 1.0, labels, t::soil_crop_weed(), {1});
  CHECK_THROWS_WITH_AS((void)f.with_geo(FieldGeo{-90.5, 0.0, 0.0, 0.0}), doctest::Contains("latitude_deg"),
                       std::invalid_argument);
  CHECK_THROWS_AS(GeoReference(FieldGeo{0.0, 0.0, NAN, 0.0}), std::invalid_argument);
  CHECK_THROWS_AS((void)GeoReference(kGeo).to_field({95.0, 0.0, 0.0}), std::invalid_argument);
}

TEST_CASE("export: paths keep positions, GSD and levels of a planned or flown mission") {
  const ExportPath p = sample_path();
  const GeoReference geo(kGeo);
  REQUIRE(p.waypoints.size() > 9);
  check_same_home(p.home, GeoPoint{kGeo.latitude_deg, kGeo.longitude_deg, kGeo.altitude_m});
  CHECK(p.home.altitude_m == kGeo.altitude_m);
  CHECK(p.waypoints[0].level == 0);
  CHECK(p.waypoints[1].level == 1);
  CHECK(p.waypoints[1].gsd_cm == 1.5);
  CHECK(p.waypoints.back().level == 0);
  const auto& w = p.waypoints[0];
  const Eigen::Vector3d back = geo.to_field({w.latitude_deg, w.longitude_deg, kGeo.altitude_m + w.relative_altitude_m});
  CHECK(back.z() == doctest::Approx(adaptseg::CameraModel{}.altitude_m(3.0)).epsilon(1e-3));  // to the centimetre

  // A flown mission: the levels come from its records.
  adaptseg::MissionResult r;
  r.field = "f";
  r.strategy = "adaptive";
  for (int k = 0; k < 3; ++k) {
    adaptseg::WaypointRecord rec;
    rec.waypoint.position = {k * 10.0, 5.0, 20.0 - k};
    rec.waypoint.gsd_cm = 2.0;
    rec.level = k == 1 ? 1 : 0;
    r.waypoints.push_back(rec);
  }
  const ExportPath flown = adaptseg::make_export_path(r, geo);
  CHECK(flown.name == "f adaptive");
  REQUIRE(flown.waypoints.size() == 3);
  CHECK(flown.waypoints[1].level == 1);
  CHECK(flown.waypoints[2].relative_altitude_m == 18.0);
  // Altitudes to the centimetre, as an autopilot is told them.
  r.waypoints[2].waypoint.position.z() = 165.00000000001054;
  CHECK(adaptseg::make_export_path(r, geo).waypoints[2].relative_altitude_m == 165.0);
  r.waypoints[2].waypoint.position.z() = 16.504999;
  CHECK(adaptseg::make_export_path(r, geo).waypoints[2].relative_altitude_m == doctest::Approx(16.50).epsilon(1e-12));
  // A planned path alone: every waypoint top-level.
  const ExportPath planned = adaptseg::make_export_path({r.waypoints[0].waypoint}, geo, "planned");
  CHECK(planned.waypoints.at(0).level == 0);

  CHECK_THROWS_WITH_AS((void)adaptseg::make_export_path({r.waypoints[0].waypoint}, std::vector<int>{}, geo, "x"),
                       doctest::Contains("one level per waypoint"), std::invalid_argument);
  CHECK_THROWS_AS((void)adaptseg::make_export_path({r.waypoints[0].waypoint}, std::vector<int>{-1}, geo, "x"),
                  std::invalid_argument);
}

TEST_CASE("export: mission items take off, hold at every waypoint, capture one image, and come back") {
  const ExportPath p = sample_path();
  adaptseg::ExportOptions opt;
  opt.hold_s = 2.5;
  opt.hover_speed_mps = 3.5;
  const auto items = adaptseg::mission_items(p, opt);
  REQUIRE(items.size() == 2 * p.waypoints.size() + 3);
  const MissionItem& takeoff = items.front();
  CHECK(takeoff.command == 22);
  CHECK(takeoff.frame == 3);
  CHECK(takeoff.params[0] == 0.0);  // pitch
  CHECK(std::isnan(takeoff.params[3]));
  CHECK(takeoff.params[4] == p.home.latitude_deg);
  CHECK(takeoff.params[5] == p.home.longitude_deg);
  CHECK(takeoff.params[6] == p.waypoints.front().relative_altitude_m);
  // Then the speed the mission's times were computed with: ground speed, throttle unchanged.
  const MissionItem& speed = items[1];
  CHECK(speed.command == 178);
  CHECK(speed.frame == 2);
  CHECK(speed.params[0] == 1.0);
  CHECK(speed.params[1] == 3.5);
  CHECK(speed.params[2] == -1.0);
  for (std::size_t i = 0; i < p.waypoints.size(); ++i) {
    const MissionItem& nav = items[2 + 2 * i];
    const MissionItem& cap = items[3 + 2 * i];
    CHECK(nav.command == 16);
    CHECK(nav.frame == 3);
    CHECK(nav.params[0] == 2.5);
    CHECK(std::isnan(nav.params[3]));
    CHECK(nav.params[4] == p.waypoints[i].latitude_deg);
    CHECK(nav.params[5] == p.waypoints[i].longitude_deg);
    CHECK(nav.params[6] == p.waypoints[i].relative_altitude_m);
    CHECK(cap.command == 2000);
    CHECK(cap.frame == 2);
    CHECK(cap.params[2] == 1.0);                         // one image
    CHECK(cap.params[3] == static_cast<double>(i + 1));  // capture sequence number
  }
  const MissionItem& rtl = items.back();
  CHECK(rtl.command == 20);
  CHECK(rtl.frame == 2);
  CHECK(rtl.params == std::array<double, 7>{});

  // Mission Planner's camera item, a landing at home instead of RTL, no take-off.
  opt.camera_trigger = adaptseg::CameraTrigger::digicam_control;
  opt.end = adaptseg::MissionEnd::land;
  opt.takeoff = false;
  opt.set_speed = false;
  const auto other = adaptseg::mission_items(p, opt);
  REQUIRE(other.size() == 2 * p.waypoints.size() + 1);
  CHECK(other.front().command == 16);
  CHECK(other[1].command == 203);
  CHECK(other[1].frame == 2);
  CHECK(other[1].params == std::array<double, 7>{0, 0, 0, 0, 1, 0, 0});  // param5 1: one shot
  CHECK(other.back().command == 21);
  CHECK(other.back().frame == 3);
  CHECK(other.back().params[4] == p.home.latitude_deg);
  CHECK(other.back().params[5] == p.home.longitude_deg);
  CHECK(other.back().params[6] == 0.0);
  opt.end = adaptseg::MissionEnd::none;
  opt.capture_images = false;
  CHECK(adaptseg::mission_items(p, opt).size() == p.waypoints.size());

  // A take-off needs somewhere to climb to.
  ExportPath low = p;
  low.waypoints.front().relative_altitude_m = 0.0;
  CHECK_THROWS_WITH_AS((void)adaptseg::mission_items(low),
                       doctest::Contains("take-off needs the first waypoint above home"), std::invalid_argument);
  opt.takeoff = false;
  CHECK(adaptseg::mission_items(low, opt).size() == p.waypoints.size());
  // Above the legal ceiling (120 m by default): refused.
  ExportPath high = p;
  high.waypoints.back().relative_altitude_m = 165.0;
  CHECK_THROWS_WITH_AS((void)adaptseg::mission_items(high, opt), doctest::Contains("flies above max_altitude_m 120"),
                       std::invalid_argument);
  opt.max_altitude_m = 200.0;
  CHECK(adaptseg::mission_items(high, opt).size() == p.waypoints.size());
  opt.hold_s = -1.0;
  CHECK_THROWS_WITH_AS((void)adaptseg::mission_items(p, opt), doctest::Contains("hold_s"), std::invalid_argument);
  opt.hold_s = 1.0;
  opt.end = static_cast<adaptseg::MissionEnd>(7);
  CHECK_THROWS_WITH_AS((void)adaptseg::mission_items(p, opt), doctest::Contains("end must be a MissionEnd"),
                       std::invalid_argument);
}

TEST_CASE("export: a QGroundControl plan reads back equal and has QGC's structure") {
  const ExportPath p = sample_path(FieldGeo{-33.9, 151.2, 20.0, 217.0});
  const std::string text = adaptseg::write_qgc_plan(p);
  const adaptseg::MissionFile back = adaptseg::read_qgc_plan(text);
  check_same_home(back.home, p.home);
  check_same_items(back.items, adaptseg::mission_items(p));

  const auto j = nlohmann::json::parse(text);
  CHECK(j["fileType"] == "Plan");
  CHECK(j["version"] == 1);
  CHECK(j["groundStation"].is_string());
  CHECK(j["geoFence"]["version"] == 2);
  CHECK(j["rallyPoints"]["points"].empty());
  const auto& m = j["mission"];
  CHECK(m["version"] == 2);
  CHECK(m["hoverSpeed"] == 2.0);
  CHECK(m["plannedHomePosition"].size() == 3);
  const auto& takeoff = m["items"][0];
  CHECK(takeoff["type"] == "SimpleItem");
  CHECK(takeoff["command"] == 22);
  CHECK(takeoff["frame"] == 3);
  CHECK(takeoff["doJumpId"] == 1);
  CHECK(takeoff["AltitudeMode"] == 1);
  CHECK(takeoff["Altitude"] == p.waypoints.front().relative_altitude_m);
  const auto& speed = m["items"][1];  // DO_CHANGE_SPEED: no position, QGC writes no altitude keys
  CHECK(speed["command"] == 178);
  CHECK_FALSE(speed.contains("Altitude"));
  const auto& first = m["items"][2];
  CHECK(first["type"] == "SimpleItem");
  CHECK(first["command"] == 16);
  CHECK(first["frame"] == 3);
  CHECK(first["doJumpId"] == 3);
  CHECK(first["autoContinue"] == true);
  CHECK(first["AltitudeMode"] == 1);
  CHECK(first["AMSLAltAboveTerrain"].is_null());
  CHECK(first["Altitude"] == first["params"][6]);
  CHECK(first["params"][3].is_null());
  CHECK(m["items"][3]["command"] == 2000);
  CHECK_FALSE(m["items"][3].contains("Altitude"));
  CHECK(m["items"][3]["doJumpId"] == 4);
  const auto& last = m["items"].back();
  CHECK(last["command"] == 20);
  CHECK(last["frame"] == 2);
  CHECK_FALSE(last.contains("Altitude"));
  CHECK(last["doJumpId"] == m["items"].size());
}

TEST_CASE("export: a QGC WPL 110 file reads back equal") {
  const ExportPath p = sample_path(FieldGeo{0.0, -0.00001, -12.5, 45.0});
  const std::string text = adaptseg::write_wpl(p);
  CHECK(text.rfind("QGC WPL 110\n0\t1\t0\t16\t", 0) == 0);
  const adaptseg::MissionFile back = adaptseg::read_wpl(text);
  check_same_home(back.home, p.home);
  check_same_items(back.items, adaptseg::mission_items(p));
  // Exact, too: shortest round-trip text.
  CHECK(back.items[2].params[4] == p.waypoints[0].latitude_deg);
  // Spaces, \r\n and blank lines are read as well.
  std::string crlf;
  for (char c : text) {
    if (c == '\n')
      crlf += "\r\n";
    else
      crlf += c == '\t' ? ' ' : c;
  }
  CHECK(adaptseg::read_wpl(crlf + "\r\n\r\n").items.size() == back.items.size());
}

TEST_CASE("export: GeoJSON reads back equal") {
  for (const FieldGeo g : {kGeo, FieldGeo{64.1, -21.9, 30.0, 333.0}}) {
    const ExportPath p = sample_path(g);
    const ExportPath back = adaptseg::read_geojson(adaptseg::write_geojson(p));
    CHECK(back.name == p.name);
    check_same_home(back.home, p.home);
    REQUIRE(back.waypoints.size() == p.waypoints.size());
    for (std::size_t i = 0; i < p.waypoints.size(); ++i) {
      CAPTURE(i);
      CHECK(std::abs(back.waypoints[i].latitude_deg - p.waypoints[i].latitude_deg) <= 1e-7);
      CHECK(std::abs(back.waypoints[i].longitude_deg - p.waypoints[i].longitude_deg) <= 1e-7);
      CHECK(std::abs(back.waypoints[i].relative_altitude_m - p.waypoints[i].relative_altitude_m) <= 0.01);
      CHECK(back.waypoints[i].gsd_cm == p.waypoints[i].gsd_cm);
      CHECK(back.waypoints[i].level == p.waypoints[i].level);
    }
  }
  // The documented structure: the line first, then one point per waypoint; heights above the ellipsoid.
  ExportPath one = sample_path();
  one.waypoints.resize(1);
  const auto j = nlohmann::json::parse(adaptseg::write_geojson(one));
  CHECK(j["type"] == "FeatureCollection");
  REQUIRE(j["features"].size() == 2);
  CHECK(j["features"][0]["geometry"]["type"] == "LineString");
  CHECK(j["features"][0]["geometry"]["coordinates"].size() == 2);
  const auto& pt = j["features"][1];
  CHECK(pt["properties"]["role"] == "top-level");
  CHECK(pt["geometry"]["coordinates"][0] == one.waypoints[0].longitude_deg);
  CHECK(pt["geometry"]["coordinates"][2].get<double>() ==
        doctest::Approx(kGeo.altitude_m + one.waypoints[0].relative_altitude_m));
  CHECK(adaptseg::read_geojson(j.dump()).waypoints.size() == 1);
}

TEST_CASE("export: formats by name, and empty paths are refused") {
  using adaptseg::ExportFormat;
  CHECK(adaptseg::parse_export_format("plan") == ExportFormat::qgc_plan);
  CHECK(adaptseg::parse_export_format("wpl") == ExportFormat::wpl);
  CHECK(adaptseg::parse_export_format("geojson") == ExportFormat::geojson);
  CHECK_THROWS_WITH_AS((void)adaptseg::parse_export_format("kml"),
                       doctest::Contains("export format must be 'plan', 'wpl' or 'geojson', not 'kml'"),
                       std::invalid_argument);
  CHECK(adaptseg::export_file_name(ExportFormat::wpl) == "mission.waypoints");
  ExportPath empty;
  for (const auto f : {ExportFormat::qgc_plan, ExportFormat::wpl, ExportFormat::geojson})
    CHECK_THROWS_WITH_AS((void)adaptseg::write_mission(f, empty), doctest::Contains("no waypoint"),
                         std::invalid_argument);
}

TEST_CASE("export: malformed WPL files are rejected with the line number") {
  const std::string good = adaptseg::write_wpl(sample_path());
  const std::string home = "0\t1\t0\t16\t0\t0\t0\t0\t50.7\t7.2\t60\t1\n";
  const auto expect_error = [](const std::string& text, const std::string& fragment) {
    CAPTURE(text);
    CHECK_THROWS_WITH_AS((void)adaptseg::read_wpl(text), doctest::Contains(fragment.c_str()), std::invalid_argument);
  };
  expect_error("", "empty file");
  expect_error("QGC WPL 120\n" + home, "line 1: the first line must be 'QGC WPL 110'");
  expect_error("QGC WPL 110\n", "no home line");
  expect_error("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\t50.7\t7.2\t60\n", "line 2: want 12 fields");
  expect_error("QGC WPL 110\n" + home + "2\t0\t3\t16\t0\t0\t0\t0\t50.7\t7.2\t60\t1\n", "line 3: seq 2 out of order");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t16\t0\t0\t0\t0\t95\t7.2\t60\t1\n", "line 3: latitude");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t16\t0\t0\t0\t0\t50\t-181\t60\t1\n", "line 3: longitude");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t16\t0\t0\t0\t0\t50\t7\tnan\t1\n", "line 3: altitude");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t16\tx\t0\t0\t0\t50\t7\t60\t1\n", "line 3: field 5 (param1)");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t16\t0\t0\t0\t0\t50\t7\t60\t2\n", "line 3: autocontinue");
  expect_error("QGC WPL 110\n" + home + "1\t2\t3\t16\t0\t0\t0\t0\t50\t7\t60\t1\n", "line 3: current");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t99999999999999999999\t0\t0\t0\t0\t50\t7\t60\t1\n", "line 3: command");
  expect_error("QGC WPL 110\n" + home + "1\t0\t3\t16\t1e999\t0\t0\t0\t50\t7\t60\t1\n", "line 3: field 5");
  expect_error("QGC WPL 110\n0\t1\t0\t16\t0\t0\t0\t0\tnan\t7.2\t60\t1\n", "line 2: latitude");
  expect_error("QGC WPL 110\n0\t1\t2\t16\t0\t0\t0\t0\tnan\t7.2\t60\t1\n", "line 2: the home position");
  // Any truncation or byte change either reads or throws invalid_argument, never worse.
  std::mt19937 rng(11);
  for (int trial = 0; trial < 2000; ++trial) {
    std::string text = good.substr(0, std::uniform_int_distribution<std::size_t>(0, good.size())(rng));
    if (trial % 2 == 1 && !text.empty())
      text[std::uniform_int_distribution<std::size_t>(0, text.size() - 1)(rng)] =
          static_cast<char>(std::uniform_int_distribution<int>(0, 255)(rng));
    try {
      (void)adaptseg::read_wpl(text);
    } catch (const std::invalid_argument&) {
    }
  }
}

TEST_CASE("export: malformed plan and GeoJSON files are rejected, naming the member") {
  const ExportPath p = sample_path();
  const auto plan = nlohmann::json::parse(adaptseg::write_qgc_plan(p));
  const auto expect_plan_error = [](const nlohmann::json& j, const std::string& fragment) {
    CAPTURE(fragment);
    CHECK_THROWS_WITH_AS((void)adaptseg::read_qgc_plan(j.dump()), doctest::Contains(fragment.c_str()),
                         std::invalid_argument);
  };
  CHECK_THROWS_WITH_AS((void)adaptseg::read_qgc_plan("{\"fileType\": "), doctest::Contains("not valid JSON"),
                       std::invalid_argument);
  auto j = plan;
  j["fileType"] = "Fence";
  expect_plan_error(j, "fileType");
  j = plan;
  j["mission"]["items"][3]["type"] = "ComplexItem";
  expect_plan_error(j, "mission.items[3]: item type 'ComplexItem' is not supported");
  j = plan;
  j["mission"]["items"][0]["params"].erase(0);
  expect_plan_error(j, "mission.items[0].params must be an array of 7");
  j = plan;
  j["mission"]["items"][4]["params"][4] = 123.0;
  expect_plan_error(j, "mission.items[4]: latitude");
  j = plan;
  j["mission"]["items"][0]["command"] = -1;
  expect_plan_error(j, "mission.items[0].command must be an integer");
  j = plan;
  j["mission"].erase("plannedHomePosition");
  expect_plan_error(j, "missing key 'plannedHomePosition'");

  const auto geo = nlohmann::json::parse(adaptseg::write_geojson(p));
  const auto expect_geo_error = [](const nlohmann::json& g, const std::string& fragment) {
    CAPTURE(fragment);
    CHECK_THROWS_WITH_AS((void)adaptseg::read_geojson(g.dump()), doctest::Contains(fragment.c_str()),
                         std::invalid_argument);
  };
  auto g = geo;
  g["type"] = "Feature";
  expect_geo_error(g, "FeatureCollection");
  g = geo;
  g["features"][2]["properties"]["index"] = 0;
  expect_geo_error(g, "appears twice");
  g = geo;
  g["features"][0]["geometry"]["coordinates"][1][0] = 0.0;
  expect_geo_error(g, "LineString position 1 differs");
  g = geo;
  g["features"][3]["geometry"]["coordinates"] = {7.0, 91.0, 0.0};
  expect_geo_error(g, "features[3].geometry.coordinates: latitude");
  g = geo;
  g["features"][1]["properties"].erase("gsd_cm");
  expect_geo_error(g, "missing key 'gsd_cm'");
  g = geo;
  g["features"].erase(0);
  expect_geo_error(g, "no LineString");
  g = geo;
  g["features"][1]["geometry"]["type"] = "Polygon";
  expect_geo_error(g, "geometry type 'Polygon'");
}

TEST_CASE("export: each firmware's own camera item, unless one is asked for") {
  const ExportPath p = sample_path();
  const auto cameras = [&](const adaptseg::ExportOptions& opt) {
    std::vector<int> out;
    for (const MissionItem& item : adaptseg::mission_items(p, opt))
      if (item.command == 2000 || item.command == 203) out.push_back(item.command);
    return out;
  };
  adaptseg::ExportOptions opt;
  CHECK(cameras(opt) == std::vector<int>(p.waypoints.size(), 2000));  // PX4: IMAGE_START_CAPTURE
  opt.firmware_type = adaptseg::mavlink::kAutopilotArduPilot;
  CHECK(cameras(opt) == std::vector<int>(p.waypoints.size(), 203));  // ArduPilot: DO_DIGICAM_CONTROL
  opt.camera_trigger = adaptseg::CameraTrigger::image_start_capture;
  CHECK(cameras(opt) == std::vector<int>(p.waypoints.size(), 2000));
  opt.firmware_type = adaptseg::mavlink::kAutopilotPx4;
  opt.camera_trigger = adaptseg::CameraTrigger::digicam_control;
  CHECK(cameras(opt) == std::vector<int>(p.waypoints.size(), 203));
  // In the files too: the .plan of an ArduPilot mission triggers with 203.
  adaptseg::ExportOptions ardupilot;
  ardupilot.firmware_type = adaptseg::mavlink::kAutopilotArduPilot;
  const auto plan = adaptseg::read_qgc_plan(adaptseg::write_qgc_plan(p, ardupilot));
  CHECK(plan.items[3].command == 203);
  CHECK(adaptseg::read_wpl(adaptseg::write_wpl(p, ardupilot)).items[3].command == 203);
}

TEST_CASE("export: a mission longer than the firmware stores is refused, naming the count and the limit") {
  // 250 waypoints: take-off, speed, 250 x (waypoint, camera), RTL = 503 items.
  const adaptseg::LawnmowerPlanner planner(adaptseg::CameraModel{});
  const auto path = planner.plan({0.0, 0.0, 250 * 14.4, 10.0}, 3.0);
  REQUIRE(path.size() == 250);
  const ExportPath p = adaptseg::make_export_path(path, GeoReference(kGeo), "long");
  adaptseg::ExportOptions opt;  // PX4: 500
  CHECK_THROWS_WITH_AS(
      (void)adaptseg::mission_items(p, opt),
      doctest::Contains("the mission has 503 mission items (250 waypoints), more than the PX4 limit of 500"),
      std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)adaptseg::write_qgc_plan(p, opt), doctest::Contains("more than the PX4 limit of 500"),
                       std::invalid_argument);
  opt.firmware_type = adaptseg::mavlink::kAutopilotArduPilot;  // 717
  CHECK(adaptseg::mission_items(p, opt).size() == 503);
  opt.max_mission_items = 400;
  CHECK_THROWS_WITH_AS((void)adaptseg::write_wpl(p, opt), doctest::Contains("more than max_mission_items 400"),
                       std::invalid_argument);
  opt.firmware_type = adaptseg::mavlink::kAutopilotPx4;
  opt.max_mission_items = 2000;  // a board built with more
  CHECK(adaptseg::mission_items(p, opt).size() == 503);
  CHECK(adaptseg::firmware_mission_item_limit(0) == std::nullopt);
  opt.max_mission_items = 0;
  CHECK_THROWS_WITH_AS((void)adaptseg::mission_items(p, opt), doctest::Contains("max_mission_items must be > 0"),
                       std::invalid_argument);
}

TEST_CASE("export: a geofence goes into the .plan as QGroundControl writes it, and reads back") {
  ExportPath p = sample_path();
  const GeoReference geo(kGeo);
  const auto at = [&](double x, double y) { return geo.to_wgs84({x, y, 0.0}); };
  adaptseg::GeoFencePolygon outer{true, {at(-5, -5), at(45, -5), at(45, 35), at(-5, 35)}};
  adaptseg::GeoFencePolygon hole{false, {at(10, 10), at(20, 10), at(15, 20)}};
  for (auto* f : {&outer, &hole})
    for (auto& v : f->vertices) v.altitude_m = 0.0;
  p.geofence = {outer, hole};
  const std::string text = adaptseg::write_qgc_plan(p);
  const auto j = nlohmann::json::parse(text);
  const auto& polygons = j["geoFence"]["polygons"];
  REQUIRE(polygons.size() == 2);
  CHECK(j["geoFence"]["version"] == 2);
  CHECK(j["geoFence"]["circles"].empty());
  CHECK(polygons[0]["inclusion"] == true);
  CHECK(polygons[1]["inclusion"] == false);
  CHECK(polygons[0]["version"] == 1);
  REQUIRE(polygons[0]["polygon"].size() == 4);  // not closed
  CHECK(polygons[0]["polygon"][1][0] == outer.vertices[1].latitude_deg);
  CHECK(polygons[0]["polygon"][1][1] == outer.vertices[1].longitude_deg);
  const adaptseg::MissionFile back = adaptseg::read_qgc_plan(text);
  REQUIRE(back.geofence.size() == 2);
  CHECK(back.geofence[0] == outer);
  CHECK(back.geofence[1] == hole);
  // WPL has no place for a fence; the mission is the same.
  CHECK(adaptseg::read_wpl(adaptseg::write_wpl(p)).items.size() == adaptseg::mission_items(p).size());
  // Broken fences are refused, both ways.
  p.geofence = {adaptseg::GeoFencePolygon{true, {at(0, 0), at(1, 0)}}};
  CHECK_THROWS_WITH_AS((void)adaptseg::write_qgc_plan(p), doctest::Contains("needs at least 3 vertices"),
                       std::invalid_argument);
  auto bad = j;
  bad["geoFence"]["polygons"][0].erase("inclusion");
  CHECK_THROWS_WITH_AS((void)adaptseg::read_qgc_plan(bad.dump()),
                       doctest::Contains("geoFence.polygons[0]: missing key 'inclusion'"), std::invalid_argument);
  // More vertices than the firmware keeps: 64 for PX4 and ArduPilot (63 kept).
  adaptseg::GeoFencePolygon many{true, {}};
  for (int k = 0; k < 64; ++k)
    many.vertices.push_back(
        at(20 + 30 * std::cos(k * 2 * std::numbers::pi / 64), 15 + 30 * std::sin(k * 2 * std::numbers::pi / 64)));
  p.geofence = {many};
  CHECK_THROWS_WITH_AS((void)adaptseg::write_qgc_plan(p),
                       doctest::Contains("the geofence has 64 vertices, more than the PX4 limit of 63"),
                       std::invalid_argument);
}

TEST_CASE("export: a via point is flown through, no hold and no image") {
  ExportPath p = sample_path();
  p.waypoints[1].via = true;
  const auto items = adaptseg::mission_items(p);
  REQUIRE(items.size() == 2 * p.waypoints.size() + 2);
  CHECK(items[4].command == 16);
  CHECK(items[4].params[0] == 0.0);  // no hold
  CHECK(items[5].command == 16);     // the next waypoint: no camera item between
  CHECK(items[6].command == 2000);
  CHECK(items[6].params[3] == 2.0);  // the second image
  const ExportPath back = adaptseg::read_geojson(adaptseg::write_geojson(p));
  CHECK(back.waypoints[1].via);
  CHECK_FALSE(back.waypoints[0].via);
  CHECK(nlohmann::json::parse(adaptseg::write_geojson(p))["features"][2]["properties"]["role"] == "via");
}

TEST_CASE("sorties: each fits the flight-time limit, in order, and none could take the next waypoint") {
  const adaptseg::LawnmowerPlanner planner(adaptseg::CameraModel{});
  const std::vector<adaptseg::Waypoint> path = planner.plan({0.0, 0.0, 80.0, 60.0}, 2.0);  // 9.6 m x 7.2 m footprints
  REQUIRE(path.size() == 81);
  const adaptseg::TimingModel timing;
  const Eigen::Vector3d home(-20.0, -10.0, 0.0);
  const double limit = 200.0;
  const auto sorties = adaptseg::split_into_sorties(path, home, timing, 1.0, limit);
  REQUIRE(sorties.size() > 1);
  std::size_t next = 0;
  for (std::size_t k = 0; k < sorties.size(); ++k) {
    CAPTURE(k);
    const adaptseg::Sortie& s = sorties[k];
    CHECK(s.first == next);
    CHECK(s.end > s.first);
    const std::span<const adaptseg::Waypoint> part(path.data() + s.first, s.size());
    CHECK(s.flight_s == doctest::Approx(adaptseg::sortie_flight_s(part, home, timing, 1.0)));
    CHECK(s.flight_s <= limit);
    if (s.end < path.size())  // one waypoint more would not fit
      CHECK(adaptseg::sortie_flight_s(std::span<const adaptseg::Waypoint>(path.data() + s.first, s.size() + 1), home,
                                      timing, 1.0) > limit);
    next = s.end;
  }
  CHECK(next == path.size());
  // Take-off straight up, legs, holds, back level and down: one waypoint 30 m above (0, 0).
  adaptseg::Waypoint w;
  w.position = {30.0, 40.0, 30.0};
  const std::vector<adaptseg::Waypoint> one{w};
  const double up = timing.segment_time_s(Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 30));
  const double across = timing.segment_time_s(Eigen::Vector3d(0, 0, 30), Eigen::Vector3d(30, 40, 30));
  CHECK(adaptseg::sortie_flight_s(one, Eigen::Vector3d::Zero(), timing, 2.0) ==
        doctest::Approx(2 * up + 2 * across + 2.0));
  // Without a limit, one sortie; a waypoint that alone does not fit is named.
  CHECK(adaptseg::split_into_sorties(path, home, timing, 1.0).size() == 1);
  CHECK_THROWS_WITH_AS((void)adaptseg::split_into_sorties(one, Eigen::Vector3d::Zero(), timing, 1.0, 30.0),
                       doctest::Contains("waypoint 0 alone takes 85 s from home and back, more than max_flight_s 30 s"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)adaptseg::split_into_sorties(path, home, timing, 1.0, 0.0),
                       doctest::Contains("max_flight_s"), std::invalid_argument);
}

TEST_CASE("fence route: legs that would leave an L-shaped fence or cross its hole bend at its corners") {
  // An L (an 80 x 60 m square less its 40 x 30 m upper-right quarter) with a 10 m square hole.
  const std::vector<Eigen::Vector2d> l{{0, 0}, {80, 0}, {80, 30}, {40, 30}, {40, 60}, {0, 60}};
  const std::vector<Eigen::Vector2d> hole{{15, 10}, {25, 10}, {25, 20}, {15, 20}};
  const adaptseg::FenceRouter router({l, hole}, {true, false}, 1.0);
  CHECK(router.inside({5, 5}));
  CHECK_FALSE(router.inside({60, 45}));          // the missing quarter
  CHECK_FALSE(router.inside({20, 15}));          // the hole
  CHECK(router.route({5, 5}, {75, 5}).empty());  // straight and clear
  // Across the missing quarter: one bend at its corner (40, 30), on the inside.
  const auto vias = router.route({70, 25}, {35, 55});
  REQUIRE(vias.size() == 1);
  CHECK((vias[0] - Eigen::Vector2d(40, 30)).norm() < 10.0);
  CHECK(vias[0].x() < 40.0);
  CHECK(vias[0].y() < 30.0);
  // Through the hole: around it, every leg clear.
  const std::vector<Eigen::Vector2d> ends{{5, 15}, {35, 15}};
  const auto around = router.route(ends[0], ends[1]);
  REQUIRE(!around.empty());
  std::vector<Eigen::Vector2d> all{ends[0]};
  all.insert(all.end(), around.begin(), around.end());
  all.push_back(ends[1]);
  for (std::size_t k = 1; k < all.size(); ++k) CHECK(router.clear(all[k - 1], all[k]));
  CHECK_THROWS_WITH_AS((void)router.route({60, 45}, {5, 5}), doctest::Contains("outside the geofence"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(adaptseg::FenceRouter({{{0, 0}, {1, 0}}}, {true}, 1.0), doctest::Contains("at least 3 vertices"),
                       std::invalid_argument);
}
