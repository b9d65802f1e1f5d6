#pragma once
/// @file
/// The front-aware decision rule (beyond the paper; docs/method.md): descend where a descent's
/// forecast gain beats what flying the whole field lower would have gained in the same time,
/// with the forecasts corrected in flight from what the descents actually changed.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/detail/interpolate.hpp>
#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gain_model.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// How the front-aware rule chooses the GSD of its top level among those it was calibrated for
/// (FrontAwarePolicy::top_gsd; the lawnmower times are this field's, the accuracies the training
/// fields' lawnmower curves at the same GSD, so no label of this field is read):
/// - `undominated`: the one whose lawnmower falls least short of the faster lawnmowers, the
///   shortfall taken on each training field's curve and averaged (the coarsest where they tie:
///   where no lawnmower is faster, the nominal one);
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
/// Without a cell gain model `field` and `corrected` read the training fields' curves.
enum class CurveSource { training, field, corrected };

/// Every curve source by name (`--curve` of the programs; the model file keeps the flags
/// `field_curve` and `curve_ratio` of earlier versions, docs/data_format.md).
inline constexpr std::array<detail::NamedValue<CurveSource>, 3> kCurveSources{{
    {CurveSource::training, "training"},
    {CurveSource::field, "field"},
    {CurveSource::corrected, "corrected"},
}};

/// The name of a curve source.
[[nodiscard]] inline std::string to_string(CurveSource c) { return detail::name_of(kCurveSources, c, "curve source"); }

/// Parses a curve source's name.
/// @throws std::invalid_argument for anything but `training`, `field` or `corrected`.
[[nodiscard]] inline CurveSource parse_curve_source(std::string_view name) {
  return detail::value_named(kCurveSources, name, "curve source");
}

/// How much of its forecast field gain a descent to one GSD realised when the training fields
/// were flown as new ground (FrontAwarePolicy::Params::gain_ratios; calibrate() with
/// CalibrationOptions::gain_ratios measures it).
struct GainRatio {
  double gsd_cm = 0.0;  ///< the descent GSD [cm/px]
  double ratio = 1.0;   ///< realised / forecast field gain, >= 0
};

/// How far descents to one GSD ended above their forecast margin, per second of descent, when
/// the training fields were flown as new ground (FrontAwarePolicy::Params::margin_biases;
/// calibrate() with CalibrationOptions::margin_biases measures it): the error of the gain and of
/// the lawnmower curve's rise together, which is what decides whether a descent pays.
struct MarginBias {
  double gsd_cm = 0.0;  ///< the descent GSD [cm/px]
  double per_s = 0.0;   ///< (realised − forecast margin) per second of the descent's extra time
};

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

  /// The field's mean input at top-level GSD `top_gsd_cm`: its `top_inputs` entry, else
  /// `field_input`.
  [[nodiscard]] double input_at(double top_gsd_cm) const {
    for (const auto& [g, x] : top_inputs)
      if (detail::same_gsd(g, top_gsd_cm)) return x;
    return field_input;
  }
};

/// The front-aware rule over a GainModel; a DecisionPolicy.
///
/// The paper's utility G / T says nothing about what else the UAV could have done with the
/// time. This rule measures a descent against exactly that: the fixed-altitude lawnmowers over
/// the field being flown, at the top and candidate GSDs (DecisionContext::lawnmowers: times
/// known from the geometry before flying). Their accuracy comes from the training fields'
/// lawnmower curves at the same GSD (GSD transfers between fields of one kind, time does not):
/// each training field gives a predicted lawnmower curve for the field being flown.
///
/// At a top-level image of σ over a region whose share of the field's ground is a:
/// - T0 = elapsed + rest of the top-level coverage: the mission's end if it descends no more;
/// - per candidate, the descent's field-level gain ĝ = η · s · μ_C · a / σ̂ (GainModel: μ_C the
///   share of the region's pixels the descent relabels, η the field gain per relabelled share;
///   s the field correction below), with variance (η·a/σ̂)²·(s²·sd_C² + Var(s)·μ_C²) plus
///   σ̂'s (below). Field mIoU counts a class's pixels over the whole field, so a corrected
///   pixel is worth 1 / (the field's pixels of L): σ̂ estimates the field's σ from the
///   top-level images so far (area weighted), the part not yet seen taken at their σ shrunk
///   towards the training fields' mean σ with a weight of k = `sigma_prior_weight` fields;
/// - σ̂'s own uncertainty (a hierarchical model: the field's mean σ spread τ = `sigma_prior_sd`
///   about the training fields' mean, the mean of a seen share S spread v / S about the field's,
///   v = k·τ²): Var σ̂ = (1 − S)²·τ²·k / (k + S) + (1 − S)·v, zero once the field is seen; it
///   enters Var ĝ as ĝ²·Var σ̂ / σ̂² (delta method). τ = 0 (one training field; model files
///   without `sigma_prior_sd`): none, the default. Calibration can estimate τ, or k and τ, on
///   several training fields (CalibrationOptions::sigma_prior; measured in docs/results.md);
/// - the curve's rise ΔD over the descent's extra time, [T0, T0 + T], on the upper envelope
///   (upper_envelope(): never falling) of each training field's predicted curve: mean ΔD̄ and
///   spread sd_D over the training fields; beyond the curve's last point its last segment goes
///   on (rising_curve_miou);
/// - the descent is worth its time if its lower bound (ĝ − ΔD̄ + b·T) − z·sqrt(Var ĝ + sd_D²) > 0
///   (z = `confidence`, chosen on training fields; 0: the forecasts' means; b the margin bias
///   per second of a descent to the candidate's GSD, `margin_biases`, 0 unless calibrated with
///   them). The UAV descends
///   to the candidate of largest lower bound, if σ >= `min_sigma`. Since ΔD̄ grows with T0, it
///   descends while descents beat flying lower everywhere, and stops when they no longer do.
///
/// Field correction (`online`; beyond the paper, §3.2.3's idea applied to what is observable):
/// a descent's relabelled share χ (Relabelling::interest_share, the region's field pixels whose
/// label changed with a label of interest involved) needs no ground truth. C forecasts it; on
/// this field the truth is taken to be χ = s·μ_C + ε with one field factor s (prior N(1, ω²),
/// ω = `scale_prior_sd`; ε ~ N(0, sd_C²), C's predictive spread of one region) and the same
/// factor on the gains, the gain being paid by the relabelled pixels. After each descent s's
/// posterior is updated (conjugate Gaussian): descents that change less than forecast lower
/// ĝ and the UAV stops earlier; descents that change more raise it; each observation narrows
/// Var(s), so the lower bound rises as evidence accrues. Also the paper's update of O.
/// `online = false` (non-adaptive) keeps s = 1, Var(s) = ω² and O as initialised. The rule
/// needs C or a cell gain model (every calibrated model has C; models of adaptseg 0.1, which
/// forecast the gain from I alone, are no longer read since 0.2.0).
class FrontAwarePolicy {
 public:
  /// Behaviour; validated by the constructor.
  struct Params {
    double min_sigma = 0.0;            ///< σ below which the UAV never descends
    bool online = true;                ///< field correction and O's update (false: non-adaptive)
    double confidence = 0.0;           ///< z >= 0 of the lower bound (see class comment)
    double scale_prior_sd = 0.5;       ///< ω > 0, prior spread of the field factor s
    double sigma_prior_weight = 0.25;  ///< k > 0: weight of the training fields' σ in σ̂ [fields]
    double sigma_prior_sd = 0.0;       ///< τ >= 0: spread of a field's σ about the training fields' mean
    /// The lawnmower curve a descent is compared with (CurveSource; `corrected` is the
    /// programs' default, this struct's the training fields' curves).
    CurveSource curve = CurveSource::training;
    /// How top_gsd() chooses the top level (TopLevelChoice).
    TopLevelChoice top_level = TopLevelChoice::undominated;
    /// Per descent GSD, the factor on a candidate's forecast field gain (its mean and its
    /// spread): what the training fields, each flown with a model that never saw it, realised
    /// of what descents to that GSD were forecast to gain (calibrate() with
    /// CalibrationOptions::gain_ratios). A GSD not listed: 1. Empty (the default): none.
    std::vector<GainRatio> gain_ratios{};
    /// Per descent GSD, b: what descents to it ended above their forecast margin per second of
    /// their extra time on the training fields, each flown with a model that never saw it
    /// (calibrate() with CalibrationOptions::margin_biases); b·T is added to a candidate's
    /// margin (ĝ − ΔD̄), its spread unchanged. A GSD not listed: 0. Empty (the default): none.
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
      for (const GainRatio& r : gain_ratios) {
        detail::require(std::isfinite(r.gsd_cm) && r.gsd_cm > 0.0,
                        "FrontAwarePolicy::Params::gain_ratios: a GSD must be finite and > 0", r.gsd_cm);
        detail::require(std::isfinite(r.ratio) && r.ratio >= 0.0,
                        "FrontAwarePolicy::Params::gain_ratios: a ratio must be finite and >= 0", r.ratio);
      }
      for (const MarginBias& b : margin_biases) {
        detail::require(std::isfinite(b.gsd_cm) && b.gsd_cm > 0.0,
                        "FrontAwarePolicy::Params::margin_biases: a GSD must be finite and > 0", b.gsd_cm);
        detail::require(std::isfinite(b.per_s), "FrontAwarePolicy::Params::margin_biases: a bias must be finite",
                        b.per_s);
      }
    }

    /// The factor on the forecast gain of a descent to `gsd_cm` (1 where none is listed).
    [[nodiscard]] double gain_ratio(double gsd_cm) const noexcept {
      for (const GainRatio& r : gain_ratios)
        if (std::abs(r.gsd_cm - gsd_cm) <= 1e-9 * gsd_cm) return r.ratio;
      return 1.0;
    }

    /// The margin bias per second of a descent to `gsd_cm` (0 where none is listed).
    [[nodiscard]] double margin_bias(double gsd_cm) const noexcept {
      for (const MarginBias& b : margin_biases)
        if (std::abs(b.gsd_cm - gsd_cm) <= 1e-9 * gsd_cm) return b.per_s;
      return 0.0;
    }
  };

  /// @throws std::invalid_argument for invalid params, a model without C and without a cell gain
  ///         model, no reference curve, a curve without points, or a point with a GSD <= 0 or
  ///         a non-finite value.
  FrontAwarePolicy(GainModel model, std::vector<ReferenceCurve> reference, Params params)
      : initial_(std::move(model)), model_(initial_), reference_(std::move(reference)), params_(params) {
    params_.validate();
    detail::require(model_.c_model().has_value() || model_.cells().has_value(),
                    "FrontAwarePolicy: the gain model needs C or a cell gain model (what a descent relabels); C",
                    "absent");
    std::size_t with_sigma = 0;
    detail::require(!reference_.empty(), "FrontAwarePolicy: at least one reference lawnmower curve is needed; count",
                    reference_.size());
    for (const auto& r : reference_) {
      detail::require(!r.points.empty(), "FrontAwarePolicy: reference curve '" + r.field + "' has no point; count",
                      r.points.size());
      for (const auto& p : r.points)
        detail::require(std::isfinite(p.gsd_cm) && p.gsd_cm > 0.0 && std::isfinite(p.miou),
                        "FrontAwarePolicy: reference curve '" + r.field + "' needs GSD > 0 and finite mIoU; GSD",
                        p.gsd_cm);
      detail::require(std::isfinite(r.field_sigma) && r.field_sigma >= 0.0 && r.field_sigma <= 1.0,
                      "FrontAwarePolicy: reference curve '" + r.field + "' needs field_sigma in [0, 1]", r.field_sigma);
      if (r.field_sigma > 0.0) {
        prior_sigma_ += r.field_sigma / static_cast<double>(reference_.size());
        ++with_sigma;
      }
    }
    if (with_sigma != reference_.size()) prior_sigma_ = 0.0;  // unknown for some: the running mean of σ
    for (const auto& r : reference_) {
      detail::require(std::isfinite(r.field_input) && r.field_input >= 0.0,
                      "FrontAwarePolicy: reference curve '" + r.field + "' needs field_input >= 0", r.field_input);
      for (const auto& [g, x] : r.top_inputs)
        detail::require(
            std::isfinite(g) && g > 0.0 && std::isfinite(x) && x >= 0.0,
            "FrontAwarePolicy: reference curve '" + r.field + "' needs top_inputs of GSD > 0 and input >= 0; GSD", g);
    }
    begin_mission();
  }

  [[nodiscard]] std::string name() const { return params_.online ? "adaptive" : "nonadaptive"; }
  [[nodiscard]] const Params& params() const noexcept { return params_; }
  /// @throws std::invalid_argument for invalid params.
  void set_params(const Params& p) {
    p.validate();
    params_ = p;
  }
  [[nodiscard]] const std::vector<ReferenceCurve>& reference() const noexcept { return reference_; }
  /// The model as updated during the current mission.
  [[nodiscard]] const GainModel& model() const noexcept { return model_; }
  /// The model as given (what begin_mission restores).
  [[nodiscard]] const GainModel& initial_model() const noexcept { return initial_; }
  /// The field factor s: posterior mean and standard deviation so far in this mission.
  [[nodiscard]] double field_scale() const noexcept { return scale_mean_; }
  [[nodiscard]] double field_scale_sd() const noexcept { return std::sqrt(scale_var_); }

  void begin_mission() {
    model_ = initial_;
    sigma_sum_ = 0.0;
    sigma_count_ = 0;
    seen_share_ = 0.0;
    seen_interest_ = 0.0;
    seen_input_ = 0.0;
    seen_input_share_ = 0.0;
    forecast_gain_ = 0.0;
    chosen_.clear();
    scale_mean_ = 1.0;
    scale_var_ = params_.scale_prior_sd * params_.scale_prior_sd;
    scale_precision_sum_ = 0.0;
    scale_evidence_sum_ = 0.0;
  }

  /// @throws std::invalid_argument if the context has no lawnmower forecasts.
  [[nodiscard]] Decision decide(const DecisionContext& c) {
    detail::require(!c.lawnmowers.empty(),
                    "FrontAwarePolicy::decide: the context needs the field's lawnmower forecasts; count",
                    c.lawnmowers.size());
    // Each training field's lawnmower accuracy, placed at this field's lawnmower times: the
    // upper envelope of that predicted curve (the best lawnmower at a time or sooner, as the
    // front margin reads it), in time order (curve_miou and rising_curve_miou read it there).
    std::vector<std::vector<CurvePoint>> curves;
    for (const auto& r : reference_) {
      std::vector<CurvePoint> curve;
      for (const auto& f : c.lawnmowers) curve.push_back({f.time_s, miou_at_gsd(r.points, f.gsd_cm)});
      curves.push_back(upper_envelope(std::move(curve)));
    }
    sigma_sum_ += c.sigma;
    ++sigma_count_;
    seen_share_ += c.region_share;
    seen_interest_ += c.region_share * c.sigma;
    if (std::isfinite(c.region_input)) {
      seen_input_ += c.region_share * c.region_input;
      seen_input_share_ += c.region_share;
    }
    const auto [weight, sigma_cv2] = gain_weight(c);
    const double t0 = c.elapsed_s + c.rest_s;
    // The predicted curve's mIoU relative to the top level's (curve not `training`) or absolute.
    double curve_level = 0.0;
    if (params_.curve != CurveSource::training && model_.cells() && c.region_share > 0.0 && weight > 0.0) {
      const double x = field_input_estimate(c);
      curves.clear();
      if (params_.curve == CurveSource::corrected)
        for (const auto& r : reference_) curves.push_back(field_curve(c, x, weight / c.region_share, &r));
      else
        curves.push_back(field_curve(c, x, weight / c.region_share, nullptr));
      curve_level = mean_top_miou(c);
    }

    Decision d;
    std::optional<std::size_t> best_index;
    double best = 0.0;
    std::vector<double> gains;
    std::vector<Relabelled> forecasts;
    for (std::size_t k = 0; k < c.candidates.size(); ++k) {
      const Candidate& cand = c.candidates[k];
      const double delta_h = c.top_altitude_m - cand.altitude_m;
      const GainForecast f = model_.forecast(delta_h, c.sigma);
      CandidateScore s = scored(cand, f);
      // The descent's gain in shares of the region (its sd, and what it relabels): from its
      // cells (DescentCoverage::ranked), else from C and η.
      double base = 0.0, base_sd = 0.0;
      Relabelled relabelled;
      if (!cand.cells.empty() && model_.cells() && c.region_px > 0.0) {
        const CellGainModel::Forecast cf = model_.cells()->forecast(c.top_gsd_cm, cand.gsd_cm, cand.cells, c.region_px);
        base = cf.gain * weight;
        base_sd = std::sqrt(cf.gain_var) * weight;
        relabelled = {cf.relabelled, std::sqrt(cf.relabelled_var), cf.gain, cf.proxy_var, c.top_gsd_cm, cand.gsd_cm};
      } else if (model_.c_model()) {
        const double eta = model_.efficiency(delta_h);
        base = f.relabelled * eta * weight;
        base_sd = f.relabelled_std * eta * weight;
        relabelled = {f.relabelled, f.relabelled_noisy_std, 0.0, 0.0, 0.0, 0.0};
      }
      // What descents to this GSD realised of their forecast on the training fields as new ground.
      const double ratio = params_.gain_ratio(cand.gsd_cm);
      base *= ratio;
      base_sd *= ratio;
      const double gain = scaled(base);
      const double gain_var =
          scale_mean_ * scale_mean_ * base_sd * base_sd + scale_var_ * base * base + gain * gain * sigma_cv2;
      s.predicted_field_gain = gain;
      if (std::isfinite(relabelled.mean)) s.predicted_relabelled = std::abs(scale_mean_) * relabelled.mean;
      s.utility = utility(gain, cand.extra_time_s);
      // The curve's rise over the descent's extra time, on every training field's curve.
      double rise_sum = 0.0, rise_sq = 0.0;
      for (const auto& curve : curves) {
        const double rise = rising_curve_miou(curve, t0 + cand.extra_time_s) - rising_curve_miou(curve, t0);
        rise_sum += rise;
        rise_sq += rise * rise;
      }
      const double n = static_cast<double>(curves.size());
      const double rise = rise_sum / n;
      const double rise_var = curves.size() > 1 ? std::max(0.0, (rise_sq - n * rise * rise) / (n - 1.0)) : 0.0;
      // What descents to this GSD ended above their forecast margin on the training fields as new ground.
      const double bias = params_.margin_bias(cand.gsd_cm) * cand.extra_time_s;
      const double lower = gain - rise + bias - params_.confidence * std::sqrt(gain_var + rise_var);
      s.predicted_front_margin =
          mean_top_miou(c) + forecast_gain_ + gain - curve_level - mean_curve_miou(curves, t0 + cand.extra_time_s);
      s.predicted_curve_rise = rise;
      s.predicted_end_s = t0 + cand.extra_time_s;
      if (gain > 0.0 && lower > best) {
        best = lower;
        best_index = k;
      }
      d.scores.push_back(s);
      gains.push_back(gain);
      forecasts.push_back(relabelled);
    }
    if (best_index && c.sigma >= params_.min_sigma) {
      d.descend = true;
      d.gsd_cm = c.candidates[*best_index].gsd_cm;
      d.candidate = *best_index;
      forecast_gain_ += gains[*best_index];
      chosen_.push_back(forecasts[*best_index]);
    }
    return d;
  }

  /// The GSD to fly the top level at (ChoosesTopLevel): of those the model can decide from (its
  /// cell gain model's top-level GSDs, else the nominal one), the one whose lawnmower over the
  /// area falls least short of the lawnmowers of `lawnmowers` as fast or faster: on each training
  /// field's curve, the most any of them maps better (0 if none), averaged over the fields; the
  /// coarsest where they tie. The margin a mission is judged by is exactly such a shortfall
  /// against the curve's upper envelope, and it is taken field by field because the fields'
  /// curves cross: a network on ground it never saw maps one field better at 12.5 cm/px than at
  /// 15 and the next worse, so the shortfall of their mean curve can be 0 where flying the
  /// coarser, slower lawnmower loses on some of them. With TopLevelChoice::hull,
  /// then a finer one of them while the predicted curve rises faster per second up to it than
  /// from it to any finer lawnmower of `lawnmowers`. Both the adaptive and the non-adaptive rule
  /// choose so (nothing is learnt here).
  [[nodiscard]] double top_gsd(std::span<const LawnmowerForecast> lawnmowers, double nominal) const {
    std::vector<double> allowed;
    if (model_.cells())
      for (double g : model_.cells()->top_gsds())
        for (const auto& l : lawnmowers)
          if (detail::same_gsd(l.gsd_cm, g)) allowed.push_back(l.gsd_cm);
    if (std::find(allowed.begin(), allowed.end(), nominal) == allowed.end()) allowed.push_back(nominal);
    std::sort(allowed.begin(), allowed.end(), std::greater<>());
    const auto predicted = [&](double g) {
      double m = 0.0;
      for (const auto& r : reference_) m += miou_at_gsd(r.points, g);
      return m / static_cast<double>(reference_.size());
    };
    const auto time_of = [&](double g) {
      for (const auto& l : lawnmowers)
        if (l.gsd_cm == g) return l.time_s;
      return std::numeric_limits<double>::infinity();  // the nominal top without a forecast: never dominated
    };
    // The mean over the training fields of how far a faster lawnmower beats g on each.
    const auto shortfall = [&](double g) {
      double sum = 0.0;
      for (const auto& r : reference_) {
        double worst = 0.0;
        for (const auto& l : lawnmowers)
          if (l.time_s <= time_of(g))
            worst = std::max(worst, miou_at_gsd(r.points, l.gsd_cm) - miou_at_gsd(r.points, g));
        sum += worst;
      }
      return sum / static_cast<double>(reference_.size());
    };
    double best = nominal, best_shortfall = std::numeric_limits<double>::infinity();
    for (double g : allowed) {
      const double v = shortfall(g);
      if (v < best_shortfall - 1e-12) best = g, best_shortfall = v;
    }
    if (params_.top_level != TopLevelChoice::hull) return best;
    for (double g : allowed) {  // coarse to fine
      const double t0 = time_of(best), t1 = time_of(g);
      if (!(g < best) || !std::isfinite(t1) || !std::isfinite(t0)) continue;
      // The rise per second up to g, and the steepest from g to a finer, slower lawnmower.
      const double rise = predicted(g) - predicted(best);
      const double rate_to = t1 > t0 ? rise / (t1 - t0) : (rise > 0.0 ? std::numeric_limits<double>::infinity() : rise);
      double rate_on = 0.0;
      for (const auto& l : lawnmowers)
        if (l.gsd_cm < g && l.time_s > t1)
          rate_on = std::max(rate_on, (predicted(l.gsd_cm) - predicted(g)) / (l.time_s - t1));
      if (!(rate_to > rate_on)) break;
      best = g;
    }
    return best;
  }

  /// After a descent: the paper's update of O and the field correction (no-op unless `online`).
  void observe(const DescentOutcome& out) {
    if (!params_.online) return;
    model_.update(out);
    if (out.descent >= chosen_.size()) return;
    const Relabelled& f = chosen_[out.descent];
    if (model_.cells() && f.sub_gsd_cm > 0.0) {
      // The scene check (cell gain model): the descent's gain as the finer look estimates it,
      // y = γ·d = s·μ + ε, d = top − fine input, ε ~ N(0, κ_p·Σ w²x + τ_γ²·d²), μ the forecast
      // before s (τ_γ: how far the proxy's slope differs between the training fields). Without
      // the finer images' input, or a proxy, nothing is learnt.
      const CellGainModel::Point p = model_.cells()->at(f.top_gsd_cm, f.sub_gsd_cm);
      if (!std::isfinite(out.fine_input) || !std::isfinite(out.top_input) || !(p.proxy_slope > 0.0) ||
          !(f.proxy_var > 0.0) || !(f.gain > 0.0))
        return;
      const double y = model_.cells()->proxy_gain(f.top_gsd_cm, f.sub_gsd_cm, out.top_input, out.fine_input);
      const double d = out.top_input - out.fine_input;
      const double var = f.proxy_var + p.proxy_slope_sd * p.proxy_slope_sd * d * d;
      scale_precision_sum_ += f.gain * f.gain / var;
      scale_evidence_sum_ += f.gain * y / var;
    } else {
      if (!std::isfinite(f.mean) || !model_.c_model()) return;
      // Conjugate update of s in χ_obs = s·μ_C + ε, ε ~ N(0, sd_C²), prior s ~ N(1, ω²).
      const double noise = std::max(f.noisy_sd * f.noisy_sd, 1e-12);
      scale_precision_sum_ += f.mean * f.mean / noise;
      scale_evidence_sum_ += f.mean * out.relabelled.interest_share / noise;
    }
    const double prior_precision = 1.0 / (params_.scale_prior_sd * params_.scale_prior_sd);
    const double precision = prior_precision + scale_precision_sum_;
    // s >= 0 with C (a descent cannot relabel less than nothing); a scene check may find the
    // finer look worse than the coarse one, s < 0: descending loses there, and the UAV stops.
    scale_mean_ = (prior_precision + scale_evidence_sum_) / precision;
    if (!model_.cells()) scale_mean_ = std::max(0.0, scale_mean_);
    scale_var_ = 1.0 / precision;
  }

 private:
  /// What a chosen descent was forecast to show: the share of its region it relabels with L
  /// involved and the spread of one such observation (NaN: no forecast, no field correction
  /// from it); with a cell gain model, its normalised gain before the field factor and the
  /// spread of the scene check's measurement of it, and the GSDs it was forecast for.
  struct Relabelled {
    double mean = std::numeric_limits<double>::quiet_NaN();
    double noisy_sd = 0.0;
    double gain = 0.0;
    double proxy_var = 0.0;
    double top_gsd_cm = 0.0;
    double sub_gsd_cm = 0.0;
  };

  /// A forecast gain (of a descent, or of the field's curve) `base` before the field factor s,
  /// times s. A gain the training fields saw (base >= 0) scales with s and turns into a loss
  /// where the scene check found the finer look worse (s < 0); a loss the training fields saw
  /// (base < 0: a descent GSD that lost there) stays a loss whatever s: |s|·base. Without it, a
  /// field where descending loses would forecast a gain for exactly the descents the training
  /// fields saw lose.
  [[nodiscard]] double scaled(double base) const noexcept {
    return base >= 0.0 ? scale_mean_ * base : std::abs(scale_mean_) * base;
  }

  /// X̂, the field's mean input per field pixel (CurveSource::field): the top-level regions
  /// seen so far, the unseen part shrunk towards the training fields' mean at this top level
  /// with σ̂'s weight k.
  [[nodiscard]] double field_input_estimate(const DecisionContext& c) const {
    const double k = params_.sigma_prior_weight;
    const double unseen = std::max(0.0, 1.0 - seen_input_share_);
    double prior_input = 0.0;  // the training fields' mean input at this top level (0: unknown)
    for (const auto& r : reference_) prior_input += r.input_at(c.top_gsd_cm) / static_cast<double>(reference_.size());
    const double rest = prior_input > 0.0         ? (seen_input_ + k * prior_input) / (seen_input_share_ + k)
                        : seen_input_share_ > 0.0 ? seen_input_ / seen_input_share_
                                                  : 0.0;
    return seen_input_ + unseen * rest;
  }

  /// The lawnmower curve of this field as the cell gain model predicts it (CurveSource::field),
  /// relative to the top level's mIoU: at each lawnmower GSD g finer than the top level,
  /// s·β(top, g)·X̂·(1 / σ̂) (s applied by scaled()), `x` = X̂ (field_input_estimate),
  /// `inv_sigma` = 1 / σ̂; 0 at the top level; its upper envelope. With a training field
  /// `corrected_by`, each rise times that field's real / predicted rise (CurveSource::corrected).
  [[nodiscard]] std::vector<CurvePoint> field_curve(const DecisionContext& c, double x, double inv_sigma,
                                                    const ReferenceCurve* corrected_by) const {
    std::vector<CurvePoint> curve;
    for (const auto& l : c.lawnmowers) {
      if (l.gsd_cm > c.top_gsd_cm) continue;  // coarser than the top level: not what it compares with
      const double slope = l.gsd_cm < c.top_gsd_cm ? model_.cells()->at(c.top_gsd_cm, l.gsd_cm).gain_slope : 0.0;
      const double ratio = corrected_by ? rise_ratio(*corrected_by, c.top_gsd_cm, l.gsd_cm, slope) : 1.0;
      curve.push_back({l.time_s, scaled(slope * x * inv_sigma * ratio)});
    }
    return upper_envelope(std::move(curve));
  }

  /// CurveSource::corrected's r_f: training field `r`'s real lawnmower rise from GSD `top` to `g`
  /// over the one the cell gain model predicts for it, slope·X_f / σ_f (X_f at `top`); clamped
  /// to [1/4, 4]; 1 where nothing is predicted.
  static double rise_ratio(const ReferenceCurve& r, double top, double g, double slope) {
    const double predicted = r.field_sigma > 0.0 ? slope * r.input_at(top) / r.field_sigma : 0.0;
    if (!(predicted > 0.0)) return 1.0;
    const double real = miou_at_gsd(r.points, g) - miou_at_gsd(r.points, top);
    return std::clamp(real / predicted, 0.25, 4.0);
  }

  /// a / σ̂: a relabelled share of the region, times η, as a field-level gain; and Var σ̂ / σ̂²
  /// (see the class comment).
  [[nodiscard]] std::pair<double, double> gain_weight(const DecisionContext& c) const {
    double sigma = 0.0;
    double sigma_var = 0.0;
    if (prior_sigma_ > 0.0) {
      const double k = params_.sigma_prior_weight;
      const double rest = (seen_interest_ + k * prior_sigma_) / (seen_share_ + k);
      const double unseen = std::max(0.0, 1.0 - seen_share_);
      sigma = seen_interest_ + unseen * rest;
      const double tau2 = params_.sigma_prior_sd * params_.sigma_prior_sd;
      sigma_var = unseen * unseen * tau2 * k / (k + seen_share_) + unseen * k * tau2;
    } else {
      sigma = sigma_sum_ / static_cast<double>(sigma_count_);
    }
    if (!(sigma > 0.0)) return {0.0, 0.0};
    return {c.region_share / sigma, sigma_var / (sigma * sigma)};
  }

  /// mIoU of a predicted curve (sorted by time) at time t: linear between its points, flat
  /// beyond its ends, as front_margin reads the curve.
  static double curve_miou(const std::vector<CurvePoint>& curve, double t) {
    return detail::interpolate_flat(curve, t, &CurvePoint::time_s, &CurvePoint::miou);
  }

  /// The curve a descent's gain is compared with: as curve_miou, but beyond the last point (a
  /// mission slower than the finest lawnmower) the last segment goes on if it rises (never
  /// below the last point: the finest lawnmower can always be flown), capped at 1. There a
  /// descent must still beat what the finest lawnmowers bought per second; read flat, any
  /// positive gain would beat it however long the descent.
  static double rising_curve_miou(const std::vector<CurvePoint>& curve, double t) {
    return std::min(1.0, detail::interpolate_extend(curve, t, &CurvePoint::time_s, &CurvePoint::miou));
  }

  static double mean_curve_miou(const std::vector<std::vector<CurvePoint>>& curves, double t) {
    double s = 0.0;
    for (const auto& c : curves) s += curve_miou(c, t);
    return s / static_cast<double>(curves.size());
  }

  /// The training fields' mean lawnmower mIoU at the top GSD: where the forecast end point
  /// starts (reported as CandidateScore::predicted_front_margin only).
  [[nodiscard]] double mean_top_miou(const DecisionContext& c) const {
    double s = 0.0;
    for (const auto& r : reference_) s += miou_at_gsd(r.points, c.top_gsd_cm);
    return s / static_cast<double>(reference_.size());
  }

  GainModel initial_;
  GainModel model_;
  std::vector<ReferenceCurve> reference_;
  Params params_;
  double prior_sigma_ = 0.0;  ///< mean σ of the training fields (0: unknown)
  // Per mission (reset by begin_mission):
  double sigma_sum_ = 0.0;  ///< σ of the top-level images so far
  std::size_t sigma_count_ = 0;
  double seen_share_ = 0.0;         ///< field share of the top-level regions seen so far
  double seen_interest_ = 0.0;      ///< ... and Σ share · σ over them
  double seen_input_ = 0.0;         ///< Σ share · the region's mean cell-model input (DecisionContext::region_input)
  double seen_input_share_ = 0.0;   ///< ... the share of the field those regions cover
  double forecast_gain_ = 0.0;      ///< forecast field-level gain of the descents taken
  std::vector<Relabelled> chosen_;  ///< what each descent chosen was forecast to relabel (DescentOutcome::descent)
  double scale_mean_ = 1.0;         ///< field factor s: posterior mean
  double scale_var_ = 0.0;          ///< ... and variance
  double scale_precision_sum_ = 0.0;
  double scale_evidence_sum_ = 0.0;
};

static_assert(DecisionPolicy<FrontAwarePolicy>);
static_assert(ChoosesTopLevel<FrontAwarePolicy>);

}  // namespace adaptseg
