#pragma once
/// @file
/// The lawnmower that covers a survey site (survey_site.hpp): the grid centred on the site,
/// the cells with none of the site under them skipped, every waypoint moved at least a margin
/// inside the site's outline (and out of its holes). CMake target adaptseg::gdal.

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/gdal/survey_site.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg {

/// How a site's lawnmower is laid.
struct SiteSurveyOptions {
  LawnmowerOverlap overlap{};  ///< image overlap along and across the rows
  /// How far inside the site's outline every waypoint must lie [m], from outer edges and holes
  /// alike: the waypoint is the footprint's centre (a nadir camera), and a GNSS position error of
  /// a metre or two (the horizontal accuracy of a small UAV's receiver) must not carry the UAV
  /// across the geofence, the outline itself. 0: on the site, to the mask's pixel.
  double inside_margin_m = 2.0;
  /// The lawnmower starts in the grid corner nearest this site-frame point [m] (the take-off
  /// point); empty: the corner (x_min, y_min).
  std::optional<Eigen::Vector2d> start_xy;

  /// @throws std::invalid_argument naming the first invalid member.
  void validate() const {
    detail::require(std::isfinite(inside_margin_m) && inside_margin_m >= 0.0,
                    "SiteSurveyOptions: inside_margin_m must be finite and >= 0", inside_margin_m);
    detail::require(!start_xy || start_xy->allFinite(), "SiteSurveyOptions: start_xy must be finite",
                    start_xy ? start_xy->norm() : 0.0);
  }
};

/// A site's lawnmower and what it leaves out.
struct SiteSurvey {
  std::vector<Waypoint> waypoints;  ///< in visiting order, each at least the margin inside the site
  std::size_t moved = 0;      ///< cells whose centre lay outside (or too near the edge) and whose waypoint moved inward
  std::size_t dropped = 0;    ///< cells with some site under them but no point the margin inside: not flown
  double site_m2 = 0.0;       ///< the site's area on its mask [m^2]
  double uncovered_m2 = 0.0;  ///< the site's area under no footprint [m^2]

  /// Share of the site under a footprint, in [0, 1].
  [[nodiscard]] double coverage() const { return site_m2 > 0.0 ? 1.0 - uncovered_m2 / site_m2 : 0.0; }
};

namespace detail {

/// The site-frame point nearest `c` among the mask's pixels in `rect` that lie at least
/// `margin_m` inside the site (a pixel's distance to the nearest pixel off the site, less the
/// 1.5 pixel a rasterised edge may be off by); empty if there is none.
inline std::optional<Eigen::Vector2d> nearest_inside(const SurveySite& site, const cv::Rect& rect,
                                                     const Eigen::Vector2d& c, double margin_m) {
  const cv::Mat& mask = site.area.valid_mask;
  const double px_m = site.area.map_gsd_cm / 100.0;
  const double need_px = margin_m / px_m + 1.5;
  // The window around `rect`, padded so that every pixel of `rect` sees the edges within need_px;
  // beyond the mask nothing is site.
  const int pad = static_cast<int>(std::ceil(need_px)) + 2;
  const cv::Rect window(rect.x - pad, rect.y - pad, rect.width + 2 * pad, rect.height + 2 * pad);
  cv::Mat sub(window.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect in = window & cv::Rect(0, 0, mask.cols, mask.rows);
  if (in.area() > 0) mask(in).copyTo(sub(in - window.tl()));
  cv::Mat distance;
  cv::distanceTransform(sub != 0, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const double cx = c.x() / px_m - window.x - 0.5,
               cy = mask.rows - c.y() / px_m - window.y - 0.5;  // c in window pixels
  double best = std::numeric_limits<double>::infinity();
  std::optional<Eigen::Vector2d> out;
  for (int r = pad; r < pad + rect.height; ++r) {
    const float* d = distance.ptr<float>(r);
    for (int col = pad; col < pad + rect.width; ++col) {
      if (d[col] < need_px) continue;
      const double dd = (col - cx) * (col - cx) + (r - cy) * (r - cy);
      if (dd >= best) continue;
      best = dd;
      out = Eigen::Vector2d((window.x + col + 0.5) * px_m, (mask.rows - (window.y + r + 0.5)) * px_m);
    }
  }
  return out;
}

}  // namespace detail

/// The lawnmower that covers `site` at `gsd_cm`: the grid of LawnmowerPlanner centred on the
/// site's rectangle (its overhang split evenly between opposite sides), started in the corner
/// nearest `options.start_xy`, the cells with none of the site under them skipped, and every
/// waypoint at least `options.inside_margin_m` inside the site's outline and outside its holes
/// (the outline's polygon, SurveySite::contains).
///
/// A cell whose centre is not that far inside is *moved*, not dropped: its waypoint goes to the
/// nearest point of its footprint that is (to the mask's pixel), and its footprint with it, so
/// the image still sees the site's edge the cell was laid for. Dropping such cells would leave a
/// strip up to half a footprint wide unmapped along every edge and around every hole; moving
/// them leaves unmapped only what no footprint reaches after the move (a concave corner, a
/// sliver), which SiteSurvey::uncovered_m2 reports. A cell with no point of its footprint the
/// margin inside (a sliver of site under its corner) is dropped and counted.
/// @throws std::invalid_argument for invalid options, or as LawnmowerPlanner::plan.
[[nodiscard]] inline SiteSurvey survey_site(const SurveySite& site, const CameraModel& camera, double gsd_cm,
                                            const SiteSurveyOptions& options = {}) {
  options.validate();
  const LawnmowerPlanner planner(camera, options.overlap);
  const Area grid = planner.centred_grid(site.area.area, gsd_cm);
  const cv::Mat& mask = site.area.valid_mask;
  const cv::Rect full(0, 0, mask.cols, mask.rows);
  const double map_gsd = site.area.map_gsd_cm;
  const auto keep = [&](const Area& a) {
    const cv::Rect r = raster_rect(a, map_gsd, mask.rows) & full;
    return r.area() > 0 && cv::countNonZero(mask(r)) > 0;
  };
  const std::vector<Waypoint> cells =
      planner.plan(grid, gsd_cm, options.start_xy.value_or(Eigen::Vector2d(grid.x_min_m, grid.y_min_m)), keep);
  SiteSurvey out;
  for (Waypoint w : cells) {
    const Eigen::Vector2d c = w.position.head<2>();
    if (!site.contains(c, options.inside_margin_m)) {
      const cv::Rect rect = raster_rect(w.footprint, map_gsd, mask.rows) & full;
      const auto p = detail::nearest_inside(site, rect, c, options.inside_margin_m);
      // The raster's pick, checked against the polygon itself.
      if (!p || !site.contains(*p, options.inside_margin_m)) {
        ++out.dropped;
        continue;
      }
      const Eigen::Vector2d shift = *p - c;
      w.position.head<2>() = *p;
      w.footprint = {w.footprint.x_min_m + shift.x(), w.footprint.y_min_m + shift.y(), w.footprint.x_max_m + shift.x(),
                     w.footprint.y_max_m + shift.y()};
      ++out.moved;
    }
    out.waypoints.push_back(w);
  }
  cv::Mat seen(mask.size(), CV_8UC1, cv::Scalar(0));
  for (const auto& w : out.waypoints) {
    const cv::Rect r = raster_rect(w.footprint, map_gsd, mask.rows) & full;
    if (r.area() > 0) seen(r).setTo(255);
  }
  const double px_m2 = (map_gsd / 100.0) * (map_gsd / 100.0);
  out.site_m2 = cv::countNonZero(mask) * px_m2;
  cv::Mat unseen;
  cv::bitwise_and(mask, ~seen, unseen);
  out.uncovered_m2 = cv::countNonZero(unseen) * px_m2;
  return out;
}

/// survey_site()'s waypoints with `overlap` and the default margin (2 m inside), from the
/// corner (x_min, y_min).
/// @throws std::invalid_argument as LawnmowerPlanner::plan.
[[nodiscard]] inline std::vector<Waypoint> plan_site_survey(const SurveySite& site, const CameraModel& camera,
                                                            double gsd_cm, LawnmowerOverlap overlap = {}) {
  SiteSurveyOptions options;
  options.overlap = overlap;
  return survey_site(site, camera, gsd_cm, options).waypoints;
}

}  // namespace adaptseg
