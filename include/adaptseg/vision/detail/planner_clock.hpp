#pragma once
/// @file
/// The adaptive planner's time account (AdaptivePlanner, adaptive_planner.hpp): the mission
/// time so far, and what the budget reserves for each step still to come.

#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/core/time_account.hpp>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <optional>
#include <utility>

namespace adaptseg::detail {

/// Seconds elapsed since `t0` on the steady clock (the planner's measured planning time).
[[nodiscard]] inline double seconds_since(std::chrono::steady_clock::time_point t0) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// Mission time as the adaptive planner counts it, in its own TimeAccount or in one it shares:
/// flight by the timing model along the legs flown, segmentation per image and planning
/// (measured, or fixed per image / waypoint by the MissionOptions), unless the caller reported
/// its own clock with the last image; and the bound of a step's processing that the budget
/// reserves for each step still to come. A shared account is charged flight and segmentation
/// by its owner (the Mission that flies and segments), planning by the planner.
class PlannerClock {
 public:
  /// Fixed segmentation and planning times from `options` where it sets them (checked by
  /// check_fixed_times()); the planner's own account, or `shared` (not null: it must outlive
  /// the clock).
  explicit PlannerClock(const MissionOptions& options, TimeAccount* shared = nullptr)
      : fixed_segmentation_s_(options.fixed_segmentation_time_s),
        fixed_planning_s_(options.fixed_planning_time_s),
        shared_(shared) {}

  /// A waypoint handed out: the fixed planning time per waypoint, where the options set one.
  void waypoint_handed_out() {
    if (fixed_planning_s_) account().planning_s += *fixed_planning_s_;
  }

  /// An image reported after the flight model's `leg_s` [s], segmented in `segmentation_s` [s]
  /// (the fixed time instead where the options set one), with the mission time the caller
  /// measured if it did (`reported_elapsed_s`, used instead of the own account from now on
  /// until the next image). What the step cost beyond the leg (the mission clock's advance
  /// since the last image: segmentation, the planner's own time, and whatever else the caller's
  /// clock counted) feeds step_bound().
  void image_reported(double leg_s, double segmentation_s, std::optional<double> reported_elapsed_s) {
    reported_elapsed_s_ = reported_elapsed_s;
    if (reported_elapsed_s) caller_clock_ = true;
    const double seg = fixed_segmentation_s_.value_or(segmentation_s);
    if (!shared_) own_.flight_s += leg_s, own_.segmentation_s += seg;
    slowest_segmentation_s_ = std::max(slowest_segmentation_s_, seg);
    const double now = elapsed_s();
    slowest_step_s_ = std::max(slowest_step_s_, std::max(0.0, now - elapsed_at_last_image_s_ - leg_s));
    elapsed_at_last_image_s_ = now;
    ++steps_;
  }

  /// Measured planner computation `s` [s]: charged as planning time unless the options fix it,
  /// and kept for take_planning_s().
  void charge_planning(double s) {
    untaken_planning_s_ += s;
    if (!fixed_planning_s_) account().planning_s += s;
  }

  /// Mission time so far [s]: what the caller reported with the last image if it did,
  /// otherwise the account's (flight + segmentation + planning).
  [[nodiscard]] double elapsed_s() const noexcept { return reported_elapsed_s_.value_or(account().total_s()); }

  /// Measured planner computation [s] since the last call.
  [[nodiscard]] double take_planning_s() noexcept { return std::exchange(untaken_planning_s_, 0.0); }

  /// What an image's segmentation is expected to take [s]: the fixed time, or 1.25 times the
  /// slowest so far (0 before the first image).
  [[nodiscard]] double segmentation_estimate() const {
    return fixed_segmentation_s_.value_or(1.25 * slowest_segmentation_s_);
  }
  /// What a waypoint's planning is expected to take [s]: the fixed time, or 0.
  [[nodiscard]] double planning_estimate() const { return fixed_planning_s_.value_or(0.0); }
  /// Both [s]: what a forecast charges per image beyond its flight.
  [[nodiscard]] double per_image_estimate() const { return segmentation_estimate() + planning_estimate(); }

  /// Whether segmentation and planning times are both fixed.
  [[nodiscard]] bool times_fixed() const { return fixed_segmentation_s_.has_value() && fixed_planning_s_.has_value(); }

  /// Whether the budget reserves exactly: segmentation and planning times both fixed, and the
  /// mission time the account's, never a clock the caller reported. A caller's clock (a vehicle's)
  /// advances by whatever a step really costs (braking, hovering, the link, processing slower
  /// than the fixed times say), which fixed times do not bound.
  [[nodiscard]] bool reserves_exactly() const { return times_fixed() && !caller_clock_; }

  /// What the budget reserves for each step still to come beyond its flight [s]: where it
  /// reserves exactly (reserves_exactly()), the fixed segmentation and planning times' sum;
  /// otherwise a bound learned from the steps so far, each step's advance of the mission clock
  /// beyond the flight model's leg: the largest of k steps times (k + 1) / k (for processing
  /// times spread uniformly up to some limit, an unbiased estimate of the limit; generous while
  /// few steps are seen), and never less than segmentation_estimate() (with fixed times, never
  /// less than their sum). 0 before the first image.
  [[nodiscard]] double step_bound() const {
    if (reserves_exactly()) return per_image_estimate();
    const double floor = times_fixed() ? per_image_estimate() : segmentation_estimate();
    if (steps_ == 0) return floor;
    const double k = static_cast<double>(steps_);
    return std::max(floor, slowest_step_s_ * (k + 1.0) / k);
  }

  /// What the budget reserves for the step in progress beyond the bounds of those to come [s]:
  /// unless it reserves exactly, one more bound (the decision being made is not yet charged).
  [[nodiscard]] double this_step_reserve() const { return reserves_exactly() ? 0.0 : step_bound(); }

 private:
  std::optional<double> fixed_segmentation_s_;
  std::optional<double> fixed_planning_s_;
  TimeAccount own_;
  TimeAccount* shared_ = nullptr;  ///< the account charged instead of own_, if any
  double slowest_segmentation_s_ = 0.0;
  double slowest_step_s_ = 0.0;           ///< the largest advance of the clock beyond a leg's flight [s]
  double elapsed_at_last_image_s_ = 0.0;  ///< elapsed_s() when the last image was reported
  std::size_t steps_ = 0;                 ///< images reported
  double untaken_planning_s_ = 0.0;
  std::optional<double> reported_elapsed_s_;
  bool caller_clock_ = false;  ///< whether any image came with the caller's mission time

  [[nodiscard]] TimeAccount& account() noexcept { return shared_ ? *shared_ : own_; }
  [[nodiscard]] const TimeAccount& account() const noexcept { return shared_ ? *shared_ : own_; }
};

}  // namespace adaptseg::detail
