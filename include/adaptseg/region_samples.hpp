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

/// Flies every top-level region of `field` at `top_gsd_cm` and at each of `candidate_gsd_cm`
/// and returns one RegionSample per (region, candidate). Regions without a valid pixel are
/// skipped; candidates finer than the field's GSD are skipped. `coverage`: what each
/// sub-lawnmower covers, as AdaptivePlanner::descent_plan (with DescentCoverage::interest, a
/// (region, candidate) whose sub-lawnmower has no cell is skipped: the planner offers no such
/// descent). Each sample's `field` is `field_index`.
/// @throws std::invalid_argument for a top GSD finer than the field's or candidates not finer
///         than the top, or an empty `interest`.
template <SegmentationBackend Backend>
[[nodiscard]] std::vector<RegionSample> collect_region_samples(const Field& field, Backend& backend,
                                                               const CameraModel& camera, double top_gsd_cm,
                                                               const std::vector<double>& candidate_gsd_cm,
                                                               const std::vector<int>& interest,
                                                               DescentCoverage coverage = DescentCoverage::region,
                                                               std::size_t field_index = 0) {
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
  // The top-level lawnmower over the whole field: every sample's field terms are measured
  // against its map.
  const auto tops = planner.plan(field.area(), top_gsd_cm, {0.0, 0.0}, keep);
  std::vector<Image> top_images;
  std::vector<cv::Mat> top_segmentations;
  SemanticMap field_map(field.labels().size(), field.ignore_label());
  for (const auto& top : tops) {
    top_images.push_back(sensor.capture(top));
    top_segmentations.push_back(segment_checked(backend, top_images.back(), n));
    field_map.fuse(top_images.back(), top_segmentations.back());
  }
  ConfusionMatrix field_cm(n);
  field_cm.add(field.labels(), field_map.labels(), field.ignore_label());
  const double field_miou = field_cm.miou(interest).value_or(0.0);
  const double field_sigma = semantic_ratio(field_map.labels(), interest, field.ignore_label());
  const double field_px_total = std::max(1, field.valid_pixels());
  const cv::Rect grid(0, 0, field.width_px(), field.height_px());
  std::vector<RegionSample> out;
  for (std::size_t t = 0; t < tops.size(); ++t) {
    const Waypoint& top = tops[t];
    const Image& top_image = top_images[t];
    const cv::Mat& top_labels = top_segmentations[t];
    const ConfusionMatrix top_cm = image_confusion(top_image, top_labels, n);
    const double sigma_top = semantic_ratio(top_labels, interest, top_image.ignore_label);
    const cv::Rect region = top_image.footprint_px;
    // What the UAV knows when it plans the descent: the top-level segmentation on the map grid.
    Image top_local = top_image;  // pixel frame shifted to the region
    top_local.footprint_px -= region.tl();
    SemanticMap top_map(region.size(), field.ignore_label());
    top_map.fuse(top_local, top_labels);
    // The region's field pixels: where relabelling is counted.
    cv::Mat field_px(region.size(), CV_8UC1, cv::Scalar(0));
    const cv::Rect inside = region & grid;
    field.valid_mask()(inside).copyTo(field_px(inside - region.tl()));
    // The field's confusion without this region's top-level map, for the field gain.
    ConfusionMatrix field_without_region = field_cm;
    {
      ConfusionMatrix here(n);
      here.add(field.labels()(inside), field_map.labels()(inside), field.ignore_label());
      field_without_region -= here;
    }
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
        const cv::Mat labels = segment_checked(backend, img, n);
        img.footprint_px -= region.tl();
        local.fuse(img, labels);
      }
      ConfusionMatrix sub_cm(n);
      sub_cm.add(top_image.ground_truth, local.labels(), field.ignore_label());
      // What the descent changed in the mission's map (where the sub-lawnmower wrote nothing,
      // the map keeps the top-level labels): C's target.
      cv::Mat after = top_map.labels().clone();
      local.labels().copyTo(after, local.labels() != field.ignore_label());
      RegionSample s;
      s.field = field_index;
      s.relabelled = relabelling(top_map.labels(), after, field_px, interest);
      s.region_share = cv::countNonZero(field_px) / field_px_total;
      s.field_sigma = field_sigma;
      ConfusionMatrix with = field_without_region;
      with.add(field.labels()(inside), after(inside - region.tl()), field.ignore_label());
      s.field_gain = with.miou(interest).value_or(0.0) - field_miou;
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
