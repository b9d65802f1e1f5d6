#include <adaptseg/core/timing.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <stdexcept>
#include <vector>

using adaptseg::TimingModel;

TEST_CASE("timing: velocity ramp below and above the cruise distance v^2/a") {
  const TimingModel t({.max_speed_mps = 2.0, .max_accel_mps2 = 2.0});  // v^2/a = 2 m
  CHECK(t.segment_time_s(0.0) == 0.0);
  CHECK(t.segment_time_s(1.0) == doctest::Approx(2.0 * std::sqrt(0.5)));     // triangle profile
  CHECK(t.segment_time_s(10.0) == doctest::Approx(10.0 / 2.0 + 2.0 / 2.0));  // trapezoid
  // Continuous at the switch: 2 sqrt(d/a) = d/v + v/a = 2 v / a at d = v^2 / a.
  CHECK(t.segment_time_s(2.0 - 1e-12) == doctest::Approx(t.segment_time_s(2.0)));
  CHECK(t.segment_time_s(2.0) == doctest::Approx(2.0));
  // Monotone in distance.
  double prev = 0.0;
  for (double d = 0.05; d < 30.0; d += 0.05) {
    const double now = t.segment_time_s(d);
    CHECK(now > prev);
    prev = now;
  }
}

TEST_CASE("timing: 3-D segments include altitude changes, and paths add segments") {
  const TimingModel t;
  const Eigen::Vector3d a(0, 0, 10), b(3, 4, 10), c(3, 4, 22);
  CHECK(t.segment_time_s(a, b) == doctest::Approx(t.segment_time_s(5.0)));
  CHECK(t.segment_time_s(b, c) == doctest::Approx(t.segment_time_s(12.0)));
  const std::vector<Eigen::Vector3d> path{a, b, c};
  CHECK(t.path_time_s(path) == doctest::Approx(t.segment_time_s(5.0) + t.segment_time_s(12.0)));
  // Stopping in between costs time: a straight 17 m is faster than 5 m + 12 m with a stop.
  CHECK(t.segment_time_s(17.0) < t.path_time_s(path));
}

TEST_CASE("timing: invalid limits and distances are rejected") {
  CHECK_THROWS_WITH_AS(TimingModel({.max_speed_mps = 0.0}), doctest::Contains("max_speed_mps"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(TimingModel({.max_accel_mps2 = -1.0}), doctest::Contains("max_accel_mps2"),
                       std::invalid_argument);
  CHECK_THROWS_AS((void)TimingModel{}.segment_time_s(-0.1), std::invalid_argument);
  CHECK_THROWS_AS((void)TimingModel{}.segment_time_s(std::nan("")), std::invalid_argument);
}

TEST_CASE("timing: a vertical speed limit slows climbs and descents, not level legs") {
  const TimingModel iso;  // the paper's isotropic model: no vertical limit
  const TimingModel t({.max_speed_mps = 2.0, .max_accel_mps2 = 2.0, .max_vertical_speed_mps = 0.5});
  const Eigen::Vector3d a(0, 0, 10), b(3, 4, 10), c(3, 4, 22);
  // Level: unchanged.
  CHECK(t.segment_time_s(a, b) == iso.segment_time_s(a, b));
  // Vertical, 12 m at v_z = 0.5 m/s (reached after 0.25 m): 12 / 0.5 + 0.5 / 2.
  CHECK(t.segment_time_s(b, c) == doctest::Approx(24.25));
  CHECK(t.segment_time_s(c, b) == doctest::Approx(24.25));  // sinking as climbing
  // The Dubai descent: 72 m across, 55 m down (15 -> 5 cm/px), v_z = 1 m/s. The line's speed is
  // capped at v_z d / |dz| = 1.65 m/s < v.
  const TimingModel one({.max_vertical_speed_mps = 1.0});
  const Eigen::Vector3d top(0, 0, 82.5), low(72, 0, 27.5);
  const double d = std::hypot(72.0, 55.0);
  CHECK(one.segment_time_s(top, low) == doctest::Approx(d / (d / 55.0) + (d / 55.0) / 2.0));
  CHECK(one.segment_time_s(top, low) > iso.segment_time_s(top, low) + 9.0);
  // A limit the leg never reaches changes nothing, to the bit.
  const TimingModel fast({.max_vertical_speed_mps = 5.0});
  CHECK(fast.segment_time_s(top, low) == iso.segment_time_s(top, low));
  // Short legs that never reach the capped speed: the triangle profile, unchanged.
  const Eigen::Vector3d up(0, 0, 10.05);
  CHECK(t.segment_time_s(a, up) == doctest::Approx(2.0 * std::sqrt(0.05 / 2.0)));
  // Paths add the capped segments.
  const std::vector<Eigen::Vector3d> path{a, b, c};
  CHECK(t.path_time_s(path) == doctest::Approx(iso.segment_time_s(5.0) + 24.25));
  CHECK_THROWS_WITH_AS(TimingModel({.max_vertical_speed_mps = -1.0}),
                       doctest::Contains("max_vertical_speed_mps must be finite and >= 0"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(TimingModel({.max_vertical_speed_mps = std::nan("")}),
                       doctest::Contains("max_vertical_speed_mps"), std::invalid_argument);
}
