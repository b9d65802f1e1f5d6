#pragma once
/// @file
/// The adaptive planner (paper §3.2, Fig. workflow): fly the top-level lawnmower at h_max,
/// segment each image, ask a DecisionPolicy whether to re-map the region from a lower
/// altitude, insert that sub-lawnmower before the next top-level waypoint, fuse, and feed the
/// outcome back to the policy. Optionally never exceeds a mission-time budget.

#include <adaptseg/decision.hpp>
#include <adaptseg/lawnmower_planner.hpp>
#include <adaptseg/metrics.hpp>
#include <adaptseg/mission.hpp>

#include <algorithm>
#include <chrono>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg {

/// Settings of an adaptive mission.
struct AdaptiveOptions {
  MissionOptions mission{};
  double top_gsd_cm = 3.0;                ///< GSD at h_max [cm/px]
  std::vector<double> candidate_gsd_cm{}; ///< lower GSDs a sub-lawnmower may fly [cm/px]
  /// Mission-time budget [s] (flight + segmentation + planning). The planner only descends
  /// when the descent and the rest of the top-level coverage still fit. Exact with fixed
  /// segmentation and planning times; with measured times the remaining work is estimated
  /// from the slowest image so far plus 25 %.
  std::optional<double> budget_s{};
};

/// The decision taken at one top-level waypoint.
struct DecisionRecord {
  std::size_t waypoint_index = 0;  ///< index into MissionResult::waypoints
  double sigma = 0.0;              ///< σ of the top-level image
  Decision decision;
  std::vector<Candidate> candidates;  ///< what was affordable, with exact costs
  std::optional<DescentOutcome> outcome;  ///< after a descent
  bool budget_limited = false;     ///< some candidate was dropped because of the budget
};

/// An adaptive mission's result: the mission plus every decision.
struct AdaptiveResult {
  MissionResult mission;
  std::vector<DecisionRecord> decisions;
  [[nodiscard]] int descents() const {
    return static_cast<int>(std::count_if(decisions.begin(), decisions.end(),
                                           [](const DecisionRecord& d) { return d.decision.descend; }));
  }
};

namespace detail {

/// σ of the map's labels inside `rect` (pixels never observed left out).
inline double map_sigma(const SemanticMap& map, const cv::Rect& rect, const std::vector<int>& interest) {
  const cv::Rect in = rect & cv::Rect(0, 0, map.labels().cols, map.labels().rows);
  if (in.area() == 0) return 0.0;
  return semantic_ratio(map.labels()(in), interest, map.unknown_label());
}

/// A fixed-altitude lawnmower over the whole field, as a front-aware policy sees it.
struct LawnmowerPlanCost {
  double gsd_cm = 0.0;
  double flight_s = 0.0;  ///< velocity-ramp flight time along the plan
  std::size_t images = 0;
};

}  // namespace detail

/// Runs the adaptive strategy with `policy` over `field`.
///
/// At top-level waypoint i (GSD `top_gsd_cm`): segment, σ from the segmentation; for each
/// candidate GSD finer than the top and not finer than the field, plan the sub-lawnmower over
/// the region (starting in the corner nearest the UAV, cells without valid pixels skipped)
/// and compute its exact extra time: the flight i → sub-lawnmower → i+1 minus the flight
/// i → i+1, plus the per-image segmentation and per-waypoint planning estimates. Candidates
/// that would break the budget are dropped. The policy decides; after a descent the region's
/// σ at h' (from the fused map) goes back to the policy.
///
/// Holds references to `backend` and `policy` for the call's duration only.
/// @throws std::invalid_argument for a top GSD finer than the field's, candidates that are not
///         finer than the top, and a budget too small for the top-level coverage alone.
template <SegmentationBackend Backend, DecisionPolicy Policy>
[[nodiscard]] AdaptiveResult run_adaptive_mission(const Field& field, Backend& backend, Policy& policy,
                                                  const AdaptiveOptions& options, std::string strategy) {
  detail::require(std::isfinite(options.top_gsd_cm) && options.top_gsd_cm >= field.gsd_cm() * (1.0 - 1e-9),
                  "run_adaptive_mission: top_gsd_cm must not be finer than the field's " +
                      std::to_string(field.gsd_cm()) + " cm/px",
                  options.top_gsd_cm);
  std::vector<double> candidates;
  for (double g : options.candidate_gsd_cm) {
    detail::require(std::isfinite(g) && g > 0.0 && g < options.top_gsd_cm,
                    "run_adaptive_mission: candidate GSDs must be positive and finer than top_gsd_cm", g);
    if (g >= field.gsd_cm() * (1.0 - 1e-9)) candidates.push_back(g);  // finer than the data: skip
  }
  if (options.budget_s)
    detail::require(std::isfinite(*options.budget_s) && *options.budget_s > 0.0,
                    "run_adaptive_mission: budget_s must be finite and > 0", *options.budget_s);

  Mission<Backend> mission(field, backend, options.mission, std::move(strategy));
  const MissionOptions& mo = mission.options();
  const LawnmowerPlanner planner(mission.camera());
  const auto keep = [&](const Area& a) { return field.has_valid(a); };
  const auto t_plan = std::chrono::steady_clock::now();
  const auto top = planner.plan(field.area(), options.top_gsd_cm, {0.0, 0.0}, keep);
  double pending_planning = 0.0;  // charged at the first waypoint (set below)

  // Estimates of the per-image cost of work not yet done.
  double slowest_segmentation = 0.0;
  const auto seg_estimate = [&] {
    return mo.fixed_segmentation_time_s ? *mo.fixed_segmentation_time_s : 1.25 * slowest_segmentation;
  };
  const auto plan_estimate = [&] { return mo.fixed_planning_time_s.value_or(0.0); };
  const TimingModel& timing = mission.timing();
  // Flight time of the top-level plan from waypoint i on.
  std::vector<double> flight_after(top.size() + 1, 0.0);
  for (std::size_t i = top.size(); i-- > 1;)
    flight_after[i - 1] = flight_after[i] + timing.segment_time_s(top[i - 1].position, top[i].position);

  if (options.budget_s) {
    const double coverage = flight_after[0] + static_cast<double>(top.size()) * (seg_estimate() + plan_estimate());
    detail::require(coverage <= *options.budget_s,
                    "run_adaptive_mission: budget_s [s] is too small for the top-level coverage, which needs " +
                        std::to_string(coverage) + " s",
                    *options.budget_s);
  }

  // The field's lawnmowers at the top and candidate GSDs (what the mission could fly instead),
  // planned exactly as run_lawnmower_mission plans them; their times use the current per-image
  // estimates at each decision.
  std::vector<detail::LawnmowerPlanCost> lawnmowers;
  for (double g : candidates) lawnmowers.push_back({g, 0.0, 0});
  lawnmowers.push_back({options.top_gsd_cm, 0.0, 0});
  for (auto& l : lawnmowers) {
    const auto plan = planner.plan(field.area(), l.gsd_cm, {0.0, 0.0}, keep);
    for (std::size_t k = 1; k < plan.size(); ++k) l.flight_s += timing.segment_time_s(plan[k - 1].position, plan[k].position);
    l.images = plan.size();
  }
  const double field_valid_px = static_cast<double>(field.valid_pixels());
  pending_planning = Mission<Backend>::seconds_since(t_plan);  // the top plan and the forecasts

  std::vector<DecisionRecord> decisions;
  std::vector<LawnmowerForecast> forecasts(lawnmowers.size());
  for (std::size_t i = 0; i < top.size(); ++i) {
    mission.charge_planning(pending_planning);
    const auto visit = mission.visit(top[i], 0);
    slowest_segmentation = std::max(slowest_segmentation, visit.record->segmentation_s);
    const auto t0 = std::chrono::steady_clock::now();

    DecisionRecord rec;
    rec.waypoint_index = mission.records().size() - 1;
    rec.sigma = visit.record->semantic_ratio;
    const Eigen::Vector3d here = top[i].position;
    const bool last = i + 1 == top.size();
    const double direct = last ? 0.0 : timing.segment_time_s(here, top[i + 1].position);
    // Time still needed after this waypoint's decision to finish the top-level coverage.
    const double rest = (last ? 0.0 : direct + flight_after[i + 1]) +
                        static_cast<double>(top.size() - i - 1) * (seg_estimate() + plan_estimate());
    std::vector<std::vector<Waypoint>> sub_plans;
    for (double g : candidates) {
      auto sub = planner.plan(top[i].footprint, g, Eigen::Vector2d(here.x(), here.y()), keep);
      if (sub.empty()) continue;
      double flight = timing.segment_time_s(here, sub.front().position);
      for (std::size_t k = 1; k < sub.size(); ++k) flight += timing.segment_time_s(sub[k - 1].position, sub[k].position);
      if (!last) flight += timing.segment_time_s(sub.back().position, top[i + 1].position);
      Candidate c;
      c.gsd_cm = g;
      c.altitude_m = mission.camera().altitude_m(g);
      c.images = static_cast<int>(sub.size());
      c.extra_time_s = flight - direct + static_cast<double>(sub.size()) * (seg_estimate() + plan_estimate());
      // Descending replaces the direct leg to i+1: elapsed + extra + rest must fit.
      if (options.budget_s && mission.elapsed_s() + c.extra_time_s + rest > *options.budget_s + 1e-9) {
        rec.budget_limited = true;
        continue;
      }
      rec.candidates.push_back(c);
      sub_plans.push_back(std::move(sub));
    }
    const double region_px = static_cast<double>(field.valid_pixels(top[i].footprint));
    for (std::size_t k = 0; k < lawnmowers.size(); ++k)
      forecasts[k] = {lawnmowers[k].gsd_cm, lawnmowers[k].flight_s + static_cast<double>(lawnmowers[k].images) *
                                                                         (seg_estimate() + plan_estimate())};
    DecisionContext ctx;
    ctx.sigma = rec.sigma;
    ctx.valid_fraction = region_px / static_cast<double>(std::max(1, field.pixel_rect(top[i].footprint).area()));
    ctx.top_gsd_cm = options.top_gsd_cm;
    ctx.top_altitude_m = here.z();
    ctx.candidates = rec.candidates;
    ctx.elapsed_s = mission.elapsed_s();
    ctx.rest_s = rest;
    ctx.region_share = field_valid_px > 0.0 ? region_px / field_valid_px : 0.0;
    ctx.lawnmowers = forecasts;
    rec.decision = policy.decide(ctx);
    pending_planning = Mission<Backend>::seconds_since(t0);

    if (rec.decision.descend) {
      const auto it = std::find_if(rec.candidates.begin(), rec.candidates.end(),
                                   [&](const Candidate& c) { return c.gsd_cm == rec.decision.gsd_cm; });
      ADAPTSEG_ASSERT(it != rec.candidates.end());
      const auto& sub = sub_plans[static_cast<std::size_t>(it - rec.candidates.begin())];
      for (const auto& w : sub) {
        mission.charge_planning(pending_planning);
        pending_planning = 0.0;
        const auto v = mission.visit(w, 1);
        slowest_segmentation = std::max(slowest_segmentation, v.record->segmentation_s);
      }
      const auto t1 = std::chrono::steady_clock::now();
      DescentOutcome out;
      out.top_altitude_m = here.z();
      out.sub_altitude_m = it->altitude_m;
      out.sigma_top = rec.sigma;
      out.sigma_sub = detail::map_sigma(mission.map(), field.pixel_rect(top[i].footprint), mission.interest());
      policy.observe(out);
      rec.outcome = out;
      pending_planning += Mission<Backend>::seconds_since(t1);
    }
    decisions.push_back(std::move(rec));
  }
  // The last decision's measured time (a fixed planning time is charged per waypoint only).
  if (!mo.fixed_planning_time_s) mission.charge_planning(pending_planning);
  return AdaptiveResult{std::move(mission).finish(), std::move(decisions)};
}

}  // namespace adaptseg
