#pragma once
/// @file
/// Decision-function initialisation data (paper §3.2.2): on a training field with ground
/// truth, every top-level region is seen from h_max and from every candidate lower altitude
/// h' (a sub-lawnmower over the region), all segmented by the mission's own backend; each
/// (region, h') pair gives one sample of Δh, Δσ and ΔmIoU.

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/descent_coverage.hpp>
#include <adaptseg/vision/image_summary.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/semantic_map.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <optional>
#include <span>
#include <tuple>
#include <utility>
#include <vector>

namespace adaptseg {

/// Everything calibration learns from one training field (collect_samples()).
struct CalibrationSamples {
  std::vector<RegionSample> regions;  ///< one per (region, candidate GSD)
  /// DescentCoverage::ranked: one per (region, candidate GSD, cell of the sub-lawnmower), each
  /// cell re-mapped alone; empty for the other coverages.
  std::vector<CellSample> cells;
};

/// Flies every top-level region of `field` at `top_gsd_cm` and at each of `candidate_gsd_cm`
/// and returns one RegionSample per (region, candidate). Regions without a valid pixel are
/// skipped; candidates finer than the field's GSD are skipped. `coverage`: what each
/// sub-lawnmower covers, as AdaptivePlanner::descent_plan (DescentCoverageInfo::flies; a
/// (region, candidate) whose sub-lawnmower has no cell is skipped: the planner offers no such
/// descent; with a coverage that ranks cells, DescentCoverage::ranked, every cell it flies is
/// flown, and every cell also gives a CellSample: its decision inputs in the top-level image, segmented
/// with the backend's class probabilities where it gives them, and what re-mapping it alone
/// changes). Each sample's `field` is `field_index`. `fusion`: how the maps combine the images
/// (MissionOptions::map_fusion); with MapFusion::pooled every image is segmented with its class
/// probabilities and a descent's region map pools the top-level image with the finer ones, as the
/// mission's map does.
/// @throws std::invalid_argument for a top GSD finer than the field's or candidates not finer
///         than the top, or an empty `interest`.
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationSamples collect_samples(const Field& field, Backend& backend, const CameraModel& camera,
                                                 double top_gsd_cm, const std::vector<double>& candidate_gsd_cm,
                                                 const std::vector<int>& interest,
                                                 DescentCoverage coverage = DescentCoverage::region,
                                                 std::size_t field_index = 0, MapFusion fusion = MapFusion::finest) {
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
  const DescentCoverageInfo& covers = descent_coverage_info(coverage);
  const bool ranked = covers.ranks_cells;
  const bool pooled = fusion == MapFusion::pooled;
  // With probabilities where the cells' inputs or a pooled map read them (SemanticMap::fuse
  // refuses a pooled map a segmentation without them).
  const auto segment = [&](const Image& image) {
    return ranked || pooled ? segment_with_probabilities_checked(backend, image, n)
                            : Segmentation{segment_checked(backend, image, n), {}};
  };
  const auto tops = planner.plan(field.area(), top_gsd_cm, {0.0, 0.0}, keep);
  std::vector<Image> top_images;
  std::vector<Segmentation> top_segmentations;
  SemanticMap field_map(field.labels().size(), field.ignore_label(), fusion);
  for (const auto& top : tops) {
    top_images.push_back(sensor.capture(top));
    top_segmentations.push_back(segment(top_images.back()));
    field_map.fuse(top_images.back(), top_segmentations.back());
  }
  ConfusionMatrix field_cm(n);
  field_cm.add(field.labels(), field_map.labels(), field.ignore_label());
  const double field_miou = field_cm.miou(interest).value_or(0.0);
  const PixelCounts field_counts = field_cm.counts(interest);
  const double field_sigma = semantic_ratio(field_map.labels(), interest, field.ignore_label());
  const double field_px_total = std::max(1, field.valid_pixels());
  const cv::Rect grid(0, 0, field.width_px(), field.height_px());
  CalibrationSamples out;
  for (std::size_t t = 0; t < tops.size(); ++t) {
    const Waypoint& top = tops[t];
    const Image& top_image = top_images[t];
    const Segmentation& top_segmentation = top_segmentations[t];
    const cv::Mat& top_labels = top_segmentation.labels;
    const ConfusionMatrix top_cm = image_confusion(top_image, top_labels, n);
    const double sigma_top = semantic_ratio(top_labels, interest, top_image.ignore_label);
    const cv::Rect region = top_image.footprint_px;
    // What the UAV knows when it plans the descent: the top-level segmentation on the map grid.
    Image top_local = top_image;  // pixel frame shifted to the region
    top_local.footprint_px -= region.tl();
    SemanticMap top_map(region.size(), field.ignore_label(), fusion);
    top_map.fuse(top_local, top_segmentation);
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
      return keep(a) && (!covers.flies || covers.flies(top_map.labels(), field.pixel_rect(a) - region.tl(), top_gsd_cm,
                                                       field.gsd_cm(), interest));
    };
    // The decision inputs of the top-level image on the region's map grid (ranked only).
    const std::vector<cv::Mat> top_planes =
        ranked ? planes_on_grid(top_image, pixel_inputs(top_segmentations[t], interest, field.ignore_label()), region)
               : std::vector<cv::Mat>{};
    for (double g : candidate_gsd_cm) {
      if (g < field.gsd_cm() * (1.0 - 1e-9)) continue;
      // Fuse the sub-lawnmower into a map of the region alone (pixel frame shifted).
      const auto sub = planner.plan(top.footprint, g, Eigen::Vector2d(top.position.x(), top.position.y()), keep_cell);
      if (sub.empty()) continue;
      SemanticMap local(region.size(), field.ignore_label(), fusion);
      // Cells a coverage leaves out keep their top-level labels, as in the mission's map; a
      // pooled map pools the finer images with the top-level one everywhere.
      if (covers.flies || pooled) local.fuse(top_local, top_segmentation);
      // Ranked: each finer image's own decision inputs over its cell (the scene check's proxy).
      std::vector<CellInputs> fine_inputs;
      for (const auto& w : sub) {
        Image img = sensor.capture(w);
        const Segmentation seg = segment(img);
        img.footprint_px -= region.tl();
        local.fuse(img, seg);
        if (!ranked) continue;
        const cv::Rect cell =
            ((field.pixel_rect(w.footprint) & inside) - region.tl()) & cv::Rect(0, 0, region.width, region.height);
        if (cell.area() == 0) {
          fine_inputs.emplace_back();
          continue;
        }
        const auto planes = planes_on_grid(img, pixel_inputs(seg, interest, field.ignore_label()), cell);
        fine_inputs.push_back(cell_inputs(planes, field_px(cell), cv::Rect(0, 0, cell.width, cell.height)));
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
      // Each cell re-mapped alone: the field's top-level map with the cell's pixels from the
      // finer images (the cells of one sub-lawnmower tile the region).
      for (std::size_t k = 0; ranked && k < sub.size(); ++k) {
        const Waypoint& w = sub[k];
        const cv::Rect cell_in = field.pixel_rect(w.footprint) & inside;
        if (cell_in.area() == 0) continue;
        const cv::Rect cell = cell_in - region.tl();
        CellSample c;
        c.field = field_index;
        c.region = t;
        c.top_gsd_cm = top_gsd_cm;
        c.sub_gsd_cm = g;
        c.top = cell_inputs(top_planes, field_px, cell);
        if (!(c.top.field_px > 0.0)) continue;
        c.fine = fine_inputs[k];
        c.field_share = c.top.field_px / field_px_total;
        c.field_sigma = field_sigma;
        c.relabelled = relabelling(top_map.labels()(cell), after(cell), field_px(cell), interest).interest_share;
        ConfusionMatrix cell_cm = field_cm;
        ConfusionMatrix before_cell(n), after_cell(n);
        before_cell.add(field.labels()(cell_in), field_map.labels()(cell_in), field.ignore_label());
        after_cell.add(field.labels()(cell_in), after(cell), field.ignore_label());
        cell_cm -= before_cell;
        cell_cm += after_cell;
        c.field_gain = cell_cm.miou(interest).value_or(0.0) - field_miou;
        const PixelCounts now = after_cell.counts(interest), was = before_cell.counts(interest);
        c.delta_tp = now.tp - was.tp;
        c.delta_fp = now.fp - was.fp;
        c.field_tp = field_counts.tp;
        c.field_fp = field_counts.fp;
        c.field_fn = field_counts.fn;
        out.cells.push_back(c);
      }
      s.top_gsd_cm = top_gsd_cm;
      s.sub_gsd_cm = g;
      s.delta_h_m = camera.altitude_m(top_gsd_cm) - camera.altitude_m(g);
      s.sigma_top = sigma_top;
      s.sigma_sub = semantic_ratio(local.labels(), interest, field.ignore_label());
      std::tie(s.miou_top, s.miou_sub) = paired_miou(top_cm, sub_cm, interest);
      out.regions.push_back(s);
    }
  }
  return out;
}

/// The region samples of collect_samples() (the paper's initialisation samples).
/// @throws std::invalid_argument as collect_samples().
template <SegmentationBackend Backend>
[[nodiscard]] std::vector<RegionSample> collect_region_samples(const Field& field, Backend& backend,
                                                               const CameraModel& camera, double top_gsd_cm,
                                                               const std::vector<double>& candidate_gsd_cm,
                                                               const std::vector<int>& interest,
                                                               DescentCoverage coverage = DescentCoverage::region,
                                                               std::size_t field_index = 0,
                                                               MapFusion fusion = MapFusion::finest) {
  return collect_samples(field, backend, camera, top_gsd_cm, candidate_gsd_cm, interest, coverage, field_index, fusion)
      .regions;
}

}  // namespace adaptseg
