#pragma once
/// @file
/// The fixed-altitude lawnmower curve, the yardstick of the paper's §5 (Fig. results): field
/// mIoU against execution time of lawnmowers flown at several GSDs, and the front margin of a
/// strategy over it (docs/method.md, "Decisions where the paper is silent, and departures"). Eigen-
/// and OpenCV-free: the decision function uses it too.

#include <adaptseg/core/detail/interpolate.hpp>
#include <adaptseg/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

namespace adaptseg {

/// One point of a fixed-altitude lawnmower curve: execution time [s] and field mIoU.
struct CurvePoint {
  double time_s = 0.0;
  double miou = 0.0;
};

/// The curve's upper envelope: its running maximum over time, as points (sorted by time) whose
/// linear interpolation, flat beyond the ends, is `max over t' <= t of curve(t')`. A lawnmower
/// that is slower *and* maps worse than a faster one is not an alternative anybody would fly:
/// beyond it the best map so far stays on offer. Where the
/// curve rises with time the envelope is the curve.
/// @throws std::invalid_argument for an empty curve or non-finite values.
[[nodiscard]] inline std::vector<CurvePoint> upper_envelope(std::vector<CurvePoint> curve) {
  detail::require(!curve.empty(), "upper_envelope: the lawnmower curve is empty", 0);
  for (const CurvePoint& p : curve)
    detail::require(std::isfinite(p.time_s) && std::isfinite(p.miou), "upper_envelope: time and mIoU must be finite",
                    p.time_s);
  std::stable_sort(curve.begin(), curve.end(),
                   [](const CurvePoint& a, const CurvePoint& b) { return a.time_s < b.time_s; });
  std::vector<CurvePoint> env{curve.front()};
  double best = curve.front().miou;
  for (std::size_t k = 1; k < curve.size(); ++k) {
    const CurvePoint& a = curve[k - 1];
    const CurvePoint& b = curve[k];
    if (!(b.miou > best)) continue;  // the envelope stays flat at `best`
    // The segment a -> b climbs back through `best`: the envelope leaves its flat part there.
    if (a.miou < best && b.time_s > a.time_s)
      env.push_back({a.time_s + (best - a.miou) / (b.miou - a.miou) * (b.time_s - a.time_s), best});
    env.push_back(b);
    best = b.miou;
  }
  return env;
}

/// mIoU of a curve sorted by time (a lawnmower curve or its upper_envelope()) at `time_s`:
/// linear between its points, flat beyond its ends. How front_margin() reads the envelope.
/// @throws std::invalid_argument for an empty curve.
[[nodiscard]] inline double miou_at_time(const std::vector<CurvePoint>& curve, double time_s) {
  return detail::interpolate_flat(curve, time_s, &CurvePoint::time_s, &CurvePoint::miou);
}

/// A curve's mIoU at `time_s` as a descent has to beat it (FrontAwarePolicy): as miou_at_time(),
/// but beyond the last point (a mission slower than the finest lawnmower) the last segment goes
/// on if it rises (never below the last point: the finest lawnmower can always be flown), capped
/// at 1. There a descent must still beat what the finest lawnmowers bought per second; read
/// flat, any positive gain would beat it however long the descent.
/// @throws std::invalid_argument for an empty curve.
[[nodiscard]] inline double rising_miou_at_time(const std::vector<CurvePoint>& curve, double time_s) {
  return std::min(1.0, detail::interpolate_extend(curve, time_s, &CurvePoint::time_s, &CurvePoint::miou));
}

/// Front margin (paper §5, docs/method.md, "Decisions where the paper is silent, and departures"):
/// `miou` minus the lawnmower curve's **upper envelope**
/// (upper_envelope(): the best lawnmower at `time_s` or sooner) linearly interpolated at
/// `time_s`, flat beyond its ends. Positive: the strategy lies above every lawnmower that is
/// not slower (more accuracy for its time than flying one altitude everywhere). Where the
/// curve falls with time (a network that maps worse from lower down) the raw curve would reward
/// a mission for being slower; curve_front_margin() is that reading, reported beside it.
/// @throws std::invalid_argument for an empty curve or non-finite values.
[[nodiscard]] inline double front_margin(std::vector<CurvePoint> curve, double time_s, double miou) {
  detail::require(std::isfinite(time_s) && std::isfinite(miou), "front_margin: time and mIoU must be finite", time_s);
  const std::vector<CurvePoint> env = upper_envelope(std::move(curve));
  return miou - miou_at_time(env, time_s);
}

/// The front margin against the curve itself (linear between its points, flat beyond its ends),
/// as the paper reads Fig. results; equal to front_margin() wherever the curve rises with time.
/// @throws std::invalid_argument for an empty curve or non-finite values.
[[nodiscard]] inline double curve_front_margin(std::vector<CurvePoint> curve, double time_s, double miou) {
  detail::require(!curve.empty(), "curve_front_margin: the lawnmower curve is empty", 0);
  detail::require(std::isfinite(time_s) && std::isfinite(miou), "curve_front_margin: time and mIoU must be finite",
                  time_s);
  std::sort(curve.begin(), curve.end(), [](const CurvePoint& a, const CurvePoint& b) { return a.time_s < b.time_s; });
  return miou - miou_at_time(curve, time_s);
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
