#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/camera_presets.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <limits>
#include <stdexcept>

using adaptseg::CameraModel;

TEST_CASE("camera: GSD follows 100 h S_w / (f I_w) for the default camera") {
  const CameraModel cam;  // 480 px, 4.8 mm sensor, 5.5 mm lens
  // 100 * 16.5 * 4.8 / (5.5 * 480) = 3.0 cm/px
  CHECK(cam.gsd_cm(16.5) == doctest::Approx(3.0).epsilon(1e-12));
  CHECK(cam.gsd_cm(5.5) == doctest::Approx(1.0).epsilon(1e-12));
  CHECK(cam.altitude_m(3.0) == doctest::Approx(16.5).epsilon(1e-12));
}

TEST_CASE("camera: altitude and GSD are inverse, and the footprint scales with altitude") {
  const CameraModel cam(
      {.image_width_px = 640, .image_height_px = 480, .sensor_width_mm = 6.17, .focal_length_mm = 4.5});
  for (double h : {1.0, 7.3, 30.0, 120.0}) {
    CHECK(cam.altitude_m(cam.gsd_cm(h)) == doctest::Approx(h).epsilon(1e-12));
    const auto fp = cam.footprint(h);
    CHECK(fp.width_m == doctest::Approx(640 * cam.gsd_cm(h) / 100.0));
    CHECK(fp.height_m == doctest::Approx(480 * cam.gsd_cm(h) / 100.0));
    CHECK(fp.width_m / fp.height_m == doctest::Approx(640.0 / 480.0));
  }
  const auto fp = CameraModel{}.footprint_at_gsd(3.0);
  CHECK(fp.width_m == doctest::Approx(14.4));
  CHECK(fp.height_m == doctest::Approx(10.8));
}

TEST_CASE("camera: invalid parameters are rejected with the parameter's name") {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH_AS(CameraModel({.image_width_px = 0}), doctest::Contains("image_width_px"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(CameraModel({.image_height_px = -3}), doctest::Contains("image_height_px"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(CameraModel({.sensor_width_mm = 0.0}), doctest::Contains("sensor_width_mm"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(CameraModel({.focal_length_mm = nan}), doctest::Contains("focal_length_mm"),
                       std::invalid_argument);
  const CameraModel cam;
  CHECK_THROWS_AS((void)cam.gsd_cm(-1.0), std::invalid_argument);
  CHECK_THROWS_AS((void)cam.altitude_m(0.0), std::invalid_argument);
  CHECK_THROWS_AS((void)cam.footprint_at_gsd(std::numeric_limits<double>::infinity()), std::invalid_argument);
}

TEST_CASE("camera presets: each one a valid camera with its source, the default CameraParams's") {
  for (const auto& p : adaptseg::kCameraPresets) {
    CAPTURE(p.name);
    CHECK_NOTHROW((void)CameraModel(p.params));
    CHECK(!p.source.empty());
    CHECK(&adaptseg::camera_preset(p.name) == &p);
  }
  const adaptseg::CameraParams d = adaptseg::camera_preset("default").params, plain{};
  CHECK((d.image_width_px == plain.image_width_px && d.image_height_px == plain.image_height_px &&
         d.sensor_width_mm == plain.sensor_width_mm && d.focal_length_mm == plain.focal_length_mm));
  // DJI Phantom 4 RTK: 100 m above ground at 100 * 100 * 13.2 / (8.8 * 5472) = 2.74 cm/px, DJI's
  // own figure for its GSD at 100 m.
  CHECK(CameraModel(adaptseg::camera_preset("dji-phantom4-rtk").params).gsd_cm(100.0) ==
        doctest::Approx(2.74).epsilon(0.002));
  CHECK_THROWS_WITH_AS((void)adaptseg::camera_preset("gopro"),
                       "unknown camera 'gopro': the presets are default, micasense-rededge-mx, dji-phantom4-rtk, "
                       "dji-phantom4-pro, dji-zenmuse-p1-35mm",
                       std::invalid_argument);
}

TEST_CASE("camera presets: at_width scales the image and keeps the field of view") {
  const adaptseg::CameraParams full = adaptseg::camera_preset("dji-phantom4-rtk").params;
  const adaptseg::CameraParams small = adaptseg::at_width(full, 684);
  CHECK(small.image_width_px == 684);
  CHECK(small.image_height_px == 456);  // 3648 * 684 / 5472
  CHECK(small.sensor_width_mm == full.sensor_width_mm);
  CHECK(small.focal_length_mm == full.focal_length_mm);
  // The same footprint at every altitude; the GSD 8 times coarser.
  const CameraModel a(full), b(small);
  CHECK(b.footprint(50.0).width_m == doctest::Approx(a.footprint(50.0).width_m));
  CHECK(b.footprint(50.0).height_m == doctest::Approx(a.footprint(50.0).height_m));
  CHECK(b.gsd_cm(50.0) == doctest::Approx(8.0 * a.gsd_cm(50.0)));
  CHECK_THROWS_AS((void)adaptseg::at_width(full, 0), std::invalid_argument);
}
