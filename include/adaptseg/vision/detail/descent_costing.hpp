#pragma once
/// @file
/// Descent costing of the adaptive planner (adaptive_planner.hpp, paper §3.2.2 "exact extra
/// time"): what each candidate descent of a decision adds to the mission, which of them the
/// budget affords, whether the budget still affords the rest of a descent in progress, and what
/// the policy is told (DecisionContext).

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/inspection_tour.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/detail/descent_options.hpp>
#include <adaptseg/vision/detail/descent_tour.hpp>
#include <adaptseg/vision/detail/planner_clock.hpp>
#include <adaptseg/vision/detail/planner_route.hpp>
#include <adaptseg/vision/detail/survey_grid.hpp>
#include <adaptseg/vision/grid_inputs.hpp>

#include <opencv2/core.hpp>

#include <cstddef>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// A candidate's sub-lawnmower and its stop in the window's tour, beside DecisionRecord::candidates.
struct CostedPlan {
  std::vector<Waypoint> plan;
  TourStop stop;
  TourInsertion insertion;  ///< where it goes into the tour (deferred only)
};

/// What costing reads of the planner: its route (top level, windows, tours), the timing model,
/// the time account, the camera and the budget. Holds references; lives for one call.
struct DescentCosting {
  const PlannerRoute& route;
  const TimingModel& timing;
  const PlannerClock& clock;
  const CameraModel& camera;
  std::optional<double> budget_s;

  /// The decision at top-level waypoint i over `options` (descent_options()): each option's
  /// exact extra time into `rec.candidates`, those the budget affords (`rec.budget_limited`
  /// where it drops one), and their plans in the same order. `ahead`: what is left without
  /// descending.
  std::vector<CostedPlan> cost(std::vector<DescentOption> options, std::size_t i, const PlannerRoute::Ahead& ahead,
                               DecisionRecord& rec) const {
    const double per_image = clock.per_image_estimate();
    // The budget reserves a bound of each step's processing instead of the estimate, and, where
    // times are measured, one for what is left of this step (this decision, not yet charged).
    const double bound = clock.step_bound();
    const double reserved = ahead.flight_s + ahead.images * bound + clock.this_step_reserve();
    const double elapsed = clock.elapsed_s();
    std::vector<CostedPlan> plans;
    for (DescentOption& option : options) {
      std::vector<Waypoint>& sub = option.plan;
      if (sub.empty()) continue;
      const PlannerRoute::Priced priced = route.price(timing, i, sub, ahead);
      Candidate c;
      c.deferred = priced.deferred;
      c.gsd_cm = option.gsd_cm;
      c.altitude_m = camera.altitude_m(option.gsd_cm);
      c.images = static_cast<int>(sub.size());
      c.extra_time_s = priced.flight_s + static_cast<double>(sub.size()) * per_image;
      c.cells = std::move(option.cells);
      // Descending replaces the direct leg to i+1: elapsed + extra + rest must fit, each image
      // reserved at the bound.
      if (budget_s &&
          elapsed + priced.flight_s + static_cast<double>(sub.size()) * bound + reserved > *budget_s + 1e-9) {
        rec.budget_limited = true;
        continue;
      }
      rec.candidates.push_back(c);
      plans.push_back({std::move(sub), priced.stop, priced.insertion});
    }
    return plans;
  }

  /// Whether the budget still affords the rest of the descent in progress `current` (its
  /// waypoints `sub`, the next to hand out `sub_next` >= 1; the next top-level waypoint
  /// `top_next`), from the image just reported: its remaining images and flight, then what
  /// follows it (the next top-level waypoint, or the rest of the tour being flown) and the rest of
  /// the mission, every image at the step bound. Cutting it here flies straight on to what follows.
  [[nodiscard]] bool rest_fits(const std::vector<Waypoint>& sub, std::size_t sub_next, const ChosenDescent& current,
                               std::size_t top_next) const {
    const double bound = clock.step_bound();
    double inner = 0.0;  // from the image just reported through the descent's remaining waypoints
    for (std::size_t k = sub_next; k < sub.size(); ++k)
      inner += timing.segment_time_s(sub[k - 1].position, sub[k].position);
    const double more_images = static_cast<double>(sub.size() - sub_next);
    // What follows: the rest of the tour being flown (none for a descent flown at once), its end,
    // and the top level from there on.
    const PlannerRoute::AfterDescent after = route.after_descent(timing, current, top_next);
    const double go_on =
        inner + tour_flight_s(timing, sub.back().position, route.tour().stops(), after.order, after.end);
    const double mission_rest = after.flight_s + (more_images + after.images) * bound + clock.this_step_reserve();
    return clock.elapsed_s() + go_on + mission_rest <= *budget_s + 1e-9;
  }
};

/// The top-level waypoint a decision is taken at, as decision_context() reads it.
struct DecisionInputsAt {
  const Waypoint& top;       ///< the top-level waypoint
  cv::Rect region;           ///< its region on the map grid
  const GridInputs* inputs;  ///< the region's decision inputs (ranked cells), or none
  DecisionInput cell_input;  ///< the input the cells are ranked by
  bool entropy;              ///< whether the policy reads the region's entropy
};

/// What the policy decides on at a top-level waypoint (DecisionContext): `rec`'s σ and
/// candidates, the mission so far (`elapsed_s`) and `rest_s` ahead, the region's share of the
/// field (`grid`, `at`) and, with ranked cells, its inputs, at the top level `top_gsd_cm`;
/// `lawnmowers` must outlive its use.
[[nodiscard]] inline DecisionContext decision_context(const SurveyGrid& grid, const DecisionInputsAt& at,
                                                      double top_gsd_cm, const DecisionRecord& rec, double elapsed_s,
                                                      double rest_s, std::span<const LawnmowerForecast> lawnmowers) {
  DecisionContext ctx;
  ctx.sigma = rec.sigma;
  ctx.valid_fraction = grid.valid_fraction(at.top.footprint);
  ctx.top_gsd_cm = top_gsd_cm;
  ctx.top_altitude_m = at.top.position.z();
  ctx.candidates = rec.candidates;
  ctx.elapsed_s = elapsed_s;
  ctx.rest_s = rest_s;
  ctx.region_share =
      grid.valid_px() > 0 ? static_cast<double>(grid.valid_pixels(at.top.footprint)) / grid.valid_px() : 0.0;
  ctx.region_px = static_cast<double>(grid.valid_pixels(at.top.footprint));
  if (at.inputs) {
    const CellInputs whole =
        at.inputs->cell(grid.area().valid_mask(at.region), cv::Rect(0, 0, at.region.width, at.region.height));
    ctx.region_input = whole.value(at.cell_input);
    if (at.entropy) ctx.region_entropy = whole.value(DecisionInput::entropy);
  }
  ctx.lawnmowers = lawnmowers;
  return ctx;
}

}  // namespace adaptseg::detail
