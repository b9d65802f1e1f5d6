#pragma once
/// @file
/// What the front-aware rule (front_aware_policy.hpp) is set with beside its gain model: how it
/// chooses its top level, which lawnmower curve a descent is compared with, what the folds of its
/// calibration measured per descent GSD, and the training fields' lawnmower curves.

#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// How the front-aware rule chooses the GSD of its top level among those it was calibrated for
/// (FrontAwarePolicy::top_gsd; the lawnmower times are this field's, the accuracies the training
/// fields' lawnmower curves at the same GSD, so no label of this field is read):
/// - `undominated`: the one whose lawnmower falls least short of the faster lawnmowers, the
///   shortfall taken on each training field's curve and averaged (where they tie the fastest,
///   then the coarsest: where no lawnmower is faster, the nominal one);
/// - `hull`: from there, a finer one while the predicted curve rises faster per second up to it
///   than from it to any finer lawnmower: the top level at the first corner of the predicted
///   curve's upper concave hull. A descent is judged against the curve's upper envelope, whose
///   segments are the lawnmowers' rates; where the curve rises steeply to a GSD for little time
///   (a finer lawnmower whose grid fits the field better) and flattens after it, descents from
///   the coarser level must beat the steep segment, those from the corner only the flatter one.
enum class TopLevelChoice { undominated, hull };

/// Every top-level choice by name (`top_level` in the model file, `--top-level` of the programs).
inline constexpr std::array<detail::NamedValue<TopLevelChoice>, 2> kTopLevelChoices{{
    {TopLevelChoice::undominated, "undominated"},
    {TopLevelChoice::hull, "hull"},
}};

/// The name of a top-level choice.
[[nodiscard]] inline std::string to_string(TopLevelChoice r) {
  return detail::name_of(kTopLevelChoices, r, "top-level choice");
}

/// Parses a top-level choice's name.
/// @throws std::invalid_argument for anything but `undominated` or `hull`.
[[nodiscard]] inline TopLevelChoice parse_top_level_choice(std::string_view name) {
  return detail::value_named(kTopLevelChoices, name, "top-level choice");
}

/// The lawnmower curve a descent is compared with (FrontAwarePolicy::Params::curve, `--curve`):
/// - `training`: the training fields' own curves (the lawnmowers' times this field's);
/// - `field`: with a cell gain model, this field's curve as the model predicts it (what
///   re-mapping the whole field at each lawnmower GSD would gain, from the field's mean input
///   estimated from its top-level images so far). The field factor s and σ̂ then scale the
///   descent's gain and the curve's rise alike;
/// - `corrected`: that prediction corrected by what the training fields' real lawnmowers did.
///   For each training field f and lawnmower GSD g, its real rise from the top GSD against the
///   rise the cell gain model predicts for it, r_f = (D_f(g) − D_f(top)) / (β(top, g)·X_f / σ_f),
///   clamped to [1/4, 4] (1 where f's X_f or σ_f is unknown or nothing is predicted), scales this
///   field's predicted rise to g: one curve per training field, their mean the curve a descent
///   is compared with and their spread the sd_D of the lower bound. Single cells re-mapped alone
///   inside a coarse map, which the model is fitted on, predict a network's lawnmower poorly: it
///   re-maps every cell with its neighbours (docs/results.md, "The field curve against the real
///   ones").
/// - `mixture`: the `corrected` curves and the training fields' own together, one curve per
///   training field from each: their mean rise the one a descent must beat and their spread its
///   sd_D, so that where the two estimates of this field's curve disagree the lower bound is as
///   unsure as their disagreement (on new ground the training fields' real curves predict a
///   descent's real rise better, the corrected ones the oracle's). Flown on the
///   leave-one-tile-out runs it did worse than either: the calibration's folds answer the wider
///   spread with z = 0 (docs/journal/2026-12-loto.md, fortieth session).
/// Without a cell gain model `field`, `corrected` and `mixture` read the training fields' curves.
enum class CurveSource { training, field, corrected, mixture };

/// Every curve source by name (`--curve` of the programs; the model file keeps the flags
/// `field_curve` and `curve_ratio` of earlier versions and `curve_mixture`, docs/data_format.md).
inline constexpr std::array<detail::NamedValue<CurveSource>, 4> kCurveSources{{
    {CurveSource::training, "training"},
    {CurveSource::field, "field"},
    {CurveSource::corrected, "corrected"},
    {CurveSource::mixture, "mixture"},
}};

/// The name of a curve source.
[[nodiscard]] inline std::string to_string(CurveSource c) { return detail::name_of(kCurveSources, c, "curve source"); }

/// Parses a curve source's name.
/// @throws std::invalid_argument for anything but `training`, `field`, `corrected` or `mixture`.
[[nodiscard]] inline CurveSource parse_curve_source(std::string_view name) {
  return detail::value_named(kCurveSources, name, "curve source");
}

/// What the front-aware rule's field factor s (FieldScale: how much more or less than forecast
/// a closer look gains on this field) learns from, and what it scales
/// (FrontAwarePolicy::Params::field_factor, `field_factor` in the model file, `--field-factor`):
/// - `scene-check`: with a cell gain model, from each descent's scene check (the finer images'
///   input against the top-level one's; CellGainModel::proxy_gain); it scales the descent's
///   forecast gain and, with the field's own curve, the curve's rise alike (at z = 0 it then
///   changes a decision only by its sign). Without a cell gain model, from χ as below;
/// - `relabelled`: from each descent's relabelled share of its region with L involved (χ,
///   observable without ground truth) against the cell gain model's forecast of it; it scales
///   the descent's forecast gain only, and the predicted curve keeps the training fields'
///   anchor. On the leave-one-tile-out runs a field's gain per unit of input and its relabelled
///   share per unit of input move together for building, while the field's real lawnmower rise
///   did not follow the descents' gains (docs/method.md, "The field factor from what a descent
///   relabelled", with what it measured); how far the gain follows s is
///   FrontAwareParams::relabel_transfer (1: whole).
enum class FieldFactorSource { scene_check, relabelled };

/// Every field-factor source by name.
inline constexpr std::array<detail::NamedValue<FieldFactorSource>, 2> kFieldFactorSources{{
    {FieldFactorSource::scene_check, "scene-check"},
    {FieldFactorSource::relabelled, "relabelled"},
}};

/// The name of a field-factor source.
[[nodiscard]] inline std::string to_string(FieldFactorSource f) {
  return detail::name_of(kFieldFactorSources, f, "field-factor source");
}

/// Parses a field-factor source's name.
/// @throws std::invalid_argument for anything but `scene-check` or `relabelled`.
[[nodiscard]] inline FieldFactorSource parse_field_factor_source(std::string_view name) {
  return detail::value_named(kFieldFactorSources, name, "field-factor source");
}

/// How much of its forecast field gain a descent to one GSD realised when the training fields
/// were flown as new ground (FrontAwarePolicy::Params::gain_ratios; calibrate() with
/// CalibrationOptions::gain_ratios measures it).
struct GainRatio {
  double gsd_cm = 0.0;  ///< the descent GSD [cm/px]
  double ratio = 1.0;   ///< realised / forecast field gain, >= 0

  /// @throws std::invalid_argument for a GSD <= 0 or a ratio < 0 or not finite.
  void validate() const {
    detail::require(std::isfinite(gsd_cm) && gsd_cm > 0.0,
                    "FrontAwarePolicy::Params::gain_ratios: a GSD must be finite and > 0", gsd_cm);
    detail::require(std::isfinite(ratio) && ratio >= 0.0,
                    "FrontAwarePolicy::Params::gain_ratios: a ratio must be finite and >= 0", ratio);
  }
};

/// How far descents to one GSD ended above their forecast margin, per second of descent, when
/// the training fields were flown as new ground (FrontAwarePolicy::Params::margin_biases;
/// calibrate() with CalibrationOptions::margin_biases measures it): the error of the gain and of
/// the lawnmower curve's rise together, which is what decides whether a descent pays.
struct MarginBias {
  double gsd_cm = 0.0;  ///< the descent GSD [cm/px]
  double per_s = 0.0;   ///< (realised − forecast margin) per second of the descent's extra time

  /// @throws std::invalid_argument for a GSD <= 0 or a bias that is not finite.
  void validate() const {
    detail::require(std::isfinite(gsd_cm) && gsd_cm > 0.0,
                    "FrontAwarePolicy::Params::margin_biases: a GSD must be finite and > 0", gsd_cm);
    detail::require(std::isfinite(per_s), "FrontAwarePolicy::Params::margin_biases: a bias must be finite", per_s);
  }
};

/// The factor on the forecast gain of a descent to `gsd_cm` in `ratios` (1 where none is listed).
[[nodiscard]] inline double gain_ratio_at(std::span<const GainRatio> ratios, double gsd_cm) noexcept {
  for (const GainRatio& r : ratios)
    if (std::abs(r.gsd_cm - gsd_cm) <= 1e-9 * gsd_cm) return r.ratio;
  return 1.0;
}

/// The margin bias per second of a descent to `gsd_cm` in `biases` (0 where none is listed).
[[nodiscard]] inline double margin_bias_at(std::span<const MarginBias> biases, double gsd_cm) noexcept {
  for (const MarginBias& b : biases)
    if (std::abs(b.gsd_cm - gsd_cm) <= 1e-9 * gsd_cm) return b.per_s;
  return 0.0;
}

/// A training field's fixed-altitude lawnmower curve by GSD: the front-aware rule's yardstick.
struct ReferenceCurve {
  std::string field;             ///< the training field's name
  std::vector<GsdPoint> points;  ///< field mIoU over L by lawnmower GSD
  /// σ of the field's top-level map (its share of L as the UAV sees it); 0: unknown. The mean
  /// over the reference curves is the prior of a new field's σ.
  double field_sigma = 0.0;
  /// The mean over the field's top-level images of the cell gain model's input (its value per
  /// field pixel); 0: unknown (models without cells). The mean over the reference curves is the
  /// prior of a new field's (CurveSource::field). At the nominal top-level GSD.
  double field_input = 0.0;
  /// The same mean at every top-level GSD the cell gain model was calibrated for (the nominal
  /// one and finer ones the rule may choose, ChoosesTopLevel), as (GSD, input) pairs: a finer
  /// top level's map has less wrong, so its input is smaller. Empty (models before it):
  /// `field_input` at every top.
  std::vector<std::pair<double, double>> top_inputs{};

  /// @throws std::invalid_argument naming the field: no point, a point with a GSD <= 0 or a
  ///         non-finite mIoU, `field_sigma` outside [0, 1], `field_input` < 0 or not finite, a
  ///         `top_inputs` entry with a GSD <= 0 or an input < 0.
  void validate() const {
    const std::string curve = "reference curve '" + field + "'";
    detail::require(!points.empty(), curve + " has no point; count", points.size());
    for (const auto& p : points)
      detail::require(std::isfinite(p.gsd_cm) && p.gsd_cm > 0.0 && std::isfinite(p.miou),
                      curve + " needs GSD > 0 and finite mIoU; GSD", p.gsd_cm);
    detail::require(std::isfinite(field_sigma) && field_sigma >= 0.0 && field_sigma <= 1.0,
                    curve + " needs field_sigma in [0, 1]", field_sigma);
    detail::require(std::isfinite(field_input) && field_input >= 0.0, curve + " needs field_input >= 0", field_input);
    for (const auto& [g, x] : top_inputs)
      detail::require(std::isfinite(g) && g > 0.0 && std::isfinite(x) && x >= 0.0,
                      curve + " needs top_inputs of GSD > 0 and input >= 0; GSD", g);
  }

  /// The field's mean input at top-level GSD `top_gsd_cm`: its `top_inputs` entry, else
  /// `field_input`.
  [[nodiscard]] double input_at(double top_gsd_cm) const {
    for (const auto& [g, x] : top_inputs)
      if (detail::same_gsd(g, top_gsd_cm)) return x;
    return field_input;
  }
};

/// CurveSource::corrected's r_f: training field `r`'s real lawnmower rise from GSD `top` to `g`
/// over the one the cell gain model predicts for it, slope·X_f / σ_f (X_f at `top`, `slope` the
/// model's β(top, g)); clamped to [1/4, 4]; 1 where nothing is predicted.
[[nodiscard]] inline double corrected_rise_ratio(const ReferenceCurve& r, double top, double g, double slope) {
  const double predicted = r.field_sigma > 0.0 ? slope * r.input_at(top) / r.field_sigma : 0.0;
  if (!(predicted > 0.0)) return 1.0;
  const double real = miou_at_gsd(r.points, g) - miou_at_gsd(r.points, top);
  return std::clamp(real / predicted, 0.25, 4.0);
}

namespace detail {
/// The mean over `curves` of their mIoU at `t` (miou_at_time(): as the front margin reads them).
[[nodiscard]] inline double mean_curve_miou(const std::vector<std::vector<CurvePoint>>& curves, double t) {
  double s = 0.0;
  for (const auto& c : curves) s += miou_at_time(c, t);
  return s / static_cast<double>(curves.size());
}

/// The rise of `curves` over a descent of `extra_s` from `t0` (rising_miou_at_time(), as the
/// front-aware rule reads them): mean ΔD̄ over the curves and its variance sd_D² between them
/// (0 with one curve).
[[nodiscard]] inline std::pair<double, double> curve_rise(const std::vector<std::vector<CurvePoint>>& curves, double t0,
                                                          double extra_s) {
  double rise_sum = 0.0, rise_sq = 0.0;
  for (const auto& curve : curves) {
    const double rise = rising_miou_at_time(curve, t0 + extra_s) - rising_miou_at_time(curve, t0);
    rise_sum += rise;
    rise_sq += rise * rise;
  }
  const double n = static_cast<double>(curves.size());
  const double rise = rise_sum / n;
  return {rise, curves.size() > 1 ? std::max(0.0, (rise_sq - n * rise * rise) / (n - 1.0)) : 0.0};
}
}  // namespace detail

/// The front-aware rule's behaviour (FrontAwarePolicy::Params; the class comment there says what
/// each setting does); validated by FrontAwarePolicy's constructor.
struct FrontAwareParams {
  double min_sigma = 0.0;            ///< σ below which the UAV never descends
  bool online = true;                ///< field correction and O's update (false: non-adaptive)
  double confidence = 0.0;           ///< z >= 0 of the lower bound
  double scale_prior_sd = 0.5;       ///< ω > 0, prior spread of the field factor s
  double sigma_prior_weight = 0.25;  ///< k > 0: weight of the training fields' σ in σ̂ [fields]
  double sigma_prior_sd = 0.0;       ///< τ >= 0: spread of a field's σ about the training fields' mean
  double curve_agreement = 0.0;      ///< q in [0, 1]; 0: no such check
  /// The finest GSD a descent may fly [cm/px] (CalibrationOptions::finest_descent_gsd_cm, the
  /// training folds' choice); candidates finer than it are assessed and reported, never taken.
  /// 0: any candidate.
  double finest_descent_gsd_cm = 0.0;
  /// The most extra seconds a descent may cost (CalibrationOptions::longest_descent_s, the
  /// training folds' choice); longer candidates are assessed and reported, never taken. 0: any.
  double longest_descent_s = 0.0;
  /// The jump guard's bound (JumpGuard; adaptive and non-adaptive alike; infinity: none):
  /// after a descent image beyond it the UAV descends no more (trusts_descent_image()).
  double jump_bound = std::numeric_limits<double>::infinity();
  /// The lawnmower curve a descent is compared with (CurveSource; `corrected` is the
  /// programs' default, this struct's the training fields' curves).
  CurveSource curve = CurveSource::training;
  /// How top_gsd() chooses the top level (TopLevelChoice).
  TopLevelChoice top_level = TopLevelChoice::undominated;
  /// What the field factor s learns from and scales (FieldFactorSource).
  FieldFactorSource field_factor = FieldFactorSource::scene_check;
  /// b in [0, 1], with `field_factor` relabelled: the descent's gain is scaled by 1 + b·(s − 1),
  /// s learnt from the relabelled share, b how far a field's gain factor moved with its
  /// relabelled factor on the training fields (relabel_transfer(); 1: by s itself, 0: not at all).
  double relabel_transfer = 1.0;
  /// τ_r >= 0, with `field_factor` relabelled: how far one region's relabelled share strays from
  /// its field's factor, relative to the forecast (relabel_region_sd()); each descent's χ then
  /// tells s with the variance (τ_r·μ)² beside its cells' own spread, so that one region that
  /// relabels more or less than its field does not carry s with it. 0: the cells' spread alone.
  double relabel_region_sd = 0.0;
  /// ω_χ >= 0, with `field_factor` relabelled: the prior spread of s, how far a field's
  /// relabelled share strays from the forecast between the training fields (relabel_field_sd());
  /// the gain's factor keeps its own prior spread ω (`scale_prior_sd`), of which s explains
  /// b·ω_χ (FieldScale::transferred). 0: s's prior spread is ω.
  double relabel_field_sd = 0.0;
  /// With `online`: what the field factor learns may only stop descents, never add one
  /// (FrontAwarePolicy's class comment): each candidate's lower bound is capped by the
  /// non-adaptive rule's in the same context.
  bool learn_stop_only = false;
  /// Per descent GSD, the factor on a candidate's forecast field gain (mean and spread): what
  /// descents to it realised of their forecast on the training fields, each flown with a model
  /// that never saw it (CalibrationOptions::gain_ratios). Not listed: 1. Empty: none.
  std::vector<GainRatio> gain_ratios{};
  /// Per descent GSD, b: what descents to it ended above their forecast margin per second on
  /// the training fields flown so (CalibrationOptions::margin_biases); b·T is added to a
  /// candidate's margin (ĝ − ΔD̄), its spread unchanged. Not listed: 0. Empty: none.
  std::vector<MarginBias> margin_biases{};

  /// @throws std::invalid_argument naming the field.
  void validate() const {
    detail::require(std::isfinite(min_sigma) && min_sigma >= 0.0 && min_sigma <= 1.0,
                    "FrontAwarePolicy::Params::min_sigma must be in [0, 1]", min_sigma);
    detail::require(std::isfinite(confidence) && confidence >= 0.0,
                    "FrontAwarePolicy::Params::confidence must be finite and >= 0", confidence);
    detail::require(std::isfinite(scale_prior_sd) && scale_prior_sd > 0.0,
                    "FrontAwarePolicy::Params::scale_prior_sd must be finite and > 0", scale_prior_sd);
    detail::require(std::isfinite(sigma_prior_weight) && sigma_prior_weight > 0.0,
                    "FrontAwarePolicy::Params::sigma_prior_weight must be finite and > 0", sigma_prior_weight);
    detail::require(std::isfinite(sigma_prior_sd) && sigma_prior_sd >= 0.0 && sigma_prior_sd <= 1.0,
                    "FrontAwarePolicy::Params::sigma_prior_sd must be in [0, 1]", sigma_prior_sd);
    detail::require(std::isfinite(curve_agreement) && curve_agreement >= 0.0 && curve_agreement <= 1.0,
                    "FrontAwarePolicy::Params::curve_agreement must be in [0, 1]", curve_agreement);
    detail::require(std::isfinite(finest_descent_gsd_cm) && finest_descent_gsd_cm >= 0.0,
                    "FrontAwarePolicy::Params::finest_descent_gsd_cm must be finite and >= 0", finest_descent_gsd_cm);
    detail::require(std::isfinite(longest_descent_s) && longest_descent_s >= 0.0,
                    "FrontAwarePolicy::Params::longest_descent_s must be finite and >= 0", longest_descent_s);
    detail::require(!std::isnan(jump_bound), "FrontAwarePolicy::Params::jump_bound must not be NaN", jump_bound);
    detail::require(std::isfinite(relabel_transfer) && relabel_transfer >= 0.0 && relabel_transfer <= 1.0,
                    "FrontAwarePolicy::Params::relabel_transfer must be in [0, 1]", relabel_transfer);
    detail::require(std::isfinite(relabel_region_sd) && relabel_region_sd >= 0.0,
                    "FrontAwarePolicy::Params::relabel_region_sd must be finite and >= 0", relabel_region_sd);
    detail::require(std::isfinite(relabel_field_sd) && relabel_field_sd >= 0.0,
                    "FrontAwarePolicy::Params::relabel_field_sd must be finite and >= 0", relabel_field_sd);
    for (const GainRatio& r : gain_ratios) r.validate();
    for (const MarginBias& b : margin_biases) b.validate();
  }
};

/// The share of the training fields in `reference` whose lawnmower at GSD `g` mapped better than
/// theirs at the top level `top` (FrontAwarePolicy::Params `curve_agreement`); 0 without any.
[[nodiscard]] inline double finer_lawnmower_share(std::span<const ReferenceCurve> reference, double top, double g) {
  std::size_t finer = 0;
  for (const auto& r : reference)
    if (miou_at_gsd(r.points, g) > miou_at_gsd(r.points, top)) ++finer;
  return reference.empty() ? 0.0 : static_cast<double>(finer) / static_cast<double>(reference.size());
}

}  // namespace adaptseg
