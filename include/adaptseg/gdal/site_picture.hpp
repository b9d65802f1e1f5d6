#pragma once
/// @file
/// The picture of a site's plan (adaptseg_plan's site.png): the site and its outline, every
/// footprint, the path coloured by sortie, the take-off point, and, since the site frame is
/// turned to the site's longer side rather than to north, a north arrow and a scale bar.
/// CMake target adaptseg::gdal.

#include <adaptseg/gdal/site_plan.hpp>
#include <adaptseg/gdal/survey_site.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/visualization.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <iterator>
#include <numbers>
#include <string>
#include <vector>

namespace adaptseg {

namespace detail {

/// The longest of 1, 2, 5 x 10^k metres not above `most_m`.
inline double round_scale_length_m(double most_m) {
  const double p = std::pow(10.0, std::floor(std::log10(most_m)));
  for (double f : {5.0, 2.0, 1.0})
    if (f * p <= most_m) return f * p;
  return p;
}

/// render_site_picture's routes: each sortie from `home` through its waypoints (dots) and via
/// points (rings) and back, one colour per sortie, its first waypoint numbered when there are
/// several; `px` maps the site frame [m] to the picture.
template <class ToPixel>
void draw_sorties(cv::Mat& base, const SitePlan& plan, const ToPixel& px, const cv::Point& home, int radius) {
  static const cv::Scalar kSortie[] = {{60, 60, 60},   {30, 30, 200},  {200, 80, 30},
                                       {30, 150, 200}, {150, 30, 150}, {30, 150, 30}};
  const auto& path = plan.survey.waypoints;
  for (std::size_t k = 0; k < plan.sorties.size() && k < plan.routes.size(); ++k) {
    const Sortie& sortie = plan.sorties[k];
    const cv::Scalar colour = kSortie[k % std::size(kSortie)];
    cv::Point prev = home;
    for (const RoutePoint& r : plan.routes[k]) {
      const cv::Point p = px(r.position.x(), r.position.y());
      cv::line(base, prev, p, colour, 1, cv::LINE_AA);
      if (r.image)
        cv::circle(base, p, radius, colour, cv::FILLED, cv::LINE_AA);
      else
        cv::circle(base, p, std::max(2, radius / 2), colour, 1, cv::LINE_AA);  // a via point
      prev = p;
    }
    cv::line(base, prev, home, colour, 1, cv::LINE_4);  // the return
    if (plan.sorties.size() > 1)
      put_text(base, std::to_string(k + 1),
               px(path[sortie.first].position.x(), path[sortie.first].position.y()) + cv::Point(5, -5), 0.5, colour, 2);
  }
}

/// `base` with a strip below it: a scale bar of a round length on the left (`m_per_px` metres
/// per picture pixel), a north arrow on the right, true north at compass bearing
/// `heading_deg` of the frame's +x.
[[nodiscard]] inline cv::Mat with_scale_and_north(const cv::Mat& base, double m_per_px, double heading_deg) {
  const int strip_h = 100;
  cv::Mat out(base.rows + strip_h, std::max(base.cols, 360), CV_8UC3, cv::Scalar(255, 255, 255));
  base.copyTo(out(cv::Rect(0, 0, base.cols, base.rows)));
  const double bar_m = round_scale_length_m(0.3 * base.cols * m_per_px);
  const int bar_px = std::max(1, static_cast<int>(std::lround(bar_m / m_per_px)));
  const int y = base.rows + 50, x0 = 15;
  cv::rectangle(out, cv::Rect(x0, y - 6, bar_px, 6), cv::Scalar(0, 0, 0), cv::FILLED);
  cv::rectangle(out, cv::Rect(x0 + bar_px / 2, y - 6, bar_px - bar_px / 2, 6), cv::Scalar(255, 255, 255), cv::FILLED);
  cv::rectangle(out, cv::Rect(x0, y - 6, bar_px, 6), cv::Scalar(0, 0, 0), 1);
  put_text(out, "0", {x0 - 4, y + 20}, 0.5);
  const std::string label = (bar_m >= 1000.0 ? format_fixed(bar_m / 1000.0, bar_m >= 10000.0 ? 0 : 1) + " km"
                                             : format_fixed(bar_m, bar_m >= 1.0 ? 0 : 1) + " m");
  put_text(out, label, {x0 + bar_px - 10, y + 20}, 0.5);
  // North in the frame is (cos h, sin h); the image's y runs down.
  const double h = heading_deg * std::numbers::pi / 180.0;
  const cv::Point2d north(std::cos(h), -std::sin(h));
  const cv::Point c(out.cols - 45, base.rows + 48);
  const int len = 28;
  const cv::Point tail = c - cv::Point(static_cast<int>(std::lround(north.x * len * 0.7)),
                                       static_cast<int>(std::lround(north.y * len * 0.7)));
  const cv::Point tip = c + cv::Point(static_cast<int>(std::lround(north.x * len * 0.7)),
                                      static_cast<int>(std::lround(north.y * len * 0.7)));
  cv::circle(out, c, len, cv::Scalar(160, 160, 160), 1, cv::LINE_AA);
  cv::arrowedLine(out, tail, tip, cv::Scalar(0, 0, 0), 2, cv::LINE_AA, 0, 0.35);
  const cv::Point n_at = c + cv::Point(static_cast<int>(std::lround(north.x * (len + 10))) - 5,
                                       static_cast<int>(std::lround(north.y * (len + 10))) + 5);
  put_text(out, "N", n_at, 0.5, cv::Scalar(0, 0, 0), 2);
  return out;
}

}  // namespace detail

/// Top view of `plan` over `site` in the site frame (+x right, +y up), the longer side at most
/// `max_side` px: the site light green, its outline and holes' outlines dark green, footprints
/// outlined, each sortie's route from the take-off point through its waypoints (dots) and via
/// points (rings) and back, one colour per sortie (each sortie's first waypoint numbered when
/// there are several), the take-off point a black triangle; below, a scale
/// bar of a round length and a north arrow pointing to true north at the site's centre (the
/// frame's +x lies at compass bearing `site.geo.heading_deg`); `title` above.
[[nodiscard]] inline cv::Mat render_site_picture(const SurveySite& site, const SitePlan& plan, const std::string& title,
                                                 int max_side = 1000) {
  const cv::Mat& mask = site.area.valid_mask;
  const double gsd = site.area.map_gsd_cm;
  const auto& path = plan.survey.waypoints;
  cv::Rect canvas(0, 0, mask.cols, mask.rows);
  for (const auto& w : path) canvas |= raster_rect(w.footprint, gsd, mask.rows);
  const double s = detail::display_scale(canvas.size(), max_side);
  const cv::Size size(std::max(1, static_cast<int>(std::lround(canvas.width * s))),
                      std::max(1, static_cast<int>(std::lround(canvas.height * s))));
  cv::Mat base(size, CV_8UC3, cv::Scalar(255, 255, 255));
  // The mask scaled first: a full-resolution colour canvas of a large site would take gigabytes.
  cv::Mat small;
  cv::resize(mask, small,
             cv::Size(std::max(1, static_cast<int>(std::lround(mask.cols * s))),
                      std::max(1, static_cast<int>(std::lround(mask.rows * s)))),
             0, 0, cv::INTER_NEAREST);
  const cv::Rect at(static_cast<int>(std::lround(-canvas.x * s)), static_cast<int>(std::lround(-canvas.y * s)),
                    small.cols, small.rows);
  const cv::Rect fit = at & cv::Rect(0, 0, size.width, size.height);
  if (fit.area() > 0) base(fit).setTo(cv::Scalar(170, 225, 170), small(fit - at.tl()));
  const auto px = [&](double x_m, double y_m) {
    return cv::Point(static_cast<int>(std::lround((x_m * 100.0 / gsd - canvas.x) * s)),
                     static_cast<int>(std::lround((mask.rows - y_m * 100.0 / gsd - canvas.y) * s)));
  };
  for (const auto& ring : site.rings) {
    std::vector<cv::Point> poly;
    for (const auto& v : ring) poly.push_back(px(v.x(), v.y()));
    cv::polylines(base, std::vector<std::vector<cv::Point>>{poly}, true, cv::Scalar(40, 110, 40), 2, cv::LINE_AA);
  }
  for (const auto& w : path)
    cv::rectangle(base, px(w.footprint.x_min_m, w.footprint.y_max_m), px(w.footprint.x_max_m, w.footprint.y_min_m),
                  cv::Scalar(150, 90, 40), 1);
  const cv::Point home = px(plan.home_xy.x(), plan.home_xy.y());
  const int radius = std::max(2, static_cast<int>(std::lround(std::min(size.width, size.height) / 150.0)));
  detail::draw_sorties(base, plan, px, home, radius);
  const int tri = radius + 5;
  const std::vector<cv::Point> triangle{home + cv::Point(0, -tri), home + cv::Point(-tri, tri),
                                        home + cv::Point(tri, tri)};
  cv::fillConvexPoly(base, triangle, cv::Scalar(0, 0, 0), cv::LINE_AA);
  detail::put_text(base, "home", home + cv::Point(tri + 3, tri), 0.5);

  return detail::with_title(detail::with_scale_and_north(base, gsd / 100.0 / s, site.geo.heading_deg), title);
}

}  // namespace adaptseg
