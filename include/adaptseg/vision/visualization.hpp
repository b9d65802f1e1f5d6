#pragma once
/// @file
/// Pictures a person can judge: class-coloured label maps, the flown path over the field
/// coloured by altitude, the fused map beside the ground truth and its errors, and a map
/// with its legend.

#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/field.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cstdio>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// BGR picture of a label map in the classes' colours; `ignore_label` (and any value that is
/// not a class) drawn in `ignore_bgr`.
[[nodiscard]] inline cv::Mat colorize_labels(const cv::Mat& labels, const std::vector<ClassInfo>& classes,
                                             cv::Vec3b ignore_bgr = {128, 128, 128}) {
  detail::require(labels.type() == CV_8UC1, "colorize_labels: labels must be CV_8UC1", labels.type());
  cv::Mat lut(1, 256, CV_8UC3, cv::Scalar(ignore_bgr[0], ignore_bgr[1], ignore_bgr[2]));
  for (std::size_t i = 0; i < classes.size() && i < 256; ++i) {
    const auto& c = classes[i].color_rgb;
    lut.at<cv::Vec3b>(0, static_cast<int>(i)) = {c[2], c[1], c[0]};
  }
  cv::Mat bgr;
  cv::cvtColor(labels, bgr, cv::COLOR_GRAY2BGR);
  cv::LUT(bgr, lut, bgr);
  return bgr;
}

namespace detail {

/// Downscales `labels` for display so its longer side is at most `max_side` [px]; returns
/// the factor applied. Nearest neighbour keeps label colours pure.
inline double display_scale(cv::Size size, int max_side) {
  return std::min(1.0, static_cast<double>(max_side) / std::max(size.width, size.height));
}

inline void put_text(cv::Mat& img, const std::string& text, cv::Point at, double scale = 0.6,
                     cv::Scalar color = {0, 0, 0}, int thickness = 1) {
  cv::putText(img, text, at, cv::FONT_HERSHEY_SIMPLEX, scale, color, thickness, cv::LINE_AA);
}

/// A white band with `title` above `img`, widened (white on the right) if the title needs it.
inline cv::Mat with_title(const cv::Mat& img, const std::string& title) {
  int baseline = 0;
  const cv::Size text = cv::getTextSize(title, cv::FONT_HERSHEY_SIMPLEX, 0.65, 1, &baseline);
  cv::Mat out(img.rows + 36, std::max(img.cols, text.width + 16), CV_8UC3, cv::Scalar(255, 255, 255));
  img.copyTo(out(cv::Rect(0, 36, img.cols, img.rows)));
  put_text(out, title, {8, 25}, 0.65);
  return out;
}

/// A legend of class colours, one row per class, `width` px wide.
inline cv::Mat class_legend(const std::vector<ClassInfo>& classes, int width, const std::string& ignore_text,
                            cv::Scalar ignore_bgr = {128, 128, 128}, double fade = 0.0) {
  const auto faded = [fade](cv::Scalar c) { return c * (1.0 - fade) + cv::Scalar(255, 255, 255) * fade; };
  const int row_h = 24;
  cv::Mat out(row_h * static_cast<int>(classes.size() + 1) + 8, width, CV_8UC3, cv::Scalar(255, 255, 255));
  for (std::size_t i = 0; i <= classes.size(); ++i) {
    const int y = 4 + static_cast<int>(i) * row_h;
    cv::Scalar col = ignore_bgr;
    std::string text = ignore_text;
    if (i < classes.size()) {
      const auto& c = classes[i].color_rgb;
      col = faded(cv::Scalar(c[2], c[1], c[0]));
      text = classes[i].name;
    }
    cv::rectangle(out, cv::Rect(8, y + 2, 30, row_h - 6), col, cv::FILLED);
    cv::rectangle(out, cv::Rect(8, y + 2, 30, row_h - 6), cv::Scalar(0, 0, 0), 1);
    put_text(out, text, {46, y + row_h - 7}, 0.55);
  }
  return out;
}

/// render_path's colours of altitude: viridis from the path's lowest waypoint to its highest.
class AltitudeColours {
 public:
  explicit AltitudeColours(std::span<const Waypoint> path) {
    if (!path.empty()) {
      lo = hi = path.front().position.z();
      for (const auto& w : path) {
        lo = std::min(lo, w.position.z());
        hi = std::max(hi, w.position.z());
      }
    }
    cv::Mat ramp(1, 256, CV_8UC1);
    for (int i = 0; i < 256; ++i) ramp.at<std::uint8_t>(0, i) = static_cast<std::uint8_t>(i);
    cv::applyColorMap(ramp, ramp_bgr_, cv::COLORMAP_VIRIDIS);
  }
  [[nodiscard]] cv::Scalar operator()(double z) const {
    const double t = hi > lo ? (z - lo) / (hi - lo) : 1.0;
    const auto v = ramp_bgr_.at<cv::Vec3b>(0, static_cast<int>(std::lround(t * 255.0)));
    return cv::Scalar(v[0], v[1], v[2]);
  }
  double lo = 0.0, hi = 1.0;  ///< the lowest and highest waypoint [m]

 private:
  cv::Mat ramp_bgr_;
};

/// render_path's side panel, `rows` high: the altitude colour bar (with GSD) and the class
/// legend (colours faded by `fade`, as the map).
[[nodiscard]] inline cv::Mat path_panel(int rows, std::span<const Waypoint> path, const AltitudeColours& colours,
                                        const std::vector<ClassInfo>& classes, double fade) {
  const int panel_w = 230;
  const double z_lo = colours.lo, z_hi = colours.hi;
  cv::Mat panel(rows, panel_w, CV_8UC3, cv::Scalar(255, 255, 255));
  put_text(panel, "waypoint altitude", {10, 22}, 0.55);
  const int bar_top = 40, bar_h = std::min(260, std::max(60, rows - 200));
  for (int y = 0; y < bar_h; ++y) {
    const double z = z_hi - (z_hi - z_lo) * y / std::max(1, bar_h - 1);
    cv::line(panel, {10, bar_top + y}, {40, bar_top + y}, colours(z));
  }
  cv::rectangle(panel, cv::Rect(10, bar_top, 31, bar_h), cv::Scalar(0, 0, 0), 1);
  const double gsd_per_m = path.empty() ? 0.0 : path.front().gsd_cm / path.front().position.z();
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.1f m (%.2f cm/px)", z_hi, z_hi * gsd_per_m);
  put_text(panel, buf, {48, bar_top + 12}, 0.45);
  std::snprintf(buf, sizeof buf, "%.1f m (%.2f cm/px)", z_lo, z_lo * gsd_per_m);
  put_text(panel, buf, {48, bar_top + bar_h}, 0.45);
  std::snprintf(buf, sizeof buf, "%zu waypoints", path.size());
  put_text(panel, buf, {10, bar_top + bar_h + 28}, 0.5);
  put_text(panel, "boxes: image footprints", {10, bar_top + bar_h + 50}, 0.45);
  const cv::Mat legend = class_legend(classes, panel_w, "outside field", {255, 255, 255}, fade);
  if (bar_top + bar_h + 60 + legend.rows <= panel.rows)
    legend.copyTo(panel(cv::Rect(0, bar_top + bar_h + 60, panel_w, legend.rows)));
  return panel;
}

}  // namespace detail

/// Top view of `path` (in visiting order) over the field: the field's labels faded, the
/// path as lines, each waypoint as a dot coloured by altitude, with an altitude/GSD colour
/// bar, a class legend and `title`. Longer side of the map at most `max_side` px.
[[nodiscard]] inline cv::Mat render_path(const Field& field, std::span<const Waypoint> path, const std::string& title,
                                         int max_side = 1000) {
  // Canvas: the orthomosaic and every footprint (the last row/column may stick out).
  cv::Rect canvas(0, 0, field.width_px(), field.height_px());
  for (const auto& w : path) canvas |= field.pixel_rect(w.footprint);
  const double s = detail::display_scale(canvas.size(), max_side);
  constexpr double kFade = 0.55;  // field colours faded toward white so the path stands out
  cv::Mat full(canvas.size(), CV_8UC3, cv::Scalar(255, 255, 255));
  colorize_labels(field.labels(), field.classes(), {255, 255, 255})
      .copyTo(full(cv::Rect(-canvas.x, -canvas.y, field.width_px(), field.height_px())));
  cv::Mat base;
  cv::resize(full, base, cv::Size(), s, s, cv::INTER_NEAREST);
  cv::addWeighted(base, 1.0 - kFade, cv::Mat(base.size(), base.type(), cv::Scalar(255, 255, 255)), kFade, 0.0, base);
  const auto rect_px = [&](const Area& a) {
    const cv::Rect r = field.pixel_rect(a) - canvas.tl();
    return cv::Rect(
        cv::Point(static_cast<int>(std::lround(r.x * s)), static_cast<int>(std::lround(r.y * s))),
        cv::Point(static_cast<int>(std::lround(r.br().x * s)), static_cast<int>(std::lround(r.br().y * s))));
  };
  const detail::AltitudeColours colours(path);
  const auto to_px = [&](const Eigen::Vector3d& p) {
    return cv::Point(
        static_cast<int>(std::lround((p.x() * 100.0 / field.gsd_cm() - canvas.x) * s)),
        static_cast<int>(std::lround((field.height_px() - p.y() * 100.0 / field.gsd_cm() - canvas.y) * s)));
  };
  // Footprints: a dark outline under the altitude colour, visible on white and on any class colour.
  for (const auto& w : path) cv::rectangle(base, rect_px(w.footprint), cv::Scalar(40, 40, 40), 3);
  for (const auto& w : path) cv::rectangle(base, rect_px(w.footprint), colours(w.position.z()), 1);
  for (std::size_t i = 1; i < path.size(); ++i)
    cv::line(base, to_px(path[i - 1].position), to_px(path[i].position), cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  const int radius = std::max(2, static_cast<int>(std::lround(std::min(base.cols, base.rows) / 150.0)));
  for (const auto& w : path) {
    cv::circle(base, to_px(w.position), radius + 1, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
    cv::circle(base, to_px(w.position), radius, colours(w.position.z()), cv::FILLED, cv::LINE_AA);
  }
  if (!path.empty()) detail::put_text(base, "start", to_px(path.front().position) + cv::Point(6, -6), 0.5);

  const cv::Mat panel = detail::path_panel(base.rows, path, colours, field.classes(), kFade);
  cv::Mat out;
  cv::hconcat(base, panel, out);
  return detail::with_title(out, title);
}

/// Top view of a survey plan over a site nobody has labelled: the site (`mask`, non-zero where
/// the site is, at `map_gsd_cm` [cm/px], row 0 at the frame's top) in light green, every
/// footprint outlined, the path as lines from the start, under `title`. Longer side at most
/// `max_side` px.
/// @throws std::invalid_argument if `mask` is not CV_8UC1 or the GSD is not positive.
[[nodiscard]] inline cv::Mat render_site_plan(const cv::Mat& mask, double map_gsd_cm, std::span<const Waypoint> path,
                                              const std::string& title, int max_side = 1000) {
  detail::require(mask.type() == CV_8UC1 && !mask.empty(), "render_site_plan: mask must be a non-empty CV_8UC1",
                  mask.type());
  detail::require_positive(map_gsd_cm, "render_site_plan: map_gsd_cm");
  cv::Rect canvas(0, 0, mask.cols, mask.rows);
  for (const auto& w : path) canvas |= raster_rect(w.footprint, map_gsd_cm, mask.rows);
  const double s = detail::display_scale(canvas.size(), max_side);
  cv::Mat full(canvas.size(), CV_8UC3, cv::Scalar(255, 255, 255));
  full(cv::Rect(-canvas.x, -canvas.y, mask.cols, mask.rows)).setTo(cv::Scalar(170, 225, 170), mask);
  cv::Mat base;
  cv::resize(full, base,
             cv::Size(std::max(1, static_cast<int>(std::lround(canvas.width * s))),
                      std::max(1, static_cast<int>(std::lround(canvas.height * s)))),
             0, 0, cv::INTER_NEAREST);
  const auto px = [&](double x_m, double y_m) {
    return cv::Point(static_cast<int>(std::lround((x_m * 100.0 / map_gsd_cm - canvas.x) * s)),
                     static_cast<int>(std::lround((mask.rows - y_m * 100.0 / map_gsd_cm - canvas.y) * s)));
  };
  for (const auto& w : path)
    cv::rectangle(base, px(w.footprint.x_min_m, w.footprint.y_max_m), px(w.footprint.x_max_m, w.footprint.y_min_m),
                  cv::Scalar(150, 90, 40), 1);
  for (std::size_t i = 1; i < path.size(); ++i)
    cv::line(base, px(path[i - 1].position.x(), path[i - 1].position.y()),
             px(path[i].position.x(), path[i].position.y()), cv::Scalar(60, 60, 60), 1, cv::LINE_AA);
  const int radius = std::max(2, static_cast<int>(std::lround(std::min(base.cols, base.rows) / 150.0)));
  for (const auto& w : path)
    cv::circle(base, px(w.position.x(), w.position.y()), radius, cv::Scalar(0, 0, 0), cv::FILLED, cv::LINE_AA);
  if (!path.empty())
    detail::put_text(base, "start", px(path.front().position.x(), path.front().position.y()) + cv::Point(6, -6), 0.5);
  return detail::with_title(base, title);
}

/// A label map in class colours beside its legend, under `title`, scaled (nearest neighbour)
/// so that its longer side is `side` px: what a live mission, which has no ground truth, shows.
[[nodiscard]] inline cv::Mat render_map(const cv::Mat& labels, const std::vector<ClassInfo>& classes,
                                        const std::string& title, int side = 700) {
  const double s = static_cast<double>(side) / std::max(labels.cols, labels.rows);
  cv::Mat a;
  cv::resize(colorize_labels(labels, classes), a, cv::Size(), s, s, cv::INTER_NEAREST);
  const cv::Mat legend_src = detail::class_legend(classes, 260, "not observed / outside");
  cv::Mat legend(std::max(a.rows, legend_src.rows), 260, CV_8UC3, cv::Scalar(255, 255, 255));
  legend_src.copyTo(legend(cv::Rect(0, 0, 260, legend_src.rows)));
  cv::Mat column(legend.rows, a.cols, CV_8UC3, cv::Scalar(255, 255, 255));
  a.copyTo(column(cv::Rect(0, 0, a.cols, a.rows)));
  cv::Mat out;
  cv::hconcat(std::vector<cv::Mat>{column, legend}, out);
  return detail::with_title(out, title);
}

/// The fused map, the ground truth and the errors side by side, each scaled (nearest
/// neighbour) so that its longer side is `side` px, with a legend. Never-observed pixels are
/// grey ("not observed / outside"); in the error panel wrong pixels are red, right ones light
/// grey, pixels never observed or without truth dark grey.
[[nodiscard]] inline cv::Mat render_map_comparison(const Field& field, const cv::Mat& fused, const std::string& title,
                                                   int side = 700) {
  detail::require(fused.type() == CV_8UC1 && fused.size() == field.labels().size(),
                  "render_map_comparison: the map must be CV_8UC1 of the field's size", fused.cols);
  const double s = static_cast<double>(side) / std::max(field.width_px(), field.height_px());
  const int ignore = field.ignore_label();
  const cv::Mat truth = field.labels();
  const cv::Mat known = (truth != ignore) & (fused != ignore);
  cv::Mat errors(fused.size(), CV_8UC3, cv::Scalar(90, 90, 90));
  errors.setTo(cv::Scalar(225, 225, 225), known & (fused == truth));
  errors.setTo(cv::Scalar(0, 0, 220), known & (fused != truth));
  const double wrong = cv::countNonZero(known & (fused != truth)) / std::max(1.0, 1.0 * cv::countNonZero(known));
  cv::Mat a, b, c;
  cv::resize(colorize_labels(fused, field.classes()), a, cv::Size(), s, s, cv::INTER_NEAREST);
  cv::resize(colorize_labels(truth, field.classes()), b, cv::Size(), s, s, cv::INTER_NEAREST);
  cv::resize(errors, c, cv::Size(), s, s, cv::INTER_NEAREST);
  char buf[96];
  std::snprintf(buf, sizeof buf, "errors: %.1f %% wrong", 100.0 * wrong);
  a = detail::with_title(a, "fused map");
  b = detail::with_title(b, "ground truth");
  c = detail::with_title(c, buf);
  const cv::Mat gap(a.rows, 12, CV_8UC3, cv::Scalar(255, 255, 255));
  const cv::Mat legend_src = detail::class_legend(field.classes(), 260, "not observed / outside");
  cv::Mat legend(a.rows, 260, CV_8UC3, cv::Scalar(255, 255, 255));
  const int legend_h = std::min(legend_src.rows, a.rows - 36);
  if (legend_h > 0) legend_src(cv::Rect(0, 0, 260, legend_h)).copyTo(legend(cv::Rect(0, 36, 260, legend_h)));
  const int errors_y = 36 + legend_h + 16;
  if (errors_y + 60 <= legend.rows) {
    const std::pair<cv::Scalar, const char*> keys[] = {{{0, 0, 220}, "error panel: wrong"},
                                                       {{225, 225, 225}, "error panel: right"}};
    for (int k = 0; k < 2; ++k) {
      const int y = errors_y + 24 * k;
      cv::rectangle(legend, cv::Rect(8, y + 2, 30, 18), keys[k].first, cv::FILLED);
      cv::rectangle(legend, cv::Rect(8, y + 2, 30, 18), cv::Scalar(0, 0, 0), 1);
      detail::put_text(legend, keys[k].second, {46, y + 17}, 0.55);
    }
  }
  cv::Mat out;
  cv::hconcat(std::vector<cv::Mat>{a, gap, b, gap, c, gap, legend}, out);
  return detail::with_title(out, title);
}

}  // namespace adaptseg
