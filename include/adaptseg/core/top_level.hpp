#pragma once
/// @file
/// The top level a front-aware mission flies (TopLevelChoice): chosen from this field's
/// lawnmower times, known from its geometry before flying, and the training fields' lawnmower
/// curves at the same GSDs; no label of this field is read.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/front_aware_settings.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

namespace adaptseg {

namespace detail {

/// The time of the lawnmower at GSD `g` among `lawnmowers`; infinite where there is none (the
/// nominal top level without a forecast: never dominated).
[[nodiscard]] inline double lawnmower_time(std::span<const LawnmowerForecast> lawnmowers, double g) {
  for (const auto& l : lawnmowers)
    if (l.gsd_cm == g) return l.time_s;
  return std::numeric_limits<double>::infinity();
}

/// The training fields' mean lawnmower mIoU at GSD `g`.
[[nodiscard]] inline double mean_reference_miou(std::span<const ReferenceCurve> reference, double g) {
  double m = 0.0;
  for (const auto& r : reference) m += miou_at_gsd(r.points, g);
  return m / static_cast<double>(reference.size());
}

/// How far the lawnmowers of `lawnmowers` as fast as GSD `g`'s or faster map better than it:
/// on each training field's curve the most any of them does (0 if none), averaged over the
/// fields.
[[nodiscard]] inline double top_level_shortfall(std::span<const ReferenceCurve> reference,
                                                std::span<const LawnmowerForecast> lawnmowers, double g) {
  const double time_g = lawnmower_time(lawnmowers, g);
  double sum = 0.0;
  for (const auto& r : reference) {
    double worst = 0.0;
    for (const auto& l : lawnmowers)
      if (l.time_s <= time_g) worst = std::max(worst, miou_at_gsd(r.points, l.gsd_cm) - miou_at_gsd(r.points, g));
    sum += worst;
  }
  return sum / static_cast<double>(reference.size());
}

/// TopLevelChoice::hull from `start`: a finer GSD of `allowed` (coarse to fine) while the
/// predicted curve rises faster per second up to it than from it to any finer, slower
/// lawnmower of `lawnmowers`.
[[nodiscard]] inline double hull_top_gsd(std::span<const ReferenceCurve> reference, std::span<const double> allowed,
                                         std::span<const LawnmowerForecast> lawnmowers, double start) {
  double best = start;
  for (double g : allowed) {
    const double t0 = lawnmower_time(lawnmowers, best), t1 = lawnmower_time(lawnmowers, g);
    if (!(g < best) || !std::isfinite(t1) || !std::isfinite(t0)) continue;
    // The rise per second up to g, and the steepest from g to a finer, slower lawnmower.
    const double rise = mean_reference_miou(reference, g) - mean_reference_miou(reference, best);
    const double rate_to = t1 > t0 ? rise / (t1 - t0) : (rise > 0.0 ? std::numeric_limits<double>::infinity() : rise);
    double rate_on = 0.0;
    for (const auto& l : lawnmowers)
      if (l.gsd_cm < g && l.time_s > t1)
        rate_on = std::max(
            rate_on, (mean_reference_miou(reference, l.gsd_cm) - mean_reference_miou(reference, g)) / (l.time_s - t1));
    if (!(rate_to > rate_on)) break;
    best = g;
  }
  return best;
}

}  // namespace detail

/// The GSD to fly the top level at, among `allowed` (sorted coarse to fine, each a GSD of
/// `lawnmowers` or `nominal`): the one whose lawnmower over the area falls least short of the
/// lawnmowers of `lawnmowers` as fast or faster, on each training field's curve of `reference`
/// the most any of them maps better (0 if none), averaged over the fields; where they tie the
/// fastest, then the coarsest (`nominal` where `allowed` is empty): a slower top level that
/// the training curves cannot tell from a faster one can still fall short on this field (its
/// network may map the coarser GSD worse here), the fastest cannot. The margin a mission is
/// judged by is exactly such a shortfall against the curve's upper envelope, and it is taken field by field because
/// the fields' curves cross: a network on ground it never saw maps one field better at 12.5
/// cm/px than at 15 and the next worse, so the shortfall of their mean curve can be 0 where
/// flying the coarser, slower lawnmower loses on some of them. With TopLevelChoice::hull, then
/// a finer one of them while the predicted curve rises faster per second up to it than from it
/// to any finer lawnmower of `lawnmowers`.
/// @pre `reference` is not empty.
[[nodiscard]] inline double choose_top_gsd(std::span<const ReferenceCurve> reference, std::span<const double> allowed,
                                           std::span<const LawnmowerForecast> lawnmowers, double nominal,
                                           TopLevelChoice choice) {
  double best = nominal, best_shortfall = std::numeric_limits<double>::infinity();
  for (double g : allowed) {
    const double v = detail::top_level_shortfall(reference, lawnmowers, g);
    const bool tie = std::abs(v - best_shortfall) <= 1e-12;
    if (v < best_shortfall - 1e-12 ||
        (tie && detail::lawnmower_time(lawnmowers, g) < detail::lawnmower_time(lawnmowers, best)))
      best = g, best_shortfall = v;
  }
  return choice == TopLevelChoice::hull ? detail::hull_top_gsd(reference, allowed, lawnmowers, best) : best;
}

}  // namespace adaptseg
