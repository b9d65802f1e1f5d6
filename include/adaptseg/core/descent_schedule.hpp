#pragma once
/// @file
/// When the chosen descents are flown (DescentSchedule, an AdaptiveOptions setting), one place
/// per schedule: its name and the windows it cuts the top-level lawnmower into
/// (DescentScheduleInfo). The adaptive planner asks a schedule's row, never the schedule's name;
/// a new schedule is a new row of kDescentSchedules.

#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>

#include <array>
#include <cmath>
#include <cstddef>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

/// When the chosen descents are flown.
enum class DescentSchedule {
  /// At once (the paper): down from the region's top-level waypoint, the sub-lawnmower, back up
  /// to the next top-level waypoint: two altitude changes per descent (one for the last region's).
  immediate,
  /// Inspect at once or after the survey, whichever is cheaper (beyond the paper): each region
  /// is decided as it is seen; a chosen descent is flown at once if that adds less time, else
  /// deferred to a tour flown after the whole top-level lawnmower, every deferred sub-lawnmower
  /// back to back at low altitude in the order that takes least time (inspection_tour.hpp: one
  /// descent for all of them, no climb back). A deferred descent is charged what it adds to the
  /// tour chosen so far (cheapest insertion); the tour is reordered once the survey is flown,
  /// never longer, so the budget holds. Candidate::deferred says which way each was costed.
  tour,
  /// Inspect at once or after the lawnmower row, whichever is cheaper (beyond the paper: stay
  /// low between neighbouring regions): as `tour`, but a tour is flown after each row of the
  /// top-level lawnmower (rows run along x), from the row's last top-level waypoint through the
  /// row's deferred sub-lawnmowers, back to back at low altitude, up to the next row's first
  /// top-level waypoint. Regions of one row that all want a descent share one descent and one
  /// climb, without the flight back from the survey's end that `tour` needs; each is still
  /// decided on its own top-level image. A deferred descent is charged what it adds to the row's
  /// tour, its leg up to the next row included.
  row,
};

/// A schedule as the adaptive planner uses it. The planner cuts its top-level lawnmower into
/// windows of consecutive waypoints; a descent chosen in a window is flown at once, or (where
/// the schedule `defers`) deferred to the window's tour, flown after the window's last
/// top-level waypoint and ending at the next window's first, whichever adds less time.
struct DescentScheduleInfo {
  DescentSchedule schedule;
  const char* name;         ///< in results, model files and on the command line
  const char* description;  ///< when its descents are flown, in words (a program's banner)
  bool defers;              ///< a descent may be deferred to its window's tour
  /// Per waypoint i of the top-level lawnmower `top` (in flight order), the index of the last
  /// waypoint of i's window (>= i, and the same for every waypoint of one window).
  std::vector<std::size_t> (*window_last)(std::span<const Waypoint> top);
};

/// Every schedule, one row each.
inline constexpr std::array<DescentScheduleInfo, 3> kDescentSchedules{{
    {DescentSchedule::immediate, "immediate", "at once", false,
     [](std::span<const Waypoint> top) {
       std::vector<std::size_t> last(top.size());
       for (std::size_t i = 0; i < top.size(); ++i) last[i] = i;  // a window per waypoint
       return last;
     }},
    {DescentSchedule::tour, "tour", "at once or toured after the survey", true,
     [](std::span<const Waypoint> top) { return std::vector<std::size_t>(top.size(), top.size() - 1); }},
    {DescentSchedule::row, "row", "at once or toured after each row", true,
     [](std::span<const Waypoint> top) {
       // A row ends where the next waypoint lies on another y (rows run along x).
       std::vector<std::size_t> last(top.size());
       for (std::size_t i = top.size(); i-- > 0;) {
         const bool row_ends = i + 1 == top.size() || std::abs(top[i + 1].position.y() - top[i].position.y()) > 1e-6;
         last[i] = row_ends ? i : last[i + 1];
       }
       return last;
     }},
}};

/// The row of schedule `s`.
[[nodiscard]] inline const DescentScheduleInfo& descent_schedule_info(DescentSchedule s) {
  return detail::row_of(kDescentSchedules, &DescentScheduleInfo::schedule, s, "descent schedule");
}

/// The names before adaptseg 0.3 ("rule" now means a decision rule only); kept until 0.4.
using DescentScheduleRule [[deprecated("renamed adaptseg::DescentScheduleInfo in adaptseg 0.3")]] = DescentScheduleInfo;
[[deprecated("renamed adaptseg::descent_schedule_info in adaptseg 0.3")]] inline const DescentScheduleInfo&
descent_schedule_rule(DescentSchedule s) {
  return descent_schedule_info(s);
}

/// The name used in results and on the command line: "immediate", "tour" or "row".
[[nodiscard]] inline const char* to_string(DescentSchedule s) { return descent_schedule_info(s).name; }

/// Parses a schedule's name.
/// @throws std::invalid_argument for anything else.
[[nodiscard]] inline DescentSchedule parse_descent_schedule(const std::string& s) {
  return detail::row_named(kDescentSchedules, s, "descent schedule").schedule;
}

}  // namespace adaptseg
