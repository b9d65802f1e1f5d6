#pragma once
/// @file
/// The fixed-altitude lawnmower curve, the yardstick of the paper's §5 (Fig. results): field
/// mIoU against execution time of lawnmowers flown at several GSDs, and the front margin of a
/// strategy over it (method.md §5). Eigen- and OpenCV-free: the decision function uses it too.

#include <adaptseg/detail/interpolate.hpp>
#include <adaptseg/error.hpp>

#include <algorithm>
#include <cmath>
#include <vector>

namespace adaptseg {

/// One point of a fixed-altitude lawnmower curve: execution time [s] and field mIoU.
struct CurvePoint {
  double time_s = 0.0;
  double miou = 0.0;
};

/// Front margin (paper §5, method.md §5): `miou` minus the lawnmower curve's mIoU linearly
/// interpolated at `time_s`; the curve is flat beyond its ends. Positive: the strategy lies
/// above the curve (more accuracy for its time than flying one altitude everywhere).
/// @throws std::invalid_argument for an empty curve or non-finite values.
[[nodiscard]] inline double front_margin(std::vector<CurvePoint> curve, double time_s, double miou) {
  detail::require(!curve.empty(), "front_margin: the lawnmower curve is empty", 0);
  detail::require(std::isfinite(time_s) && std::isfinite(miou), "front_margin: time and mIoU must be finite", time_s);
  std::sort(curve.begin(), curve.end(), [](const CurvePoint& a, const CurvePoint& b) { return a.time_s < b.time_s; });
  return miou - detail::interpolate_flat(curve, time_s, &CurvePoint::time_s, &CurvePoint::miou);
}

/// Field mIoU of a fixed-altitude lawnmower at one GSD (a training field's curve, indexed by
/// GSD instead of time: GSD transfers between fields, time does not).
struct GsdPoint {
  double gsd_cm = 0.0;
  double miou = 0.0;
};

/// `points`' mIoU linearly interpolated at `gsd_cm` (flat beyond the ends).
/// @throws std::invalid_argument for no points or a non-finite GSD.
[[nodiscard]] inline double miou_at_gsd(std::vector<GsdPoint> points, double gsd_cm) {
  detail::require(!points.empty(), "miou_at_gsd: no points", 0);
  detail::require(std::isfinite(gsd_cm), "miou_at_gsd: gsd_cm must be finite", gsd_cm);
  std::sort(points.begin(), points.end(), [](const GsdPoint& a, const GsdPoint& b) { return a.gsd_cm < b.gsd_cm; });
  return detail::interpolate_flat(points, gsd_cm, &GsdPoint::gsd_cm, &GsdPoint::miou);
}

}  // namespace adaptseg
