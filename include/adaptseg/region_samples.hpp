#pragma once
/// @file
/// Decision-function initialisation data (paper §3.2.2): on a training field with ground
/// truth, every top-level region is seen from h_max and from every candidate lower altitude
/// h' (a sub-lawnmower over the region), all segmented by the mission's own backend; each
/// (region, h') pair gives one sample of Δh, Δσ and ΔmIoU.

#include <adaptseg/decision.hpp>
#include <adaptseg/lawnmower_planner.hpp>
#include <adaptseg/metrics.hpp>
#include <adaptseg/segmentation_backend.hpp>
#include <adaptseg/semantic_map.hpp>
#include <adaptseg/simulated_sensor.hpp>

#include <optional>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

namespace adaptseg {

/// mIoU over `classes` of two predictions of the same region, on a common class set: the
/// classes that occur in the truth or in either prediction. A class absent from the truth and
/// from one prediction scores 1 for that prediction (nothing to get wrong); a region where no
/// class of the set occurs anywhere scores 1 for both.
/// @return {mIoU of a, mIoU of b}
[[nodiscard]] inline std::pair<double, double> paired_miou(const ConfusionMatrix& a, const ConfusionMatrix& b,
                                                           std::span<const int> classes) {
  double sa = 0.0, sb = 0.0;
  int n = 0;
  for (int c : classes) {
    const auto ia = a.iou(c);
    const auto ib = b.iou(c);
    if (!ia && !ib) continue;
    sa += ia.value_or(1.0);
    sb += ib.value_or(1.0);
    ++n;
  }
  if (n == 0) return {1.0, 1.0};
  return {sa / n, sb / n};
}

/// Flies every top-level region of `field` at `top_gsd_cm` and at each of `candidate_gsd_cm`
/// and returns one RegionSample per (region, candidate). Regions without a valid pixel are
/// skipped; candidates finer than the field's GSD are skipped. `coverage`: what each
/// sub-lawnmower covers, as AdaptivePlanner::descent_plan (with DescentCoverage::interest, a
/// (region, candidate) whose sub-lawnmower has no cell is skipped: the planner offers no such
/// descent).
/// @throws std::invalid_argument for a top GSD finer than the field's or candidates not finer
///         than the top, or an empty `interest`.
template <SegmentationBackend Backend>
[[nodiscard]] std::vector<RegionSample> collect_region_samples(const Field& field, Backend& backend,
                                                               const CameraModel& camera, double top_gsd_cm,
                                                               const std::vector<double>& candidate_gsd_cm,
                                                               const std::vector<int>& interest,
                                                               DescentCoverage coverage = DescentCoverage::region) {
  detail::require(top_gsd_cm >= field.gsd_cm() * (1.0 - 1e-9),
                  "collect_region_samples: top_gsd_cm is finer than the field's GSD", top_gsd_cm);
  detail::require(!interest.empty(), "collect_region_samples: no labels of interest", 0);
  for (double g : candidate_gsd_cm)
    detail::require(std::isfinite(g) && g > 0.0 && g < top_gsd_cm,
                    "collect_region_samples: candidate GSDs must be finer than top_gsd_cm", g);
  const SimulatedSensor sensor(field, camera);
  const LawnmowerPlanner planner(camera);
  const auto keep = [&](const Area& a) { return field.has_valid(a); };
  const int n = field.num_classes();
  std::vector<RegionSample> out;
  for (const auto& top : planner.plan(field.area(), top_gsd_cm, {0.0, 0.0}, keep)) {
    const Image top_image = sensor.capture(top);
    const cv::Mat top_labels = backend.segment(top_image);
    const ConfusionMatrix top_cm = image_confusion(top_image, top_labels, n);
    const double sigma_top = semantic_ratio(top_labels, interest, top_image.ignore_label);
    const cv::Rect region = top_image.footprint_px;
    // What the UAV knows when it plans the descent: the top-level segmentation on the map grid.
    Image top_local = top_image;  // pixel frame shifted to the region
    top_local.footprint_px -= region.tl();
    SemanticMap top_map(region.size(), field.ignore_label());
    top_map.fuse(top_local, top_labels);
    const auto keep_cell = [&](const Area& a) {
      return keep(a) && (coverage == DescentCoverage::region ||
                         cell_shows_interest(top_map.labels(), field.pixel_rect(a) - region.tl(), top_gsd_cm,
                                             field.gsd_cm(), interest));
    };
    for (double g : candidate_gsd_cm) {
      if (g < field.gsd_cm() * (1.0 - 1e-9)) continue;
      // Fuse the sub-lawnmower into a map of the region alone (pixel frame shifted).
      const auto sub = planner.plan(top.footprint, g, Eigen::Vector2d(top.position.x(), top.position.y()), keep_cell);
      if (sub.empty()) continue;
      SemanticMap local(region.size(), field.ignore_label());
      // Cells a focused descent skips keep their top-level labels, as in the mission's map.
      if (coverage == DescentCoverage::interest) local.fuse(top_local, top_labels);
      for (const auto& w : sub) {
        Image img = sensor.capture(w);
        const cv::Mat labels = backend.segment(img);
        img.footprint_px -= region.tl();
        local.fuse(img, labels);
      }
      ConfusionMatrix sub_cm(n);
      sub_cm.add(top_image.ground_truth, local.labels(), field.ignore_label());
      RegionSample s;
      s.top_gsd_cm = top_gsd_cm;
      s.sub_gsd_cm = g;
      s.delta_h_m = camera.altitude_m(top_gsd_cm) - camera.altitude_m(g);
      s.sigma_top = sigma_top;
      s.sigma_sub = semantic_ratio(local.labels(), interest, field.ignore_label());
      std::tie(s.miou_top, s.miou_sub) = paired_miou(top_cm, sub_cm, interest);
      out.push_back(s);
    }
  }
  return out;
}

}  // namespace adaptseg
