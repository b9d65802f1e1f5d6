#pragma once
/// @file
/// The settings every mission shares (camera, timing, labels of interest, fixed per-image and
/// per-waypoint times): what the live planner and the simulated missions both need, without
/// the simulator.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/map_fusion.hpp>
#include <adaptseg/core/timing.hpp>

#include <cmath>
#include <optional>
#include <vector>

namespace adaptseg {

/// Settings common to every mission.
struct MissionOptions {
  CameraModel::Params camera{};
  TimingModel::Params timing{};
  /// Labels of interest L; empty: the field's default (`Field::interest()`).
  std::vector<int> interest{};
  /// If set, every image costs this segmentation time [s] instead of the measured one
  /// (deterministic runs: tests, reference results).
  std::optional<double> fixed_segmentation_time_s{};
  /// If set, every waypoint costs this planning time [s] instead of the measured one.
  std::optional<double> fixed_planning_time_s{};
  /// How the field map combines the images of one pixel (MapFusion); `pooled` reads the
  /// backend's class probabilities.
  MapFusion map_fusion = MapFusion::finest;
};

namespace detail {

/// Throws unless the fixed segmentation and planning times, where set, are finite and >= 0.
inline void check_fixed_times(const MissionOptions& options) {
  if (options.fixed_segmentation_time_s)
    require(std::isfinite(*options.fixed_segmentation_time_s) && *options.fixed_segmentation_time_s >= 0.0,
            "MissionOptions: fixed_segmentation_time_s must be finite and >= 0", *options.fixed_segmentation_time_s);
  if (options.fixed_planning_time_s)
    require(std::isfinite(*options.fixed_planning_time_s) && *options.fixed_planning_time_s >= 0.0,
            "MissionOptions: fixed_planning_time_s must be finite and >= 0", *options.fixed_planning_time_s);
}

}  // namespace detail

}  // namespace adaptseg
