#pragma once
/// @file
/// Velocity-ramp flight-time model (docs/method.md, "Decisions where the paper is silent, and
/// departures").

#include <adaptseg/core/error.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <span>

namespace adaptseg {

/// Speed limits of the velocity-ramp model; validated by TimingModel's constructor.
struct TimingParams {
  double max_speed_mps = 2.0;   ///< v [m/s], along the segment
  double max_accel_mps2 = 2.0;  ///< a [m/s^2], along the segment
  /// v_z [m/s]: limit of the vertical component of the speed (real multicopters climb and sink
  /// slower than they fly level); 0 = none, the paper's isotropic model (the default).
  double max_vertical_speed_mps = 0.0;
};

/// Flight time of straight segments flown from standstill to standstill (the UAV stops at
/// every waypoint, paper §3.2.1 (iv)) with maximum speed v and maximum acceleration a:
/// `t(d) = 2 sqrt(d / a)` if `d < v^2 / a` (the UAV never reaches v), else `d / v + v / a`.
/// Defaults v = 2 m/s, a = 2 m/s^2, as in the Bonn group's open planners.
///
/// With a vertical speed limit v_z (beyond the paper), a 3-D segment of length d that climbs or
/// sinks by |dz| is flown on the same straight line with its speed capped so that the vertical
/// component stays within v_z: the ramp above with v replaced by `min(v, v_z d / |dz|)` (the
/// acceleration along the line stays a). A vertical leg then takes `|dz| / v_z + v_z / a` once
/// it reaches v_z; level legs are unchanged.
class TimingModel {
 public:
  using Params = TimingParams;

  /// @throws std::invalid_argument if v or a is not finite and positive, or v_z is not finite
  ///         and >= 0.
  explicit TimingModel(Params params = {}) : params_(params) {
    detail::require_positive(params_.max_speed_mps, "TimingModel: max_speed_mps");
    detail::require_positive(params_.max_accel_mps2, "TimingModel: max_accel_mps2");
    detail::require(std::isfinite(params_.max_vertical_speed_mps) && params_.max_vertical_speed_mps >= 0.0,
                    "TimingModel: max_vertical_speed_mps must be finite and >= 0 (0: no vertical limit)",
                    params_.max_vertical_speed_mps);
  }

  [[nodiscard]] const Params& params() const noexcept { return params_; }

  /// Time [s] to fly a level straight segment of length `distance_m` [m], at rest at both ends.
  /// @throws std::invalid_argument if the distance is negative or not finite.
  [[nodiscard]] double segment_time_s(double distance_m) const {
    detail::require(std::isfinite(distance_m) && distance_m >= 0.0,
                    "TimingModel::segment_time_s: distance_m must be finite and >= 0", distance_m);
    return ramp_time_s(distance_m, params_.max_speed_mps);
  }

  /// Time [s] between two 3-D positions [m] (altitude changes included, under the vertical
  /// speed limit if one is set).
  [[nodiscard]] double segment_time_s(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const {
    const double d = (to - from).norm();
    detail::require(std::isfinite(d), "TimingModel::segment_time_s: positions must be finite", d);
    const double dz = std::abs(to.z() - from.z());
    const double vz = params_.max_vertical_speed_mps;
    double v = params_.max_speed_mps;
    if (vz > 0.0 && dz > 0.0) v = std::min(v, vz * d / dz);
    return ramp_time_s(d, v);
  }

  /// Time [s] to fly through `points` in order, stopping at each.
  [[nodiscard]] double path_time_s(std::span<const Eigen::Vector3d> points) const {
    double t = 0.0;
    for (std::size_t i = 1; i < points.size(); ++i) t += segment_time_s(points[i - 1], points[i]);
    return t;
  }

 private:
  /// The velocity ramp over distance d with top speed v and acceleration a.
  [[nodiscard]] double ramp_time_s(double d, double v) const {
    const double a = params_.max_accel_mps2;
    if (d < v * v / a) return 2.0 * std::sqrt(d / a);
    return d / v + v / a;
  }

  Params params_;
};

}  // namespace adaptseg
