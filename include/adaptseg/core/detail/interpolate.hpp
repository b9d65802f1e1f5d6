#pragma once
/// @file
/// Piecewise-linear interpolation through sorted points, flat beyond the ends: the lawnmower
/// curve by time (front_margin) and by GSD (miou_at_gsd), and η by descent height (GainModel);
/// extended beyond the last point along a rising last segment: the curve a decision compares a
/// descent with (FrontAwarePolicy).

#include <cstddef>
#include <functional>
#include <vector>

namespace adaptseg::detail {

/// y at `x` of the polyline through `points` (at least one, sorted by x ascending), flat beyond
/// its ends; where two points share an x, the later one's y. `x_of` and `y_of` read a point's
/// coordinates (e.g. pointers to members).
template <class Point, class X, class Y>
[[nodiscard]] double interpolate_flat(const std::vector<Point>& points, double x, X x_of, Y y_of) {
  const auto px = [&](const Point& p) { return static_cast<double>(std::invoke(x_of, p)); };
  const auto py = [&](const Point& p) { return static_cast<double>(std::invoke(y_of, p)); };
  if (x <= px(points.front())) return py(points.front());
  if (x >= px(points.back())) return py(points.back());
  std::size_t k = 1;
  while (x > px(points[k])) ++k;
  const Point& a = points[k - 1];
  const Point& b = points[k];
  const double t = px(b) > px(a) ? (x - px(a)) / (px(b) - px(a)) : 1.0;
  return py(a) + t * (py(b) - py(a));
}

/// As interpolate_flat, but beyond the last point the line through the last two points goes on
/// if it rises (flat if it falls, or if there is only one point or the last two share an x):
/// never below the last point.
template <class Point, class X, class Y>
[[nodiscard]] double interpolate_extend(const std::vector<Point>& points, double x, X x_of, Y y_of) {
  const auto px = [&](const Point& p) { return static_cast<double>(std::invoke(x_of, p)); };
  const auto py = [&](const Point& p) { return static_cast<double>(std::invoke(y_of, p)); };
  const std::size_t n = points.size();
  if (n < 2 || x <= px(points.back())) return interpolate_flat(points, x, x_of, y_of);
  const Point& a = points[n - 2];
  const Point& b = points[n - 1];
  if (!(px(b) > px(a)) || !(py(b) > py(a))) return py(b);
  return py(b) + (x - px(b)) * (py(b) - py(a)) / (px(b) - px(a));
}

}  // namespace adaptseg::detail
