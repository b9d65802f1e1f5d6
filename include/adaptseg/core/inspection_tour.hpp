#pragma once
/// @file
/// Ordering inspections into one tour (beyond the paper; docs/method.md, "When descents are
/// flown"): once the top-level lawnmower (or one of its rows) is flown, the sub-lawnmowers it
/// chose are flown back to back at low altitude, in the order that takes least flight time. Each
/// inspection is flown as planned (its own waypoint order), so it enters at its first
/// waypoint and leaves at its last: the tour is an open path from a fixed start through
/// directed stops, an asymmetric travelling-salesman path. A tour may also have a fixed end
/// (`end`, e.g. the next lawnmower row's first top-level waypoint for a tour flown after each
/// row): the leg from its last stop's exit to that point is then part of its time.
///
/// Each stop is priced as it is chosen by cheapest insertion into the tour so far. Once every
/// stop is known, `plan_tour_order` orders them: exactly (Held-Karp dynamic programme) up to
/// `kExactTourStops` stops, beyond that by local search from the insertion order: 2-opt (reverse
/// a stretch of the order) and or-opt (move a run of 1-3 stops), a move taken only when it
/// shortens the tour, until none does. Either way the tour is never longer than the insertion
/// order, which is what lets the planner charge a decision its insertion cost and keep its
/// budget. Tests check the optimum against every permutation and measure the local search's gap
/// to it.

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/timing.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cstddef>
#include <limits>
#include <numeric>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace adaptseg {

/// A stretch flown as one unit of a tour: it is entered at `entry`, left at `exit`, and
/// flying it takes `inner_flight_s` [s] (its own legs, the same in any tour).
struct TourStop {
  Eigen::Vector3d entry = Eigen::Vector3d::Zero();
  Eigen::Vector3d exit = Eigen::Vector3d::Zero();
  double inner_flight_s = 0.0;
};

/// Where a tour must end, if anywhere (nullopt: at its last stop's exit).
using TourEnd = std::optional<Eigen::Vector3d>;

/// Flight time [s] of the tour from `start` through `stops` in `order` (indices into
/// `stops`), each stop's inner flight included; it ends at the last stop's exit, or flies on
/// to `end` if one is given (with no stop: start to end).
/// @throws std::invalid_argument for an index out of range.
[[nodiscard]] inline double tour_flight_s(const TimingModel& timing, const Eigen::Vector3d& start,
                                          std::span<const TourStop> stops, std::span<const std::size_t> order,
                                          const TourEnd& end = std::nullopt) {
  double t = 0.0;
  Eigen::Vector3d at = start;
  for (std::size_t k : order) {
    detail::require(k < stops.size(), "tour_flight_s: a stop index is out of range", k);
    t += timing.segment_time_s(at, stops[k].entry) + stops[k].inner_flight_s;
    at = stops[k].exit;
  }
  if (end) t += timing.segment_time_s(at, *end);
  return t;
}

/// Where a stop would go in a tour and what it would add.
struct TourInsertion {
  std::size_t position = 0;  ///< insert before order[position] (order.size(): at the end)
  double added_s = 0.0;      ///< flight time it adds [s], its inner flight included
};

/// The cheapest place for `stop` in the tour from `start` through `stops` in `order` (to
/// `end`, if given).
/// @throws std::invalid_argument for an index out of range.
[[nodiscard]] inline TourInsertion cheapest_insertion(const TimingModel& timing, const Eigen::Vector3d& start,
                                                      std::span<const TourStop> stops,
                                                      std::span<const std::size_t> order, const TourStop& stop,
                                                      const TourEnd& end = std::nullopt) {
  TourInsertion best{0, std::numeric_limits<double>::infinity()};
  Eigen::Vector3d before = start;
  for (std::size_t p = 0; p <= order.size(); ++p) {
    double added = timing.segment_time_s(before, stop.entry) + stop.inner_flight_s;
    if (p < order.size()) {
      detail::require(order[p] < stops.size(), "cheapest_insertion: a stop index is out of range", order[p]);
      const TourStop& next = stops[order[p]];
      added += timing.segment_time_s(stop.exit, next.entry) - timing.segment_time_s(before, next.entry);
      before = next.exit;
    } else if (end) {
      added += timing.segment_time_s(stop.exit, *end) - timing.segment_time_s(before, *end);
    }
    if (added < best.added_s) best = {p, added};
  }
  return best;
}

/// `order` improved by 2-opt and or-opt (runs of 1-3 stops) moves, each taken only if it
/// shortens the tour (to `end`, if given) by more than a microsecond, until none does (or
/// after `max_passes` passes); never longer than `order`. O(n³) per pass; meant for the tens
/// of inspections of one mission.
/// @throws std::invalid_argument for an index out of range.
[[nodiscard]] inline std::vector<std::size_t> improve_tour_order(
    const TimingModel& timing, const Eigen::Vector3d& start, std::span<const TourStop> stops,
    std::vector<std::size_t> order, const TourEnd& end = std::nullopt, int max_passes = 100) {
  const auto cost = [&](const std::vector<std::size_t>& o) { return tour_flight_s(timing, start, stops, o, end); };
  double best = cost(order);
  const std::size_t n = order.size();
  for (int pass = 0; pass < max_passes; ++pass) {
    bool improved = false;
    // 2-opt: reverse order[i..j].
    for (std::size_t i = 0; i + 1 < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) {
        std::vector<std::size_t> o = order;
        std::reverse(o.begin() + static_cast<std::ptrdiff_t>(i), o.begin() + static_cast<std::ptrdiff_t>(j) + 1);
        if (const double c = cost(o); c < best - 1e-6) best = c, order = std::move(o), improved = true;
      }
    // or-opt: move the run of `len` stops at i to position j of what is left.
    for (std::size_t len = 1; len <= 3 && len < n; ++len)
      for (std::size_t i = 0; i + len <= n; ++i)
        for (std::size_t j = 0; j + len <= n; ++j) {
          if (i == j) continue;
          std::vector<std::size_t> o = order;
          const auto first = o.begin() + static_cast<std::ptrdiff_t>(i);
          const std::vector<std::size_t> run(first, first + static_cast<std::ptrdiff_t>(len));
          o.erase(first, first + static_cast<std::ptrdiff_t>(len));
          o.insert(o.begin() + static_cast<std::ptrdiff_t>(j), run.begin(), run.end());
          if (const double c = cost(o); c < best - 1e-6) best = c, order = std::move(o), improved = true;
        }
    if (!improved) break;
  }
  return order;
}

/// Up to this many stops plan_tour_order finds the optimum (2^12 · 12² steps at most).
inline constexpr std::size_t kExactTourStops = 12;

/// The order of least flight time (Held-Karp: for every set of stops and every last stop, the
/// fastest way from `start` through that set ending there; with an `end`, the leg from the
/// last stop to it added). O(2^n · n²) time, O(2^n · n) memory.
/// @throws std::invalid_argument for more than kExactTourStops stops.
[[nodiscard]] inline std::vector<std::size_t> optimal_tour_order(const TimingModel& timing,
                                                                 const Eigen::Vector3d& start,
                                                                 std::span<const TourStop> stops,
                                                                 const TourEnd& end = std::nullopt) {
  const std::size_t n = stops.size();
  detail::require(n <= kExactTourStops,
                  "optimal_tour_order: at most " + std::to_string(kExactTourStops) + " stops (exact search)", n);
  if (n == 0) return {};
  const std::size_t sets = std::size_t{1} << n;
  const double inf = std::numeric_limits<double>::infinity();
  std::vector<double> best(sets * n, inf);  // best[set * n + last]
  std::vector<std::size_t> previous(sets * n, n);
  for (std::size_t k = 0; k < n; ++k)
    best[(std::size_t{1} << k) * n + k] = timing.segment_time_s(start, stops[k].entry) + stops[k].inner_flight_s;
  for (std::size_t set = 1; set < sets; ++set)
    for (std::size_t last = 0; last < n; ++last) {
      const double here = best[set * n + last];
      if (!(set >> last & 1U) || here == inf) continue;
      for (std::size_t next = 0; next < n; ++next) {
        if (set >> next & 1U) continue;
        const std::size_t grown = set | std::size_t{1} << next;
        const double t = here + timing.segment_time_s(stops[last].exit, stops[next].entry) + stops[next].inner_flight_s;
        if (t < best[grown * n + next]) best[grown * n + next] = t, previous[grown * n + next] = last;
      }
    }
  std::size_t set = sets - 1, last = 0;
  const auto finish = [&](std::size_t k) {
    return best[set * n + k] + (end ? timing.segment_time_s(stops[k].exit, *end) : 0.0);
  };
  for (std::size_t k = 1; k < n; ++k)
    if (finish(k) < finish(last)) last = k;
  std::vector<std::size_t> order;
  while (last < n) {
    order.push_back(last);
    const std::size_t before = previous[set * n + last];
    set &= ~(std::size_t{1} << last);
    last = before;
  }
  std::reverse(order.begin(), order.end());
  return order;
}

/// The order a tour is flown in: optimal_tour_order up to kExactTourStops stops, else `order`
/// improved by improve_tour_order (both to `end`, if given). Never longer than `order` (a
/// permutation of the stops).
/// @throws std::invalid_argument for an index out of range.
[[nodiscard]] inline std::vector<std::size_t> plan_tour_order(const TimingModel& timing, const Eigen::Vector3d& start,
                                                              std::span<const TourStop> stops,
                                                              std::vector<std::size_t> order,
                                                              const TourEnd& end = std::nullopt) {
  if (stops.size() <= kExactTourStops && order.size() == stops.size()) {
    auto exact = optimal_tour_order(timing, start, stops, end);
    if (tour_flight_s(timing, start, stops, exact, end) <= tour_flight_s(timing, start, stops, order, end))
      return exact;
    return order;
  }
  return improve_tour_order(timing, start, stops, std::move(order), end);
}

}  // namespace adaptseg
