#pragma once
/// @file
/// The adaptive planner's route (adaptive_planner.hpp): the top-level lawnmower cut into the
/// schedule's windows, the tour of each window's deferred descents, and what a descent adds to
/// flying them (the flight part of a candidate's exact extra time, paper §3.2.2).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/descent_schedule.hpp>
#include <adaptseg/core/inspection_tour.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/vision/detail/descent_tour.hpp>
#include <adaptseg/vision/detail/survey_grid.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// Flight time along `plan`'s waypoints, in order [s].
[[nodiscard]] inline double flight_along(const TimingModel& timing, const std::vector<Waypoint>& plan) {
  double t = 0.0;
  for (std::size_t k = 1; k < plan.size(); ++k) t += timing.segment_time_s(plan[k - 1].position, plan[k].position);
  return t;
}

/// The area's lawnmowers at some GSDs, planned as run_lawnmower_mission plans them: what the
/// mission could fly instead (a front-aware policy's yardstick, DecisionContext::lawnmowers).
class LawnmowerCosts {
 public:
  LawnmowerCosts() = default;
  LawnmowerCosts(const SurveyGrid& grid, const TimingModel& timing, const std::vector<double>& gsds) {
    for (double g : gsds) {
      const auto plan = grid.lawnmower(g);
      costs_.push_back({g, flight_along(timing, plan), plan.size()});
    }
  }
  /// Whether one of them is at `gsd_cm`.
  [[nodiscard]] bool has(double gsd_cm) const {
    return std::any_of(costs_.begin(), costs_.end(), [&](const Cost& c) { return c.gsd_cm == gsd_cm; });
  }
  /// Each one's mission time: its flight plus `per_image` [s] per image.
  [[nodiscard]] std::vector<LawnmowerForecast> forecasts(double per_image) const {
    std::vector<LawnmowerForecast> out;
    for (const Cost& c : costs_) out.push_back({c.gsd_cm, c.flight_s + static_cast<double>(c.images) * per_image});
    return out;
  }

 private:
  struct Cost {
    double gsd_cm = 0.0;
    double flight_s = 0.0;
    std::size_t images = 0;
  };
  std::vector<Cost> costs_;
};

/// The GSD the top level is flown at: `nominal` (AdaptiveOptions::top_gsd_cm), or where
/// `policy` chooses one (ChoosesTopLevel) its choice among the area's `lawnmowers` (their
/// forecast times `forecasts`); the `candidates` not finer than it are then dropped.
/// @throws std::logic_error naming the policy if it chooses a GSD that is not one of the
///         lawnmowers' or has no candidate below it.
template <class Policy>
[[nodiscard]] double choose_top_gsd(Policy& policy, const LawnmowerCosts& lawnmowers,
                                    const std::vector<LawnmowerForecast>& forecasts, double nominal,
                                    std::vector<double>& candidates) {
  if constexpr (!ChoosesTopLevel<Policy>) {
    return nominal;
  } else {
    const double g = policy.top_gsd(forecasts, nominal);
    const bool below = std::any_of(candidates.begin(), candidates.end(), [&](double c) { return c < g; });
    if (!lawnmowers.has(g) || !below)
      throw std::logic_error("decision policy '" + std::string(policy.name()) + "' chose the top-level GSD " +
                             std::to_string(g) +
                             " cm/px, which is not one of the lawnmower GSDs with a candidate below it");
    std::erase_if(candidates, [&](double c) { return c >= g; });
    return g;
  }
}

/// The top-level lawnmower W^{h_max} cut into the windows of a DescentSchedule, and the tour of
/// the window being flown (DescentTour): the flight from each top-level waypoint on, where each
/// window's tour starts and ends, and what a descent adds to the flight, flown at once or
/// inserted into the tour.
class PlannerRoute {
 public:
  PlannerRoute() = default;

  /// @throws std::logic_error if `schedule`'s windows do not cut `top` into runs of consecutive
  ///         waypoints.
  PlannerRoute(std::vector<Waypoint> top, const DescentScheduleInfo& schedule, const TimingModel& timing)
      : top_(std::move(top)), window_last_(schedule.window_last(top_)), defers_(schedule.defers) {
    // Each waypoint's window ends at or after it, and where the previous window reaches it, it is that one.
    bool runs = window_last_.size() == top_.size();
    for (std::size_t i = 0; runs && i < top_.size(); ++i)
      runs = window_last_[i] >= i && window_last_[i] < top_.size() &&
             (i == 0 || window_last_[i - 1] < i || window_last_[i - 1] == window_last_[i]);
    if (!runs)
      throw std::logic_error(std::string("descent schedule '") + schedule.name +
                             "': its windows are not runs of consecutive top-level waypoints");
    flight_after_.assign(top_.size() + 1, 0.0);
    for (std::size_t i = top_.size(); i-- > 1;)
      flight_after_[i - 1] = flight_after_[i] + timing.segment_time_s(top_[i - 1].position, top_[i].position);
  }

  [[nodiscard]] const std::vector<Waypoint>& top() const noexcept { return top_; }
  /// The last top-level waypoint of waypoint i's window.
  [[nodiscard]] std::size_t window_last(std::size_t i) const { return window_last_[i]; }
  /// The top-level flight from waypoint i on [s] (0 from the last; i up to the number of waypoints).
  [[nodiscard]] double flight_after(std::size_t i) const { return flight_after_[i]; }
  [[nodiscard]] DescentTour& tour() noexcept { return tour_; }
  [[nodiscard]] const DescentTour& tour() const noexcept { return tour_; }

  /// Where the tour of top-level waypoint i's window starts: the window's last top-level
  /// waypoint (DescentSchedule::tour: the survey's last; row: the row's last).
  [[nodiscard]] Eigen::Vector3d tour_start(std::size_t i) const { return top_[window_last_[i]].position; }
  /// Where it ends: the next window's first top-level waypoint (none after the survey's end).
  [[nodiscard]] TourEnd tour_end(std::size_t i) const {
    const std::size_t after = window_last_[i] + 1;
    return after < top_.size() ? TourEnd(top_[after].position) : std::nullopt;
  }
  /// What the tour chosen so far in top-level waypoint i's window adds to the top-level flight
  /// [s] (it replaces the direct leg from its start to its end).
  [[nodiscard]] double tour_extra_s(const TimingModel& timing, std::size_t i) const {
    return tour_.extra_s(timing, tour_start(i), tour_end(i));
  }

  /// What is left after top-level waypoint i's decision without descending: the direct leg to
  /// i + 1, and the flight and images to finish the top level (with the tour chosen so far).
  struct Ahead {
    double direct_s = 0.0;
    double flight_s = 0.0;
    double images = 0.0;
  };
  [[nodiscard]] Ahead ahead(const TimingModel& timing, std::size_t i) const {
    const bool last = i + 1 == top_.size();
    Ahead a;
    a.direct_s = last ? 0.0 : timing.segment_time_s(top_[i].position, top_[i + 1].position);
    a.flight_s = last ? 0.0 : a.direct_s + flight_after_[i + 1];
    a.images = static_cast<double>(top_.size() - i - 1);
    if (defers_) a.flight_s += tour_extra_s(timing, i), a.images += static_cast<double>(tour_.images());
    return a;
  }

  /// What descending at top-level waypoint i into `sub` (non-empty) adds to the flight [s]: at
  /// once, down and back up to the next waypoint instead of the direct leg (`ahead.direct_s`);
  /// or, where the schedule defers, inserted into the window's tour where it adds least, if
  /// that is less. At the window's last top-level waypoint, where a tour already chosen
  /// starts, flying it at once is the insertion at the tour's head, so the tour prices it (the
  /// at-once cost would ignore that the tour then starts from the descent's end).
  struct Priced {
    double flight_s = 0.0;
    TourStop stop;
    TourInsertion insertion;  ///< where it goes into the tour (deferred only)
    bool deferred = false;
  };
  [[nodiscard]] Priced price(const TimingModel& timing, std::size_t i, const std::vector<Waypoint>& sub,
                             const Ahead& ahead) const {
    const bool last = i + 1 == top_.size();
    const double inner = flight_along(timing, sub);
    Priced p;
    p.flight_s = timing.segment_time_s(top_[i].position, sub.front().position) + inner - ahead.direct_s;
    if (!last) p.flight_s += timing.segment_time_s(sub.back().position, top_[i + 1].position);
    p.stop = TourStop{sub.front().position, sub.back().position, inner};
    if (defers_) {
      p.insertion = cheapest_insertion(timing, tour_start(i), tour_.stops(), tour_.order(), p.stop, tour_end(i));
      p.deferred = (i == window_last_[i] && !tour_.empty()) || p.insertion.added_s < p.flight_s;
      if (p.deferred) p.flight_s = p.insertion.added_s;
    }
    return p;
  }

  /// What follows the descent in progress `current` (next top-level waypoint `top_next` to hand
  /// out): the rest of the tour being flown (none for a descent flown at once) and its end, then
  /// the top level from there on, its flight and images.
  struct AfterDescent {
    std::vector<std::size_t> order;  ///< the tour's stops still to fly, in order
    TourEnd end;                     ///< where they lead
    double flight_s = 0.0;           ///< the top level's flight from there on (and the tour chosen so far)
    double images = 0.0;             ///< the images of the tour's rest and the top level's
  };
  [[nodiscard]] AfterDescent after_descent(const TimingModel& timing, const ChosenDescent& current,
                                           std::size_t top_next) const {
    AfterDescent a;
    std::size_t next_top = current.top_index + 1;
    if (current.deferred) {
      a.order = tour_.order_left();
      a.images = tour_.images_left();
      const std::size_t window_last = top_next - 1;
      a.end = tour_end(window_last);
      next_top = window_last + 1;
    } else {
      if (next_top < top_.size()) a.end = top_[next_top].position;
      if (defers_)
        a.flight_s += tour_extra_s(timing, current.top_index), a.images += static_cast<double>(tour_.images());
    }
    if (next_top < top_.size()) a.flight_s += flight_after_[next_top];
    a.images += static_cast<double>(top_.size() - std::min(next_top, top_.size()));
    return a;
  }

 private:
  std::vector<Waypoint> top_;
  /// Per top-level waypoint, the last top-level waypoint of its window: where the window's tour
  /// starts (DescentScheduleInfo::window_last).
  std::vector<std::size_t> window_last_;
  std::vector<double> flight_after_;  ///< flight time of the top-level plan from waypoint i on [s]
  bool defers_ = false;
  DescentTour tour_;  ///< the tour of the window being flown
};

}  // namespace adaptseg::detail
