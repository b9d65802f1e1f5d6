#pragma once
/// @file
/// Velocity-ramp flight-time model (method.md §2).

#include <adaptseg/error.hpp>

#include <Eigen/Core>

#include <cmath>
#include <span>

namespace adaptseg {

/// Speed limits of the velocity-ramp model; validated by TimingModel's constructor.
struct TimingParams {
  double max_speed_mps = 2.0;   ///< v [m/s]
  double max_accel_mps2 = 2.0;  ///< a [m/s^2]
};

/// Flight time of straight segments flown from standstill to standstill (the UAV stops at
/// every waypoint, paper §3.2.1 (iv)) with maximum speed v and maximum acceleration a:
/// `t(d) = 2 sqrt(d / a)` if `d < v^2 / a` (the UAV never reaches v), else `d / v + v / a`.
/// Defaults v = 2 m/s, a = 2 m/s^2, as in the Bonn group's open planners.
class TimingModel {
 public:
  using Params = TimingParams;

  /// @throws std::invalid_argument if a value is not finite and positive.
  explicit TimingModel(Params params = {}) : params_(params) {
    detail::require_positive(params_.max_speed_mps, "TimingModel: max_speed_mps");
    detail::require_positive(params_.max_accel_mps2, "TimingModel: max_accel_mps2");
  }

  [[nodiscard]] const Params& params() const noexcept { return params_; }

  /// Time [s] to fly a straight segment of length `distance_m` [m], at rest at both ends.
  /// @throws std::invalid_argument if the distance is negative or not finite.
  [[nodiscard]] double segment_time_s(double distance_m) const {
    detail::require(std::isfinite(distance_m) && distance_m >= 0.0,
                    "TimingModel::segment_time_s: distance_m must be finite and >= 0", distance_m);
    const double v = params_.max_speed_mps;
    const double a = params_.max_accel_mps2;
    if (distance_m < v * v / a) return 2.0 * std::sqrt(distance_m / a);
    return distance_m / v + v / a;
  }

  /// Time [s] between two 3-D positions [m] (altitude changes included).
  [[nodiscard]] double segment_time_s(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const {
    return segment_time_s((to - from).norm());
  }

  /// Time [s] to fly through `points` in order, stopping at each.
  [[nodiscard]] double path_time_s(std::span<const Eigen::Vector3d> points) const {
    double t = 0.0;
    for (std::size_t i = 1; i < points.size(); ++i) t += segment_time_s(points[i - 1], points[i]);
    return t;
  }

 private:
  Params params_;
};

}  // namespace adaptseg
