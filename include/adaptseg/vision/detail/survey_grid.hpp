#pragma once
/// @file
/// The ground the adaptive planner (adaptive_planner.hpp) maps: the survey area on the map
/// grid, its field pixels, and the lawnmowers laid over it and over each region.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::detail {

/// A SurveyArea on its map grid (the valid mask's, or just enough to cover the area, every
/// pixel of the area field where the mask is not given), seen by `camera`, with the
/// lawnmowers' grids laid as `anchor` says (AdaptiveOptions::grid_anchor) and each descent's
/// as `descent` says (AdaptiveOptions::descent_grid).
class SurveyGrid {
 public:
  /// @throws std::invalid_argument for an invalid area (SurveyArea's contract).
  SurveyGrid(SurveyArea area, CameraModel camera, GridAnchor anchor, DescentGrid descent = DescentGrid::region)
      : area_(std::move(area)),
        camera_(std::move(camera)),
        anchor_(anchor),
        descent_(descent),
        size_(grid_size(area_)) {
    if (area_.valid_mask.empty()) {
      area_.valid_mask = cv::Mat(size_, CV_8UC1, cv::Scalar(0));
      area_.valid_mask(pixel_rect(area_.area) & rect()).setTo(255);
    }
    valid_px_ = cv::countNonZero(area_.valid_mask);
  }

  [[nodiscard]] const SurveyArea& area() const noexcept { return area_; }
  [[nodiscard]] const CameraModel& camera() const noexcept { return camera_; }
  [[nodiscard]] cv::Size size() const noexcept { return size_; }
  /// The whole grid as a rectangle of pixels.
  [[nodiscard]] cv::Rect rect() const noexcept { return {0, 0, size_.width, size_.height}; }
  /// Field pixels of the whole grid.
  [[nodiscard]] double valid_px() const noexcept { return valid_px_; }

  /// The pixels of the map grid under `a` (raster_rect, as Field::pixel_rect); may extend
  /// beyond the grid.
  [[nodiscard]] cv::Rect pixel_rect(const Area& a) const { return raster_rect(a, area_.map_gsd_cm, size_.height); }

  /// Field pixels of the map grid under `a`.
  [[nodiscard]] int valid_pixels(const Area& a) const {
    const cv::Rect in = pixel_rect(a) & rect();
    return in.area() > 0 ? cv::countNonZero(area_.valid_mask(in)) : 0;
  }

  /// Share of the ground under `a` that is field (paper: DecisionContext::valid_fraction).
  [[nodiscard]] double valid_fraction(const Area& a) const {
    const cv::Rect r = pixel_rect(a);
    if (r.area() <= 0) return 0.0;
    return static_cast<double>(valid_pixels(a)) / static_cast<double>(r.area());
  }

  /// Which lawnmower cells to fly: those with any field under them (valid_pixels()).
  [[nodiscard]] auto keep() const {
    return [this](const Area& a) { return valid_pixels(a) > 0; };
  }

  /// AdaptivePlanner::image_at(): the Image of a camera frame `bgr` taken at `pose`, rotated by
  /// `yaw_deg`, its footprint snapped to the map grid.
  /// @throws std::invalid_argument as AdaptivePlanner::image_at().
  [[nodiscard]] Image image_at(const Eigen::Vector3d& pose, cv::Mat bgr = {}, double yaw_deg = 0.0) const {
    require(pose.allFinite(), "AdaptivePlanner::image_at: the pose must be finite", pose.transpose());
    require(std::isfinite(yaw_deg), "AdaptivePlanner::image_at: yaw_deg must be finite", yaw_deg);
    require(bgr.empty() || (bgr.type() == CV_8UC3 && bgr.cols == camera_.width_px() && bgr.rows == camera_.height_px()),
            "AdaptivePlanner::image_at: bgr must be CV_8UC3 of the camera's size " +
                std::to_string(camera_.width_px()) + "x" + std::to_string(camera_.height_px()),
            std::to_string(bgr.cols) + "x" + std::to_string(bgr.rows));
    Image img;
    img.bgr = std::move(bgr);
    img.position = pose;
    img.gsd_cm = camera_.gsd_cm(pose.z());
    img.width_px = camera_.width_px();
    img.height_px = camera_.height_px();
    img.ignore_label = area_.ignore_label;
    const Extent fp = camera_.footprint_at_gsd(img.gsd_cm);
    img.footprint_px = pixel_rect({pose.x() - 0.5 * fp.width_m, pose.y() - 0.5 * fp.height_m,
                                   pose.x() + 0.5 * fp.width_m, pose.y() + 0.5 * fp.height_m});
    img.yaw_deg = yaw_deg;
    return img;
  }

  /// A lawnmower over the whole area at `gsd_cm`, its grid laid as the anchor says, the cells
  /// without field left out.
  [[nodiscard]] std::vector<Waypoint> lawnmower(double gsd_cm) const {
    const Area laid = laid_grid(gsd_cm);
    return LawnmowerPlanner(camera_).plan(laid, gsd_cm, Eigen::Vector2d(laid.x_min_m, laid.y_min_m), keep());
  }

  /// The sub-lawnmower over the region of top-level waypoint `t` at `gsd_cm` (paper §3.2.1
  /// W^{h'}), laid on sub_grid() (DescentGrid::field: the cells of lawnmower(gsd_cm) centred in
  /// the region; none where no centre is), visited from the corner nearest `t`, the cells
  /// `keep_cell` keeps (default: those with field under them).
  template <class Keep>
  [[nodiscard]] std::vector<Waypoint> sub_lawnmower(const Waypoint& t, double gsd_cm, Keep&& keep_cell) const {
    const LawnmowerPlanner planner(camera_);
    const std::optional<Area> on = descent_ == DescentGrid::field
                                       ? planner.cells_centred_in(laid_grid(gsd_cm), gsd_cm, t.footprint, area_.area)
                                       : std::optional<Area>(sub_grid(t, gsd_cm));
    if (!on) return {};
    return planner.plan(*on, gsd_cm, Eigen::Vector2d(t.position.x(), t.position.y()), std::forward<Keep>(keep_cell));
  }
  [[nodiscard]] std::vector<Waypoint> sub_lawnmower(const Waypoint& t, double gsd_cm) const {
    return sub_lawnmower(t, gsd_cm, keep());
  }

 private:
  /// The rectangle the whole area's lawnmower at `gsd_cm` is laid on: the area, or (centred)
  /// the grid centred on it.
  [[nodiscard]] Area laid_grid(double gsd_cm) const {
    return anchor_ == GridAnchor::centred ? LawnmowerPlanner(camera_).centred_grid(area_.area, gsd_cm) : area_.area;
  }

  /// The map grid's size: the mask's, or just enough to cover the area.
  static cv::Size grid_size(const SurveyArea& a) {
    const Area& r = a.area;
    require_positive(a.map_gsd_cm, "SurveyArea: map_gsd_cm");
    require(std::isfinite(r.x_min_m) && std::isfinite(r.y_min_m) && r.x_min_m >= 0.0 && r.y_min_m >= 0.0 &&
                std::isfinite(r.width_m()) && r.width_m() > 0.0 && std::isfinite(r.height_m()) && r.height_m() > 0.0,
            "SurveyArea: area must be finite with x_min, y_min >= 0 and a positive size [m]",
            r.width_m() * r.height_m());
    require(a.num_classes >= 1 && a.num_classes <= 255,
            "SurveyArea: num_classes must be the size of the backend's class set, 1..255 "
            "(SurveyArea::of(field) sets it)",
            a.num_classes);
    require(a.ignore_label >= a.num_classes && a.ignore_label <= 255,
            "SurveyArea: ignore_label must be in num_classes..255, not a class index", a.ignore_label);
    const double s = 100.0 / a.map_gsd_cm;
    if (a.valid_mask.empty())
      return {static_cast<int>(std::ceil(r.x_max_m * s - 1e-6)), static_cast<int>(std::ceil(r.y_max_m * s - 1e-6))};
    require(a.valid_mask.type() == CV_8UC1, "SurveyArea: valid_mask must be CV_8UC1", a.valid_mask.type());
    require(r.x_max_m * s <= a.valid_mask.cols + 0.5 && r.y_max_m * s <= a.valid_mask.rows + 0.5,
            "SurveyArea: area must lie inside the valid mask's grid",
            std::to_string(a.valid_mask.cols) + "x" + std::to_string(a.valid_mask.rows) + " px");
    return a.valid_mask.size();
  }

  /// The rectangle a descent's sub-lawnmower at `gsd_cm` is laid on over top-level waypoint
  /// `t`'s region: the region itself (GridAnchor::corner: the grid grows from the corner nearest
  /// the waypoint, the region's centre, so which side overhangs is a tie that the frame's axes
  /// and round-off break), or the grid centred on the part of the region inside the area
  /// (GridAnchor::centred: every waypoint inside the area, as the top level's, and the same
  /// waypoints on the ground in any frame of the same site).
  [[nodiscard]] Area sub_grid(const Waypoint& t, double gsd_cm) const {
    if (anchor_ != GridAnchor::centred) return t.footprint;
    const Area& a = area_.area;
    const Area inside{std::max(t.footprint.x_min_m, a.x_min_m), std::max(t.footprint.y_min_m, a.y_min_m),
                      std::min(t.footprint.x_max_m, a.x_max_m), std::min(t.footprint.y_max_m, a.y_max_m)};
    // A region that does not reach into the area (no cell of it is kept anyway): the region.
    const bool empty = !(inside.x_max_m > inside.x_min_m && inside.y_max_m > inside.y_min_m);
    return LawnmowerPlanner(camera_).centred_grid(empty ? t.footprint : inside, gsd_cm);
  }

  SurveyArea area_;
  CameraModel camera_;
  GridAnchor anchor_;
  DescentGrid descent_;
  cv::Size size_;
  double valid_px_ = 0.0;
};

}  // namespace adaptseg::detail
