#include <adaptseg/core/camera.hpp>

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
  const CameraModel cam({.image_width_px = 640, .image_height_px = 480, .sensor_width_mm = 6.17,
                         .focal_length_mm = 4.5});
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
  CHECK_THROWS_WITH_AS(CameraModel({.image_width_px = 0}), doctest::Contains("image_width_px"),
                       std::invalid_argument);
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
