#pragma once
/// @file
/// A mission's time account: flight, segmentation and planning, charged as they happen.

namespace adaptseg {

/// Mission time [s] by what it was spent on. Mission keeps one for the images it flies and
/// segments; AdaptivePlanner keeps its own, or charges its planning into one it shares (the
/// simulation's: run_adaptive_mission gives the planner the mission's, so that one account
/// holds the mission's time and nothing is handed from one to the other).
struct TimeAccount {
  double flight_s = 0.0;        ///< flight by the timing model along the legs flown
  double segmentation_s = 0.0;  ///< segmentation, measured or fixed per image
  double planning_s = 0.0;      ///< planning, measured or fixed per waypoint

  /// Time so far: flight + segmentation + planning [s].
  [[nodiscard]] double total_s() const noexcept { return flight_s + segmentation_s + planning_s; }
};

}  // namespace adaptseg
