#pragma once
/// @file
/// The fixed-altitude lawnmower curve, the yardstick of the paper's §5 (Fig. results): field
/// mIoU against execution time of lawnmowers flown at several GSDs, and the front margin of a
/// strategy over it (method.md §5). Eigen- and OpenCV-free: the decision function uses it too.

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
  if (time_s <= curve.front().time_s) return miou - curve.front().miou;
  if (time_s >= curve.back().time_s) return miou - curve.back().miou;
  for (std::size_t k = 1; k < curve.size(); ++k) {
    if (time_s <= curve[k].time_s) {
      const CurvePoint& a = curve[k - 1];
      const CurvePoint& b = curve[k];
      const double t = b.time_s > a.time_s ? (time_s - a.time_s) / (b.time_s - a.time_s) : 1.0;
      return miou - (a.miou + t * (b.miou - a.miou));
    }
  }
  return miou - curve.back().miou;  // unreachable
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
  if (gsd_cm <= points.front().gsd_cm) return points.front().miou;
  if (gsd_cm >= points.back().gsd_cm) return points.back().miou;
  std::size_t k = 1;
  while (gsd_cm > points[k].gsd_cm) ++k;
  const GsdPoint& a = points[k - 1];
  const GsdPoint& b = points[k];
  const double t = b.gsd_cm > a.gsd_cm ? (gsd_cm - a.gsd_cm) / (b.gsd_cm - a.gsd_cm) : 1.0;
  return a.miou + t * (b.miou - a.miou);
}

}  // namespace adaptseg
