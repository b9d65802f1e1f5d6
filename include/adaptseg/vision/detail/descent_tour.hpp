#pragma once
/// @file
/// The descents the adaptive planner (adaptive_planner.hpp) has chosen: the one in progress,
/// and those a schedule defers (DescentSchedule::tour, row) queued as one tour per window.

#include <adaptseg/core/inspection_tour.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/timing.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <iterator>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// A descent the policy chose.
struct ChosenDescent {
  std::size_t decision = 0;   ///< index into the planner's decisions
  std::size_t top_index = 0;  ///< its region's top-level waypoint
  double altitude_m = 0.0;    ///< h'
  std::size_t ordinal = 0;    ///< 0, 1, ... in the order chosen (DescentOutcome::descent)
  std::vector<Waypoint> plan;
  bool deferred = false;  ///< flown in a tour (DescentSchedule::tour, row), not at once
};

/// The deferred descents of one window of the top-level lawnmower (the survey, or a row),
/// flown as one tour from the window's last top-level waypoint to the next window's first:
/// each queued where the decision costed it (its insertion into the tour so far), reordered
/// once before the first is flown (plan_tour_order: never longer than the order charged).
class DescentTour {
 public:
  /// Queues `d` (deferred) as `stop`, at `position` of the flying order so far.
  void add(ChosenDescent d, const TourStop& stop, std::size_t position) {
    stops_.push_back(stop);
    order_.insert(order_.begin() + static_cast<std::ptrdiff_t>(position), queued_.size());
    images_ += d.plan.size();
    queued_.push_back(std::move(d));
  }

  /// The next descent to fly, the tour from `start` to `end` reordered first if none is flown yet.
  [[nodiscard]] const ChosenDescent& take_next(const TimingModel& timing, const Eigen::Vector3d& start,
                                               const TourEnd& end) {
    if (next_ == 0) order_ = plan_tour_order(timing, start, stops_, std::move(order_), end);
    return queued_[order_[next_++]];
  }

  /// After the window's tour is flown: the next window's starts empty.
  void clear() {
    queued_.clear();
    stops_.clear();
    order_.clear();
    next_ = 0;
    images_ = 0;
  }

  [[nodiscard]] bool empty() const noexcept { return order_.empty(); }
  /// Whether a descent of it has been taken (take_next()).
  [[nodiscard]] bool started() const noexcept { return next_ > 0; }
  /// Whether every descent queued has been taken (true for an empty tour).
  [[nodiscard]] bool taken() const noexcept { return next_ >= order_.size(); }
  /// Images of every descent queued.
  [[nodiscard]] std::size_t images() const noexcept { return images_; }
  [[nodiscard]] const std::vector<TourStop>& stops() const noexcept { return stops_; }
  [[nodiscard]] const std::vector<std::size_t>& order() const noexcept { return order_; }
  /// The descents not yet taken, in flying order (indices into stops()), and their images.
  [[nodiscard]] std::vector<std::size_t> order_left() const {
    return {order_.begin() + static_cast<std::ptrdiff_t>(next_), order_.end()};
  }
  [[nodiscard]] double images_left() const {
    double n = 0.0;
    for (std::size_t k = next_; k < order_.size(); ++k) n += static_cast<double>(queued_[order_[k]].plan.size());
    return n;
  }

  /// What the tour adds to the top-level flight from `start` to `end` [s] (it replaces the
  /// direct leg between them); 0 for an empty tour.
  [[nodiscard]] double extra_s(const TimingModel& timing, const Eigen::Vector3d& start, const TourEnd& end) const {
    if (order_.empty()) return 0.0;
    return tour_flight_s(timing, start, stops_, order_, end) - (end ? timing.segment_time_s(start, *end) : 0.0);
  }

 private:
  std::vector<ChosenDescent> queued_;  ///< every descent deferred in the window, in decision order
  std::vector<TourStop> stops_;        ///< ... as tour stops (same order)
  std::vector<std::size_t> order_;     ///< indices into queued_, in flight order
  std::size_t next_ = 0;               ///< next of order_ to fly
  std::size_t images_ = 0;             ///< images of the queued descents
};

}  // namespace adaptseg::detail
