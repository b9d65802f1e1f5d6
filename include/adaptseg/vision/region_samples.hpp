#pragma once
/// @file
/// Decision-function initialisation data (paper §3.2.2): on a training field with ground
/// truth, every top-level region is seen from h_max and from every candidate lower altitude
/// h' (a sub-lawnmower over the region), all segmented by the mission's own backend; each
/// (region, h') pair gives one sample of Δh, Δσ and ΔmIoU.

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/descent_coverage.hpp>
#include <adaptseg/vision/detail/survey_grid.hpp>
#include <adaptseg/vision/gain_extent.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/semantic_map.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <algorithm>
#include <cmath>
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

namespace detail {

/// collect_samples() on one field: the top-level lawnmower flown once (its map and confusion are
/// every sample's reference), then each top-level region (TopRegion) re-mapped at every
/// candidate GSD, a RegionSample each and, with a coverage that ranks cells, a CellSample per
/// cell of the sub-lawnmower.
template <SegmentationBackend Backend>
class SampleCollector {
 public:
  SampleCollector(const Field& field, Backend& backend, const CameraModel& camera, double top_gsd_cm,
                  const std::vector<int>& interest, DescentCoverage coverage, std::size_t field_index, MapFusion fusion,
                  bool frame_check, DescentGrid descent_grid, GainExtent gain_extent)
      : field_(field),
        backend_(backend),
        camera_(camera),
        top_gsd_cm_(top_gsd_cm),
        interest_(interest),
        covers_(descent_coverage_info(coverage)),
        survey_(SurveyArea::of(field), camera, GridAnchor::corner, descent_grid),
        field_index_(field_index),
        fusion_(fusion),
        sensor_(field, camera),
        planner_(camera),
        n_(field.num_classes()),
        ranked_(covers_.ranks_cells),
        frame_check_(ranked_ && frame_check),
        pooled_(pools_probabilities(fusion)),
        whole_images_(gain_extent == GainExtent::images),
        field_map_(field.labels().size(), field.ignore_label(), fusion, interest),
        field_cm_(n_),
        field_px_total_(std::max(1, field.valid_pixels())),
        grid_(0, 0, field.width_px(), field.height_px()) {
    // The top-level lawnmower over the whole field: every sample's field terms are measured
    // against its map.
    tops_ = planner_.plan(field.area(), top_gsd_cm, {0.0, 0.0}, [&](const Area& a) { return keep(a); });
    for (const auto& top : tops_) {
      top_images_.push_back(sensor_.capture(top));
      top_segmentations_.push_back(segment(top_images_.back()));
      field_map_.fuse(top_images_.back(), top_segmentations_.back());
    }
    field_cm_.add(field.labels(), field_map_.labels(), field.ignore_label());
    field_miou_ = field_cm_.miou(interest).value_or(0.0);
    field_counts_ = field_cm_.counts(interest);
    field_sigma_ = semantic_ratio(field_map_.labels(), interest, field.ignore_label());
  }

  /// Every sample of the field.
  [[nodiscard]] CalibrationSamples collect(const std::vector<double>& candidate_gsd_cm) {
    CalibrationSamples out;
    for (std::size_t t = 0; t < tops_.size(); ++t) {
      const TopRegion r = top_region(t);
      const std::size_t first_cell = out.cells.size();
      afters_.clear();
      reframed_.clear();
      cell_rects_.clear();
      for (double g : candidate_gsd_cm) {
        if (g < field_.gsd_cm() * (1.0 - 1e-9)) continue;
        descend(r, g, out);
      }
      confirm(r, std::span(out.cells).subspan(first_cell));
    }
    return out;
  }

 private:
  /// What the UAV knows of top-level region `t` when it plans the descent.
  struct TopRegion {
    std::size_t index = 0;
    cv::Rect region, inside;  ///< the footprint on the field's grid; its part on the grid
    Image local;              ///< the top-level image, pixel frame shifted to the region
    SemanticMap map;          ///< its segmentation on the map grid
    cv::Mat field_px;         ///< the region's field pixels: where relabelling is counted
    GridInputs inputs;        ///< the decision inputs over the region's map grid (ranked only)
    ConfusionMatrix cm;       ///< the top-level image's own confusion
    double sigma = 0.0;       ///< its semantic ratio
  };

  /// A finer image of the current descent, on the field's grid, and its segmentation.
  struct Look {
    Image image;
    Segmentation segmentation;
  };

  [[nodiscard]] bool keep(const Area& a) const { return field_.has_valid(a); }

  // With probabilities where the cells' inputs or a pooled map read them (SemanticMap::fuse
  // refuses a pooled map a segmentation without them).
  [[nodiscard]] Segmentation segment(const Image& image) {
    return segment_and_check(backend_, image, n_, ranked_ || pooled_).release();
  }

  [[nodiscard]] TopRegion top_region(std::size_t t) const {
    const Image& top_image = top_images_[t];
    const Segmentation& top_segmentation = top_segmentations_[t];
    const cv::Rect region = top_image.footprint_px;
    TopRegion r{t,
                region,
                region & grid_,
                top_image,
                SemanticMap(region.size(), field_.ignore_label(), fusion_, interest_),
                cv::Mat(region.size(), CV_8UC1, cv::Scalar(0)),
                {},
                image_confusion(top_image, top_segmentation.labels, n_),
                semantic_ratio(top_segmentation.labels, interest_, top_image.ignore_label)};
    r.local.footprint_px -= region.tl();
    r.map.fuse(r.local, top_segmentation);
    field_.valid_mask()(r.inside).copyTo(r.field_px(r.inside - region.tl()));
    if (ranked_)
      r.inputs.assign(top_image, top_segmentation, interest_, field_.ignore_label(), region, kEveryDecisionInputList);
    return r;
  }

  /// The region `r` re-mapped by a sub-lawnmower at `g`: its RegionSample and CellSamples.
  void descend(const TopRegion& r, double g, CalibrationSamples& out) {
    const Waypoint& top = tops_[r.index];
    const auto keep_cell = [&](const Area& a) {
      return keep(a) && (!covers_.flies || covers_.flies(r.map.labels(), field_.pixel_rect(a) - r.region.tl(),
                                                         top_gsd_cm_, field_.gsd_cm(), interest_));
    };
    // The sub-lawnmower as AdaptivePlanner::sub_plan lays it.
    const auto sub = survey_.sub_lawnmower(top, g, keep_cell);
    if (sub.empty()) return;
    // Fuse the sub-lawnmower into a map of the region alone (region_map()).
    SemanticMap local = region_map(r);
    // Ranked: each finer image's own decision inputs over its cell (the scene check's proxy).
    std::vector<CellInputs> fine_inputs;
    looks_.clear();
    for (const auto& w : sub) {
      Image img = sensor_.capture(w);
      const Segmentation seg = segment(img);
      if (whole_images_) looks_.push_back({img, seg});
      img.footprint_px -= r.region.tl();
      local.fuse(img, seg);
      if (!ranked_) continue;
      const cv::Rect cell = ((field_.pixel_rect(w.footprint) & r.inside) - r.region.tl()) &
                            cv::Rect(0, 0, r.region.width, r.region.height);
      if (cell.area() == 0) {
        fine_inputs.emplace_back();
        continue;
      }
      fine_inputs_.assign(img, seg, interest_, field_.ignore_label(), cell, kEveryDecisionInputList,
                          GridInputs::Cells::one);
      fine_inputs.push_back(fine_inputs_.cell(r.field_px(cell), cv::Rect(0, 0, cell.width, cell.height)));
    }
    ConfusionMatrix sub_cm(n_);
    sub_cm.add(top_images_[r.index].ground_truth, local.labels(), field_.ignore_label());
    // What the descent changed in the mission's map: C's target.
    const cv::Mat after = map_after(r, local);
    if (ranked_) afters_.emplace_back(g, after);
    if (frame_check_) reframed_.emplace_back(g, reframed_after(r, sub));
    RegionSample s;
    s.field = field_index_;
    s.relabelled = relabelling(r.map.labels(), after, r.field_px, interest_);
    s.region_share = cv::countNonZero(r.field_px) / field_px_total_;
    s.field_sigma = field_sigma_;
    s.field_gain =
        (whole_images_ ? field_change(looks_) : field_change(r.inside, after(r.inside - r.region.tl()))).gain;
    if (ranked_) cell_samples(r, g, sub, fine_inputs, after, out);
    s.top_gsd_cm = top_gsd_cm_;
    s.sub_gsd_cm = g;
    s.delta_h_m = camera_.altitude_m(top_gsd_cm_) - camera_.altitude_m(g);
    s.sigma_top = r.sigma;
    s.sigma_sub = semantic_ratio(local.labels(), interest_, field_.ignore_label());
    std::tie(s.miou_top, s.miou_sub) = paired_miou(r.cm, sub_cm, interest_);
    out.regions.push_back(s);
  }

  /// Each cell of the sub-lawnmower `sub` re-mapped alone: the field's top-level map with the
  /// cell's pixels from the finer images (`after`; the cells of one sub-lawnmower tile the region).
  void cell_samples(const TopRegion& r, double g, const std::vector<Waypoint>& sub,
                    const std::vector<CellInputs>& fine_inputs, const cv::Mat& after, CalibrationSamples& out) {
    for (std::size_t k = 0; k < sub.size(); ++k) {
      const cv::Rect cell_in = field_.pixel_rect(sub[k].footprint) & r.inside;
      if (cell_in.area() == 0) continue;
      const cv::Rect cell = cell_in - r.region.tl();
      CellSample c;
      c.field = field_index_;
      c.region = r.index;
      c.top_gsd_cm = top_gsd_cm_;
      c.sub_gsd_cm = g;
      c.top = r.inputs.cell(r.field_px, cell);
      if (!(c.top.field_px > 0.0)) continue;
      // GainExtent::images: the gain is counted over the cell's whole footprint, and normalised
      // by it (the planner forecasts the same pixels: CellInputs::gain_px).
      if (whole_images_) c.top.footprint_px = field_.valid_pixels(sub[k].footprint);
      c.fine = fine_inputs[k];
      c.field_share = c.top.gain_px() / field_px_total_;
      c.field_sigma = field_sigma_;
      const Relabelling changed = relabelling(r.map.labels()(cell), after(cell), r.field_px(cell), interest_);
      c.relabelled = changed.interest_share;
      c.added = changed.added_share;
      c.removed = changed.removed_share;
      c.right =
          agreeing_changes(r.map.labels()(cell), after(cell), {field_.labels()(cell_in)}, r.field_px(cell), interest_);
      const FieldChange change =
          whole_images_ ? field_change(std::span(looks_).subspan(k, 1)) : field_change(cell_in, after(cell));
      c.field_gain = change.gain;
      c.delta_tp = change.delta_tp;
      c.delta_fp = change.delta_fp;
      c.field_tp = field_counts_.tp;
      c.field_fp = field_counts_.fp;
      c.field_fn = field_counts_.fn;
      out.cells.push_back(c);
      cell_rects_.push_back(cell);
    }
  }

  /// What the field's top-level map gains over L where the rectangle `on` (on the field's grid)
  /// takes the labels `labels` instead of its own.
  struct FieldChange {
    double gain = 0.0;  ///< field mIoU over L after, minus before
    std::int64_t delta_tp = 0, delta_fp = 0;
  };
  [[nodiscard]] FieldChange field_change(const cv::Rect& on, const cv::Mat& labels) const {
    ConfusionMatrix before(n_), after(n_);
    before.add(field_.labels()(on), field_map_.labels()(on), field_.ignore_label());
    after.add(field_.labels()(on), labels, field_.ignore_label());
    ConfusionMatrix cm = field_cm_;
    cm -= before;
    cm += after;
    const PixelCounts now = after.counts(interest_), was = before.counts(interest_);
    return {cm.miou(interest_).value_or(0.0) - field_miou_, now.tp - was.tp, now.fp - was.fp};
  }

  /// GainExtent::images: the change of the field's map over every pixel `looks` (finer images
  /// on the field's grid) cover, fused into it as a flight fuses them: with every top-level image
  /// over those pixels, the neighbouring regions' included.
  [[nodiscard]] FieldChange field_change(std::span<const Look> looks) const {
    cv::Rect box;
    for (const Look& l : looks) box = box.area() == 0 ? l.image.footprint_px : (box | l.image.footprint_px);
    box &= grid_;
    if (box.area() == 0) return {};
    SemanticMap map(box.size(), field_.ignore_label(), fusion_, interest_);
    const auto fuse = [&](Image image, const Segmentation& seg) {
      image.footprint_px -= box.tl();
      map.fuse(image, seg);
    };
    for (std::size_t t = 0; t < tops_.size(); ++t)  // in the field map's order: the same sums
      if ((top_images_[t].footprint_px & box).area() > 0) fuse(top_images_[t], top_segmentations_[t]);
    for (const Look& l : looks) fuse(l.image, l.segmentation);
    cv::Mat labels = field_map_.labels()(box).clone();
    map.labels().copyTo(labels, map.labels() != field_.ignore_label());
    return field_change(box, labels);
  }

  /// The mission's map of region `r` after the sub-lawnmower `sub` shifted half a footprint
  /// along its rows both ways (frames another image's width apart from each original, those
  /// shared by two neighbours flown once), as descend() makes it from `sub`.
  [[nodiscard]] cv::Mat reframed_after(const TopRegion& r, const std::vector<Waypoint>& sub) {
    std::vector<Waypoint> shifted;
    for (const Waypoint& w : sub)
      for (double side : {-0.5, 0.5}) {
        Waypoint s = w;
        const double dx = side * w.footprint.width_m();
        s.position.x() += dx;
        s.footprint.x_min_m += dx;
        s.footprint.x_max_m += dx;
        const auto same = [&](const Waypoint& o) { return (o.position - s.position).norm() < 1e-6; };
        if (keep(s.footprint) && std::none_of(shifted.begin(), shifted.end(), same)) shifted.push_back(s);
      }
    SemanticMap local = region_map(r);
    for (const Waypoint& w : shifted) {
      Image img = sensor_.capture(w);
      const Segmentation seg = segment(img);
      img.footprint_px -= r.region.tl();
      local.fuse(img, seg);
    }
    return map_after(r, local);
  }

  /// A map of region `r` alone (pixel frame shifted) for a sub-lawnmower's images to be fused
  /// into. Cells a coverage leaves out keep their top-level labels, as in the mission's map; a
  /// pooled map pools the finer images with the top-level one everywhere.
  [[nodiscard]] SemanticMap region_map(const TopRegion& r) const {
    SemanticMap local(r.region.size(), field_.ignore_label(), fusion_, interest_);
    if (covers_.flies || pooled_) local.fuse(r.local, top_segmentations_[r.index]);
    return local;
  }

  /// The mission's map of region `r` after a descent fused into `local` (region_map()): the
  /// top-level labels where the sub-lawnmower wrote nothing.
  [[nodiscard]] cv::Mat map_after(const TopRegion& r, const SemanticMap& local) const {
    cv::Mat after = r.map.labels().clone();
    local.labels().copyTo(after, local.labels() != field_.ignore_label());
    return after;
  }

  /// The region's cells (`cells`, cell_samples() of every candidate GSD, in order) checked
  /// against the region's map at twice each cell's GSD where that was a candidate
  /// (CellSample::confirmed, confirmed_right) and, with frame_check_, against its map from the
  /// shifted frames at the cell's own GSD (reframed, reframed_right).
  void confirm(const TopRegion& r, std::span<CellSample> cells) const {
    for (std::size_t i = 0; i < cells.size(); ++i) {
      CellSample& c = cells[i];
      const auto find = [](const auto& maps, double g) {
        return std::find_if(maps.begin(), maps.end(), [&](const auto& a) { return std::abs(a.first - g) <= 1e-9 * g; });
      };
      const auto own = find(afters_, c.sub_gsd_cm);
      if (own == afters_.end()) continue;
      const cv::Rect cell = cell_rects_[i];
      const cv::Mat before = r.map.labels()(cell), after = own->second(cell), mask = r.field_px(cell),
                    truth = field_.labels()(cell + r.region.tl());
      const auto check = [&](const cv::Mat& other, Relabelling& agreed, Relabelling& right) {
        agreed = agreeing_changes(before, after, {other(cell)}, mask, interest_);
        right = agreeing_changes(before, after, {other(cell), truth}, mask, interest_);
      };
      if (const auto coarser = find(afters_, 2.0 * c.sub_gsd_cm); coarser != afters_.end())
        check(coarser->second, c.confirmed, c.confirmed_right);
      if (const auto shifted = find(reframed_, c.sub_gsd_cm); shifted != reframed_.end())
        check(shifted->second, c.reframed, c.reframed_right);
    }
  }

  const Field& field_;
  Backend& backend_;
  const CameraModel& camera_;
  double top_gsd_cm_;
  const std::vector<int>& interest_;
  const DescentCoverageInfo& covers_;
  /// The field as the planner lays its descents (grid from the corner, AdaptiveOptions::descent_grid).
  SurveyGrid survey_;
  std::size_t field_index_;
  MapFusion fusion_;
  SimulatedSensor sensor_;
  LawnmowerPlanner planner_;
  int n_;
  bool ranked_, frame_check_, pooled_;
  bool whole_images_;        ///< GainExtent::images
  std::vector<Look> looks_;  ///< GainExtent::images: the current descent's finer images
  std::vector<Waypoint> tops_;
  std::vector<Image> top_images_;
  std::vector<Segmentation> top_segmentations_;
  SemanticMap field_map_;
  ConfusionMatrix field_cm_;
  double field_miou_ = 0.0;
  PixelCounts field_counts_{};
  double field_sigma_ = 0.0;
  double field_px_total_;
  cv::Rect grid_;
  /// Ranked: the last finer image's decision inputs over its cell (buffers reused). GridInputs
  /// sums of every input give cell_inputs() of planes_on_grid() of pixel_inputs(), to the bit.
  GridInputs fine_inputs_;
  /// Ranked: the current region's map after the descent at each candidate GSD, and the region
  /// frame's rectangle of each of its cell samples (confirm()).
  std::vector<std::pair<double, cv::Mat>> afters_;
  std::vector<std::pair<double, cv::Mat>> reframed_;  ///< frame_check_: reframed_after() per GSD
  std::vector<cv::Rect> cell_rects_;
};

}  // namespace detail

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
/// mission's map does. `frame_check`: CalibrationOptions::frame_check (cells only).
/// `descent_grid`: how each sub-lawnmower is laid, as AdaptivePlanner::sub_plan lays it
/// (AdaptiveOptions::descent_grid). `gain_extent`: which pixels the field gains count.
/// @throws std::invalid_argument for a top GSD finer than the field's or candidates not finer
///         than the top, or an empty `interest`.
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationSamples collect_samples(const Field& field, Backend& backend, const CameraModel& camera,
                                                 double top_gsd_cm, const std::vector<double>& candidate_gsd_cm,
                                                 const std::vector<int>& interest,
                                                 DescentCoverage coverage = DescentCoverage::region,
                                                 std::size_t field_index = 0, MapFusion fusion = MapFusion::finest,
                                                 bool frame_check = false,
                                                 DescentGrid descent_grid = DescentGrid::region,
                                                 GainExtent gain_extent = GainExtent::region) {
  detail::require(top_gsd_cm >= field.gsd_cm() * (1.0 - 1e-9),
                  "collect_region_samples: top_gsd_cm is finer than the field's GSD", top_gsd_cm);
  detail::require(!interest.empty(), "collect_region_samples: no labels of interest", 0);
  for (double g : candidate_gsd_cm)
    detail::require(std::isfinite(g) && g > 0.0 && g < top_gsd_cm,
                    "collect_region_samples: candidate GSDs must be finer than top_gsd_cm", g);
  return detail::SampleCollector<Backend>(field, backend, camera, top_gsd_cm, interest, coverage, field_index, fusion,
                                          frame_check, descent_grid, gain_extent)
      .collect(candidate_gsd_cm);
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
