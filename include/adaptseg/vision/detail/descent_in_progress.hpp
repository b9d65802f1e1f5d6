#pragma once
/// @file
/// The adaptive planner's (adaptive_planner.hpp) descent in progress: the descent chosen, its
/// waypoints handed out one by one, what its images do to its region, until its outcome goes
/// to the policy (paper §3.2.3).

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/detail/descent_costing.hpp>
#include <adaptseg/vision/detail/descent_tour.hpp>
#include <adaptseg/vision/detail/descent_watch.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/semantic_map.hpp>

#include <opencv2/core.hpp>

#include <cstddef>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// Where a descent's region lies and what is read of it when the descent ends: the fused map's
/// labels and the map grid's field (`valid_mask`), the region on that grid, its field pixels,
/// the labels of interest and the map's label for ground not yet seen.
struct DescentRegion {
  const cv::Mat& labels;
  const cv::Mat& valid_mask;
  cv::Rect rect;
  double field_px = 0.0;
  std::span<const int> interest;
  int unknown_label = 0;
};

/// Whether `policy` trusts a descent image of σ `sigma_image` (about `interest`) over `cell` of
/// `map` before it is fused, whose σ there is the top-level one (GuardsDescentImages); a policy
/// without a guard, or an empty cell, trusts every one.
template <class Policy>
[[nodiscard]] bool trusts_descent_image(Policy& policy, const SemanticMap& map, const cv::Rect& cell,
                                        std::span<const int> interest, double sigma_image) {
  if constexpr (GuardsDescentImages<Policy>)
    return cell.area() == 0 ||
           policy.trusts_descent_image(semantic_ratio(map.labels()(cell), interest, map.unknown_label()), sigma_image);
  else
    return true;
}

/// The descent in progress: the descent chosen at a top-level waypoint (or taken from the tour),
/// its waypoints handed out in order, what its images do to its region (DescentWatch), and
/// whether the budget ended it early. Empty between descents.
class DescentInProgress {
 public:
  /// `d`'s waypoints come next, from its first.
  void start(ChosenDescent d) {
    waypoints_ = std::move(d.plan);
    next_ = 0;
    chosen_ = std::move(d);
  }

  /// Whether a waypoint of it is still to be handed out.
  [[nodiscard]] bool has_next() const noexcept { return next_ < waypoints_.size(); }

  /// Fills `p` with its next waypoint (level 1, its region, its decision, its step) and moves on.
  void hand_out(PlannedWaypoint& p) {
    p.waypoint = waypoints_[next_];
    p.level = 1;
    p.top_index = chosen_.top_index;
    p.decision = chosen_.decision;
    p.step = next_++;
  }

  /// Its waypoints in visiting order (empty between descents).
  [[nodiscard]] const std::vector<Waypoint>& waypoints() const noexcept { return waypoints_; }
  /// The descent chosen (its plan moved to waypoints()).
  [[nodiscard]] const ChosenDescent& chosen() const noexcept { return chosen_; }

  /// One of its images (`image`, `segmentation`) is reported at step `step`, before it is fused:
  /// the first keeps its region's map before it (`region_labels`, what the outcome compares); one
  /// not `trusted` (the policy's guard) ends the descent there; with ranked cells (`input` given)
  /// a trusted one adds its own mass of the input over its `cell` of the map grid (the scene
  /// check; an empty cell adds nothing), whose field is `valid_mask(cell)`.
  void see(std::size_t step, bool trusted, const cv::Mat& region_labels, const Image& image,
           const Segmentation& segmentation, const std::optional<DecisionInput>& input, const cv::Rect& cell,
           std::span<const int> interest, int ignore_label, const cv::Mat& valid_mask) {
    if (step == 0) watch_.begin(region_labels);
    if (!trusted)
      end_here();
    else if (input && cell.area() > 0)
      watch_.add_fine_image(step, image, segmentation, interest, ignore_label, cell, valid_mask, *input);
  }

  /// After one of its images was reported, with waypoints left: ends it there where `costing`
  /// no longer affords the rest (the bound of a step, learned since it was chosen, may have
  /// grown; the next top-level waypoint `top_next`). A descent cut short flies straight on.
  void cut_short_unless_it_fits(const DescentCosting& costing, std::size_t top_next) {
    if (!has_next() || !costing.budget_s || costing.rest_fits(waypoints_, next_, chosen_, top_next)) return;
    end_here();
  }

  /// Ends it after the waypoints handed out so far (DescentOutcome::cut_short).
  void end_here() {
    waypoints_.resize(next_);
    cut_short_ = true;
  }

  /// After its last image: what it did to `region` (σ at h', what it relabelled; with ranked
  /// cells by `cell_input`, the input's mass over the cells of `chosen` flown), the decision's
  /// `sigma_top`, the top level's altitude `top_altitude_m`; then it is empty again.
  [[nodiscard]] DescentOutcome finish(const DescentRegion& region, double sigma_top, double top_altitude_m,
                                      const Candidate* chosen, DecisionInput cell_input) {
    DescentOutcome out;
    out.top_altitude_m = top_altitude_m;
    out.sub_altitude_m = chosen_.altitude_m;
    out.descent = chosen_.ordinal;
    out.sigma_top = sigma_top;
    watch_.region_outcome(out, region.labels, region.valid_mask, region.rect, region.interest, region.unknown_label);
    if (chosen) watch_.input_outcome(out, *chosen, waypoints_.size(), region.field_px, cell_input);
    out.cut_short = std::exchange(cut_short_, false);
    waypoints_.clear();
    next_ = 0;
    return out;
  }

 private:
  std::vector<Waypoint> waypoints_;  ///< the descent's waypoints (empty between descents)
  std::size_t next_ = 0;             ///< the next of them to hand out
  ChosenDescent chosen_;             ///< the descent (its plan moved to waypoints_)
  DescentWatch watch_;               ///< what its images do to its region
  bool cut_short_ = false;           ///< the budget ended it early
};

}  // namespace adaptseg::detail
