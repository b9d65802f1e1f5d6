#pragma once
/// @file
/// A survey split into sorties that each fit a flight-time (battery) limit: every sortie takes
/// off at home, flies its run of the path, and comes back, and the next resumes where it
/// stopped. CMake target adaptseg::geo (it writes one mission file per sortie).
///
/// @code
/// const adaptseg::TimingModel timing;
/// const auto sorties = adaptseg::split_into_sorties(path, Eigen::Vector3d::Zero(), timing, 1.0, 15 * 60.0);
/// // sorties[k].first .. sorties[k].end - 1: the waypoints of mission-(k+1).plan
/// @endcode

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/timing.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

/// One flight of a split survey: waypoints [first, end) of the path.
struct Sortie {
  std::size_t first = 0;  ///< index of its first waypoint (where it resumes the survey)
  std::size_t end = 0;    ///< one past its last waypoint
  double flight_s = 0.0;  ///< its flight time from home and back [s] (sortie_flight_s)

  [[nodiscard]] std::size_t size() const noexcept { return end - first; }
  friend bool operator==(const Sortie&, const Sortie&) = default;
};

namespace detail {

/// The return from `last` to `home`: level at the last waypoint's altitude to above home, then
/// straight down (the autopilot's RTL climbs or descends to its own return altitude first, which
/// the plan cannot know; see sortie_flight_s).
inline double return_time_s(const TimingModel& timing, const Eigen::Vector3d& last, const Eigen::Vector3d& home) {
  const Eigen::Vector3d above_home(home.x(), home.y(), last.z());
  return timing.segment_time_s(last, above_home) + timing.segment_time_s(above_home, home);
}

/// The take-off at `home` straight up to the first waypoint's altitude, then level to it.
inline double takeoff_time_s(const TimingModel& timing, const Eigen::Vector3d& home, const Eigen::Vector3d& first) {
  const Eigen::Vector3d above_home(home.x(), home.y(), first.z());
  return timing.segment_time_s(home, above_home) + timing.segment_time_s(above_home, first);
}

}  // namespace detail

/// The flight time [s] of one sortie over `path` (non-empty) from `home` (a frame position [m],
/// z the take-off ground, 0 for a path whose altitudes are relative to home) and back, under
/// `timing`: straight up to the first waypoint's altitude and level to it (the mission's
/// NAV_TAKEOFF), every leg between waypoints, `hold_s` at each waypoint, then level to above
/// home at the last waypoint's altitude and straight down. The return is modelled at the last
/// waypoint's altitude: an autopilot's RTL first climbs (or descends) to its return altitude
/// (PX4 RTL_RETURN_ALT, ArduPilot RTL_ALT), which adds |RTL altitude - last altitude| at the
/// vertical speed; leave a reserve for it, for wind, and for the landing.
/// @throws std::invalid_argument for an empty path, a negative hold, or as TimingModel.
[[nodiscard]] inline double sortie_flight_s(std::span<const Waypoint> path, const Eigen::Vector3d& home,
                                            const TimingModel& timing, double hold_s) {
  detail::require(!path.empty(), "sortie_flight_s: the sortie has no waypoint; waypoints", path.size());
  detail::require(std::isfinite(hold_s) && hold_s >= 0.0, "sortie_flight_s: hold_s must be finite and >= 0", hold_s);
  double t = detail::takeoff_time_s(timing, home, path.front().position) + hold_s * static_cast<double>(path.size());
  for (std::size_t k = 1; k < path.size(); ++k) t += timing.segment_time_s(path[k - 1].position, path[k].position);
  return t + detail::return_time_s(timing, path.back().position, home);
}

/// Waypoints 0 .. n-1 split, in their order, into sorties whose flight time is at most
/// `max_flight_s` each, the times given by the caller (what a route inside a geofence needs):
/// `outbound_s(i)` from the take-off to waypoint i, its hold included; `leg_s(i)` from waypoint
/// i - 1 to waypoint i, i's hold included; `return_s(i)` from waypoint i back home and down.
/// Each sortie takes as many waypoints as still fit (greedy: the fewest sorties for waypoints
/// flown in order, when a sortie's time only grows with each waypoint it takes). Without a
/// limit, one sortie.
/// @throws std::invalid_argument for a limit that is not finite and positive, or a waypoint
///         that alone, from home and back, takes longer than the limit (naming it and both times).
template <typename Outbound, typename Leg, typename Return>
[[nodiscard]] std::vector<Sortie> split_into_sorties(std::size_t n, std::optional<double> max_flight_s,
                                                     Outbound&& outbound_s, Leg&& leg_s, Return&& return_s) {
  if (n == 0) return {};
  if (!max_flight_s) {
    double t = outbound_s(std::size_t{0});
    for (std::size_t i = 1; i < n; ++i) t += leg_s(i);
    return {Sortie{0, n, t + return_s(n - 1)}};
  }
  detail::require_positive(*max_flight_s, "split_into_sorties: max_flight_s");
  std::vector<Sortie> out;
  std::size_t first = 0;
  while (first < n) {
    double outbound = outbound_s(first);  // without the return
    double flight = outbound + return_s(first);
    if (flight > *max_flight_s)
      throw std::invalid_argument("split_into_sorties: waypoint " + std::to_string(first) + " alone takes " +
                                  std::to_string(static_cast<long long>(std::ceil(flight))) +
                                  " s from home and back, more than max_flight_s " +
                                  std::to_string(static_cast<long long>(std::floor(*max_flight_s))) +
                                  " s: take off nearer the site or fly longer sorties");
    std::size_t end = first + 1;
    for (; end < n; ++end) {
      const double next_outbound = outbound + leg_s(end);
      const double next_flight = next_outbound + return_s(end);
      if (next_flight > *max_flight_s) break;
      outbound = next_outbound;
      flight = next_flight;
    }
    out.push_back({first, end, flight});
    first = end;
  }
  return out;
}

/// `path` split, in its order, into sorties from `home` and back, straight legs flown under
/// `timing` with `hold_s` at each waypoint, each sortie's time (sortie_flight_s) at most
/// `max_flight_s`; the greedy split above.
/// @throws std::invalid_argument as the split above, or for a negative hold.
[[nodiscard]] inline std::vector<Sortie> split_into_sorties(std::span<const Waypoint> path, const Eigen::Vector3d& home,
                                                            const TimingModel& timing, double hold_s,
                                                            std::optional<double> max_flight_s = std::nullopt) {
  detail::require(std::isfinite(hold_s) && hold_s >= 0.0, "split_into_sorties: hold_s must be finite and >= 0", hold_s);
  return split_into_sorties(
      path.size(), max_flight_s,
      [&](std::size_t i) { return detail::takeoff_time_s(timing, home, path[i].position) + hold_s; },
      [&](std::size_t i) { return timing.segment_time_s(path[i - 1].position, path[i].position) + hold_s; },
      [&](std::size_t i) { return detail::return_time_s(timing, path[i].position, home); });
}

}  // namespace adaptseg
