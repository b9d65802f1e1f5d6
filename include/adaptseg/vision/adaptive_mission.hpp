#pragma once
/// @file
/// The adaptive strategy in simulation (paper §4-5): AdaptivePlanner decides, a Mission flies
/// the simulated sensor and the segmentation backend and keeps the time account; in the end,
/// what each descent gained against the ground truth.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/vision/adaptive_planner.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/mission.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/semantic_map.hpp>

#include <opencv2/core.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace adaptseg {

/// What a descent gained, measured against the ground truth (simulation only).
struct RealisedDescent {
  std::size_t decision = 0;         ///< index into AdaptiveResult::decisions
  double region_miou_before = 0.0;  ///< mIoU over L of the region's map before the descent (paired_miou)
  double region_miou_after = 0.0;   ///< ... after it
  /// Field mIoU over L at the end of the mission minus the same with the pixels this descent
  /// mapped last (also beyond its region, where its images overhang) labelled as the top-level
  /// images labelled them: the descent's contribution to the mission's result.
  double field_gain = 0.0;
  /// field_gain counting only the pixels inside the descent's region (its top-level footprint):
  /// what the forecast models where calibration counts a descent's gain within its region
  /// (GainExtent::region; with GainExtent::images it models field_gain). The rest of field_gain
  /// comes from where the descent's images overhang the region (a sub-lawnmower whose footprints
  /// do not divide the region's: 12.5 or 10 cm/px from 15) and lands in the neighbours' map.
  double field_gain_region = 0.0;
  /// The same comparison in pixels, summed over the classes of L: how many more true positives,
  /// false positives and false negatives the field's map holds with this descent than without
  /// it. A corrected miss is one less false negative and one more true positive; a label of L
  /// the finer images put where the class is absent, one more false positive. Field IoU of a
  /// class moves by about (ΔTP − IoU·ΔFP) / (TP + FP + FN): a removed false positive is worth
  /// IoU times a corrected miss.
  std::int64_t delta_tp = 0;
  std::int64_t delta_fp = 0;
  std::int64_t delta_fn = 0;
  /// Region ΔmIoU in the sense of the decision function's I: before − after (< 0: it helped).
  [[nodiscard]] double region_delta_miou() const noexcept { return region_miou_before - region_miou_after; }
};

/// An adaptive mission's result: the mission plus every decision.
struct AdaptiveResult {
  MissionResult mission;
  std::vector<DecisionRecord> decisions;
  std::vector<RealisedDescent> realised;  ///< one per descent, in decision order (simulation)
  [[nodiscard]] int descents() const {
    return static_cast<int>(
        std::count_if(decisions.begin(), decisions.end(), [](const DecisionRecord& d) { return d.decision.descend; }));
  }
};

namespace detail {

/// A descent of run_adaptive_mission, to be scored at the end: its region's map before it and
/// the map pixels its images covered.
struct PendingDescent {
  std::size_t decision;
  cv::Rect region;
  cv::Mat before;
  cv::Rect covered;  ///< bounding box of the descent's footprints on the map
  double gsd_cm;
};

/// What each descent gained, in decision order (a tour flies them in its own), against the
/// ground truth: its region's mIoU before it and at the end, and the field's mIoU with the
/// pixels it mapped last (covered by it and still holding its GSD in `map_gsd_cm`) against the
/// same pixels from the top-level images alone (`top_only`).
[[nodiscard]] inline std::vector<RealisedDescent> realised_descents(const Field& field,
                                                                    std::vector<PendingDescent> descents,
                                                                    const SemanticMap& top_only,
                                                                    const cv::Mat& map_gsd_cm,
                                                                    const MissionResult& mission) {
  std::sort(descents.begin(), descents.end(),
            [](const PendingDescent& a, const PendingDescent& b) { return a.decision < b.decision; });
  const auto& interest = mission.interest;
  const int n = field.num_classes();
  const auto region_confusion = [&](const cv::Rect& region, const cv::Mat& labels) {
    ConfusionMatrix cm(n);
    cm.add(field.labels()(region), labels, field.ignore_label());
    return cm;
  };
  const double final_miou = mission.miou_interest().value_or(0.0);
  const cv::Mat& final_labels = mission.fused_labels;
  std::vector<RealisedDescent> out;
  for (const PendingDescent& d : descents) {
    RealisedDescent r;
    r.decision = d.decision;
    std::tie(r.region_miou_before, r.region_miou_after) =
        paired_miou(region_confusion(d.region, d.before), region_confusion(d.region, final_labels(d.region)), interest);
    // The confusions over `rect` of the final map and of the same with the pixels this descent
    // mapped last labelled as the top-level images labelled them; the field's gain between them.
    struct Reverted {
      ConfusionMatrix with_it, without_it;
      double field_gain;
    };
    const auto revert = [&](const cv::Rect& rect) {
      const cv::Mat owned = map_gsd_cm(rect) == static_cast<float>(d.gsd_cm);
      cv::Mat reverted = final_labels(rect).clone();
      top_only.labels()(rect).copyTo(reverted, owned);
      Reverted x{region_confusion(rect, final_labels(rect)), region_confusion(rect, reverted), 0.0};
      ConfusionMatrix without = mission.confusion;
      without -= x.with_it;
      without += x.without_it;
      x.field_gain = final_miou - without.miou(interest).value_or(0.0);
      return x;
    };
    const Reverted all = revert(d.covered);
    r.field_gain = all.field_gain;
    if (const cv::Rect inside = d.covered & d.region; inside.area() > 0)
      r.field_gain_region = revert(inside).field_gain;
    const PixelCounts a = all.with_it.counts(interest), b = all.without_it.counts(interest);
    r.delta_tp = a.tp - b.tp;
    r.delta_fp = a.fp - b.fp;
    r.delta_fn = a.fn - b.fn;
    out.push_back(r);
  }
  return out;
}

}  // namespace detail

/// Runs the adaptive strategy with `policy` over `field` in simulation: AdaptivePlanner
/// decides, a Mission flies (SimulatedSensor image, segmentation by `backend`, scoring) and
/// reports each image; the two share the mission's TimeAccount (the mission charges flight and
/// segmentation, the planner its planning), and the planner's fused map is the mission's map.
///
/// Holds references to `backend` and `policy` for the call's duration only.
/// @throws std::invalid_argument for a top GSD finer than the field's, candidates that are not
///         finer than the top, a budget too small for the top-level coverage alone, and the
///         reasons of Mission's constructor.
template <SegmentationBackend Backend, DecisionPolicy Policy>
[[nodiscard]] AdaptiveResult run_adaptive_mission(const Field& field, Backend& backend, Policy& policy,
                                                  const AdaptiveOptions& options, std::string strategy) {
  Mission<Backend> mission(field, backend, options.mission, std::move(strategy));
  AdaptiveOptions planner_options = options;
  planner_options.mission.interest = mission.interest();
  // One time account: the mission charges flight and segmentation, the planner its planning.
  AdaptivePlanner<Policy> planner(SurveyArea::of(field), policy, std::move(planner_options), &mission.time_account());
  // What each descent gained is scored at the end against the ground truth: its region's map
  // before it, the map pixels its images covered, and the top-level images alone.
  std::vector<detail::PendingDescent> descents;
  SemanticMap top_only(field.labels().size(), field.ignore_label(), options.mission.map_fusion, mission.interest());
  while (const auto w = planner.next()) {
    if (w->level == 1 && w->step == 0) {  // a descent starts: its region's map before it
      const cv::Rect region = planner.region_rect(w->top_index);
      cv::Rect covered;
      for (const Waypoint& s : planner.descent()) covered |= planner.pixel_rect(s.footprint);
      descents.push_back({w->decision, region, planner.map().labels()(region).clone(),
                          covered & cv::Rect(0, 0, field.width_px(), field.height_px()), w->waypoint.gsd_cm});
    }
    // With the backend's class probabilities where the decision reads them (a coverage that ranks
    // cells: the top-level images' decision inputs, a descent's scene check) or the map does
    // (MapFusion::pooled, pooled_interest); checked once, by the mission, which ran the backend.
    const auto visit = mission.visit(w->waypoint, w->level, planner.wants_probabilities());
    planner.report(visit.image, visit.segmentation, visit.record->segmentation_s);
    if (w->level == 0) top_only.fuse(visit.image, visit.segmentation.get());
  }
  AdaptiveResult result{std::move(mission).finish(planner.map()), planner.decisions(), {}};
  result.realised =
      detail::realised_descents(field, std::move(descents), top_only, planner.map().gsd_cm(), result.mission);
  return result;
}

}  // namespace adaptseg
