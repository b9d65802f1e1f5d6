#pragma once
/// @file
/// The front-aware decision rule (beyond the paper; docs/method.md): descend where a descent's
/// forecast gain beats what flying the whole field lower would have gained in the same time,
/// with the forecasts corrected in flight from what the descents actually changed.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/field_estimates.hpp>
#include <adaptseg/core/front_aware_settings.hpp>
#include <adaptseg/core/gain_model.hpp>
#include <adaptseg/core/jump_guard.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/core/top_level.hpp>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

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
///   on (rising_miou_at_time());
/// - the descent is worth its time if its lower bound (ĝ − ΔD̄ + b·T) − z·sqrt(Var ĝ + sd_D²) > 0
///   (z = `confidence`, chosen on training fields; 0: the forecasts' means; b the margin bias
///   per second of a descent to the candidate's GSD, `margin_biases`, 0 unless calibrated with
///   them). The UAV descends
///   to the candidate of largest lower bound, if σ >= `min_sigma`. Since ΔD̄ grows with T0, it
///   descends while descents beat flying lower everywhere, and stops when they no longer do.
///   With `curve_agreement` q > 0, only to a GSD g whose lawnmower mapped better than the top
///   level's on at least a share q of the training fields (finer_lawnmower_share(): where
///   flying finer lost on the fields, the cells' forecast of a gain is not trusted).
///   With `finest_descent_gsd_cm` > 0, to no GSD finer than it; with `longest_descent_s` > 0, by
///   no candidate that costs more extra seconds (limits chosen on the training folds:
///   CalibrationOptions::finest_descent_gsd_cm, longest_descent_s).
///
/// Field correction (`online`; beyond the paper, §3.2.3's idea applied to what is observable):
/// a descent's relabelled share χ (Relabelling::interest_share, the region's field pixels whose
/// label changed with a label of interest involved) needs no ground truth. C forecasts it; on
/// this field the truth is taken to be χ = s·μ_C + ε with one field factor s (prior N(1, ω²),
/// ω = `scale_prior_sd`; ε ~ N(0, sd_C²), C's predictive spread of one region) and the same
/// factor on the gains, the gain being paid by the relabelled pixels. After each descent s's
/// posterior is updated (conjugate Gaussian): descents that change less than forecast lower
/// ĝ and the UAV stops earlier; descents that change more raise it; each observation narrows
/// Var(s), so the lower bound rises as evidence accrues (with a cell gain model, s learns from
/// the scene check unless `field_factor` says otherwise: FieldFactorSource; learnt from the
/// relabelled share, s's prior spread may be its own, `relabel_field_sd`). Also the paper's
/// update of O. `online = false` (non-adaptive) keeps s = 1, Var(s) = ω² and O as initialised.
/// With `learn_stop_only`, what s learns may only stop descents: each candidate's lower bound is
/// the lesser of the learnt one and the one the non-adaptive rule computes in the same context
/// (s at its prior), so that learning can end the descents early where the field changes less
/// than forecast, and never adds one the frozen rule would not take at that point.
class FrontAwarePolicy {
 public:
  /// Behaviour (FrontAwareParams); validated by the constructor.
  using Params = FrontAwareParams;

  /// @throws std::invalid_argument for invalid params, a model without C and without a cell gain
  ///         model, no reference curve, a curve without points, or a point with a GSD <= 0 or
  ///         a non-finite value.
  FrontAwarePolicy(GainModel model, std::vector<ReferenceCurve> reference, Params params)
      : initial_(std::move(model)), model_(initial_), reference_(std::move(reference)), params_(params) {
    params_.validate();
    detail::require(model_.c_model().has_value() || model_.cells().has_value(),
                    "FrontAwarePolicy: the gain model needs C or a cell gain model (what a descent relabels); C",
                    "absent");
    detail::require(!reference_.empty(), "FrontAwarePolicy: at least one reference lawnmower curve is needed; count",
                    reference_.size());
    std::size_t with_sigma = 0;
    double prior_sigma = 0.0;  // the training fields' mean σ (0: unknown)
    for (const auto& r : reference_) {
      r.validate();
      if (r.field_sigma > 0.0) {
        prior_sigma += r.field_sigma / static_cast<double>(reference_.size());
        ++with_sigma;
      }
    }
    if (with_sigma != reference_.size()) prior_sigma = 0.0;  // unknown for some: the running mean of σ
    share_ = FieldShareEstimate(prior_sigma);
    begin_mission();
  }

  [[nodiscard]] std::string name() const { return params_.online ? "adaptive" : "nonadaptive"; }
  [[nodiscard]] const Params& params() const noexcept { return params_; }
  /// The prior spread of s (`scale_prior_sd`) takes effect at the next begin_mission().
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
  [[nodiscard]] double field_scale() const noexcept { return scale_.mean(); }
  [[nodiscard]] double field_scale_sd() const noexcept { return scale_.sd(); }

  void begin_mission() {
    model_ = initial_;
    share_.reset();
    forecast_gain_ = 0.0;
    chosen_.clear();
    scale_ = prior_scale();
    guard_ = JumpGuard(params_.jump_bound);
  }

  /// @throws std::invalid_argument if the context has no lawnmower forecasts.
  [[nodiscard]] Decision decide(const DecisionContext& c) {
    detail::require(!c.lawnmowers.empty(),
                    "FrontAwarePolicy::decide: the context needs the field's lawnmower forecasts; count",
                    c.lawnmowers.size());
    share_.add(c.sigma, c.region_share, c.region_input, c.region_entropy);
    if (reads_field_entropy())
      model_.set_field_entropy(
          share_.entropy(model_.cells()->entropy_reference(c.top_gsd_cm), params_.sigma_prior_weight));
    const auto [weight, sigma_cv2] = gain_weight(c);
    const PredictedCurves curves = predicted_curves(c, weight, scale_);
    // The frozen rule's curves, where learning may only stop descents (Params::learn_stop_only).
    std::optional<PredictedCurves> frozen;
    if (caps_learning()) frozen = predicted_curves(c, weight, prior_scale());
    Decision d;
    std::optional<std::size_t> best_index;
    double best = 0.0;
    std::vector<Assessment> assessed;
    for (std::size_t k = 0; k < c.candidates.size(); ++k) {
      assessed.push_back(assess(c, c.candidates[k], curves, weight, sigma_cv2, scale_));
      if (frozen) {
        // No higher than the frozen rule's bound, and none where the frozen rule forecasts no gain.
        const Assessment f = assess(c, c.candidates[k], *frozen, weight, sigma_cv2, prior_scale());
        assessed.back().lower =
            f.gain > 0.0 ? std::min(assessed.back().lower, f.lower) : -std::numeric_limits<double>::infinity();
      }
      if (assessed.back().gain > 0.0 && assessed.back().lower > best && agreed(c.top_gsd_cm, c.candidates[k])) {
        best = assessed.back().lower;
        best_index = k;
      }
      d.scores.push_back(assessed.back().score);
    }
    if (best_index && c.sigma >= params_.min_sigma && !guard_.tripped()) {
      d.descend = true;
      d.gsd_cm = c.candidates[*best_index].gsd_cm;
      d.candidate = *best_index;
      forecast_gain_ += assessed[*best_index].gain;
      chosen_.push_back(assessed[*best_index].relabelled);
    }
    return d;
  }

  /// The GSD to fly the top level at (ChoosesTopLevel): of those the model can decide from (its
  /// cell gain model's top-level GSDs, else the nominal one), choose_top_gsd()'s with the
  /// training fields' curves and `params().top_level`. Both the adaptive and the non-adaptive
  /// rule choose so (nothing is learnt here).
  [[nodiscard]] double top_gsd(std::span<const LawnmowerForecast> lawnmowers, double nominal) const {
    std::vector<double> allowed;
    if (model_.cells())
      for (double g : model_.cells()->top_gsds())
        for (const auto& l : lawnmowers)
          if (detail::same_gsd(l.gsd_cm, g)) allowed.push_back(l.gsd_cm);
    if (std::find(allowed.begin(), allowed.end(), nominal) == allowed.end()) allowed.push_back(nominal);
    std::sort(allowed.begin(), allowed.end(), std::greater<>());
    return choose_top_gsd(reference_, allowed, lawnmowers, nominal, params_.top_level);
  }

  /// Whether β reads the field's entropy (a cell gain model pooled by SlopePooling::field_entropy).
  [[nodiscard]] bool reads_field_entropy() const { return model_.cells() && model_.cells()->reads_field_entropy(); }

  /// Whether a descent image of σ `sigma_image` over a cell of top-level σ `sigma_top` is
  /// trusted (GuardsDescentImages; the jump guard, Params::jump_bound).
  bool trusts_descent_image(double sigma_top, double sigma_image) { return guard_.trusts(sigma_top, sigma_image); }

  /// After a descent: the paper's update of O and the field correction (no-op unless `online`).
  void observe(const DescentOutcome& out) {
    if (!params_.online) return;
    model_.update(out);
    if (out.descent >= chosen_.size()) return;
    const Relabelled& f = chosen_[out.descent];
    if (model_.cells() && f.sub_gsd_cm > 0.0 && params_.field_factor == FieldFactorSource::relabelled) {
      // χ_obs = s·μ + ε, μ the cell gain model's relabelled share, ε ~ N(0, its spread of one
      // descent and the region's own, (τ_r·μ)²).
      if (std::isfinite(f.mean) && f.mean > 0.0) {
        const double region = params_.relabel_region_sd * f.mean;
        scale_.observe(f.mean, out.relabelled.interest_share,
                       std::max(f.noisy_sd * f.noisy_sd, 1e-12) + region * region, true);
      }
    } else if (model_.cells() && f.sub_gsd_cm > 0.0) {
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
      scale_.observe(f.gain, y, var, false);  // a finer look may be worse: s < 0, and the UAV stops
    } else {
      if (!std::isfinite(f.mean) || !model_.c_model()) return;
      // χ_obs = s·μ_C + ε, ε ~ N(0, sd_C²); s >= 0 with C alone (a descent cannot relabel less
      // than nothing; with a cell gain model a scene check may have found s < 0 before).
      const double noise = std::max(f.noisy_sd * f.noisy_sd, 1e-12);
      scale_.observe(f.mean, out.relabelled.interest_share, noise, !model_.cells());
    }
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

  /// The lawnmower curves a descent is compared with at one image, per training field (or one,
  /// CurveSource::field), each in time order; `level` the mIoU they are relative to (the top
  /// level's for the curves the cell gain model predicts, 0 for the training fields' own).
  struct PredictedCurves {
    std::vector<std::vector<CurvePoint>> curves;
    double level = 0.0;
    double t0 = 0.0;  ///< the mission's end if it descends no more: elapsed + rest of the top level
  };

  /// One candidate as the rule sees it: its score, its forecast field gain ĝ, the lower bound
  /// of its margin, and what it is forecast to relabel (kept for observe() if it is chosen).
  struct Assessment {
    CandidateScore score;
    double gain = 0.0;
    double lower = 0.0;
    Relabelled relabelled{};
  };

  /// The predicted curves (CurveSource): each training field's lawnmower accuracy placed at
  /// this field's lawnmower times, the upper envelope of that predicted curve (the best
  /// lawnmower at a time or sooner, as the front margin reads it); or, with a cell gain model
  /// and a curve source other than `training`, this field's curve as predicted (field_curve),
  /// `weight` = a / σ̂; with `mixture` both sets, the predicted ones raised to the training
  /// fields' mean mIoU at the top level.
  [[nodiscard]] PredictedCurves predicted_curves(const DecisionContext& c, double weight, const FieldScale& s) const {
    PredictedCurves p;
    p.t0 = c.elapsed_s + c.rest_s;
    const bool predicts = model_.cells() && c.region_share > 0.0 && weight > 0.0;
    if (params_.curve != CurveSource::training && predicts) {
      const double x = field_input_estimate(c);
      if (params_.curve == CurveSource::field)
        p.curves.push_back(field_curve(c, x, weight / c.region_share, nullptr, s));
      else
        for (const auto& r : reference_) p.curves.push_back(field_curve(c, x, weight / c.region_share, &r, s));
      p.level = detail::mean_reference_miou(reference_, c.top_gsd_cm);
      if (params_.curve != CurveSource::mixture) return p;
      // With the training fields' own curves below, which are absolute: these from the level.
      for (auto& curve : p.curves)
        for (auto& point : curve) point.miou += p.level;
      p.level = 0.0;
    }
    for (const auto& r : reference_) {
      std::vector<CurvePoint> curve;
      for (const auto& f : c.lawnmowers) curve.push_back({f.time_s, miou_at_gsd(r.points, f.gsd_cm)});
      p.curves.push_back(upper_envelope(std::move(curve)));
    }
    return p;
  }

  /// The descent's gain in shares of the region before the field factor s (mean, sd, and what
  /// it relabels): from its cells (DescentCoverage::ranked), else from C and η; times the gain
  /// ratio of its GSD (what descents to it realised of their forecast on the training fields as
  /// new ground).
  struct BaseGain {
    double mean = 0.0, sd = 0.0;
    Relabelled relabelled{};
  };
  [[nodiscard]] BaseGain base_gain(const DecisionContext& c, const Candidate& cand, const GainForecast& f,
                                   double delta_h, double weight) const {
    BaseGain b;
    if (!cand.cells.empty() && model_.cells() && c.region_px > 0.0) {
      const CellGainModel::Forecast cf = model_.cells()->forecast(c.top_gsd_cm, cand.gsd_cm, cand.cells, c.region_px);
      b.mean = cf.gain * weight;
      b.sd = std::sqrt(cf.gain_var) * weight;
      b.relabelled = {cf.relabelled, std::sqrt(cf.relabelled_var), cf.gain, cf.proxy_var, c.top_gsd_cm, cand.gsd_cm};
    } else if (model_.c_model()) {
      const double eta = model_.efficiency(delta_h);
      b.mean = f.relabelled * eta * weight;
      b.sd = f.relabelled_std * eta * weight;
      b.relabelled = {f.relabelled, f.relabelled_noisy_std, 0.0, 0.0, 0.0, 0.0};
    }
    const double ratio = gain_ratio_at(params_.gain_ratios, cand.gsd_cm);
    b.mean *= ratio;
    b.sd *= ratio;
    return b;
  }

  /// One candidate's forecast gain ĝ and its variance, the curves' rise over its extra time and
  /// the lower bound (ĝ − ΔD̄ + b·T) − z·sqrt(Var ĝ + sd_D²) (class comment), with the field
  /// factor `scale` (the one learnt so far, or its prior: Params::learn_stop_only).
  [[nodiscard]] Assessment assess(const DecisionContext& c, const Candidate& cand, const PredictedCurves& p,
                                  double weight, double sigma_cv2, const FieldScale& scale) const {
    const double delta_h = c.top_altitude_m - cand.altitude_m;
    const GainForecast f = model_.forecast(delta_h, c.sigma);
    Assessment a;
    a.score = scored(cand, f);
    const BaseGain b = base_gain(c, cand, f, delta_h, weight);
    const FactorEstimate s = gain_factor(scale);
    a.gain = s.scaled(b.mean);
    const double gain_var = s.mean * s.mean * b.sd * b.sd + s.var * b.mean * b.mean + a.gain * a.gain * sigma_cv2;
    a.score.predicted_field_gain = a.gain;
    if (std::isfinite(b.relabelled.mean)) a.score.predicted_relabelled = std::abs(scale.mean()) * b.relabelled.mean;
    a.score.utility = utility(a.gain, cand.extra_time_s);
    const auto [rise, rise_var] = detail::curve_rise(p.curves, p.t0, cand.extra_time_s);
    // What descents to this GSD ended above their forecast margin on the training fields as new ground.
    const double bias = margin_bias_at(params_.margin_biases, cand.gsd_cm) * cand.extra_time_s;
    a.lower = a.gain - rise + bias - params_.confidence * std::sqrt(gain_var + rise_var);
    // Reported only: from the training fields' mean lawnmower mIoU at the top GSD.
    a.score.predicted_front_margin = detail::mean_reference_miou(reference_, c.top_gsd_cm) + forecast_gain_ + a.gain -
                                     p.level - detail::mean_curve_miou(p.curves, p.t0 + cand.extra_time_s);
    a.score.predicted_curve_rise = rise;
    a.score.predicted_end_s = p.t0 + cand.extra_time_s;
    a.relabelled = b.relabelled;
    return a;
  }

  /// Whether descent `cand` may be taken from top level `top` (Params::curve_agreement,
  /// Params::finest_descent_gsd_cm and Params::longest_descent_s, up to rounding).
  [[nodiscard]] bool agreed(double top, const Candidate& cand) const {
    const double gsd = cand.gsd_cm;
    if (gsd < params_.finest_descent_gsd_cm * (1.0 - 1e-9)) return false;
    if (params_.longest_descent_s > 0.0 && cand.extra_time_s > params_.longest_descent_s * (1.0 + 1e-9)) return false;
    return params_.curve_agreement <= 0.0 || finer_lawnmower_share(reference_, top, gsd) >= params_.curve_agreement;
  }

  /// The factor a descent's forecast gain is scaled by, from the field factor `s`: s, or with s
  /// learnt from the relabelled share, 1 + b·(s − 1) (Params::relabel_transfer b;
  /// FieldScale::transferred), with the gain's own prior spread ω where s has its own
  /// (Params::relabel_field_sd).
  [[nodiscard]] FactorEstimate gain_factor(const FieldScale& s) const noexcept {
    if (params_.field_factor != FieldFactorSource::relabelled) return s.estimate();
    return relabel_field_spread() ? s.transferred(params_.relabel_transfer, params_.scale_prior_sd)
                                  : s.transferred(params_.relabel_transfer);
  }

  /// The field factor before any observation: s = 1 with its prior spread (ω, or ω_χ where s has
  /// its own: Params::relabel_field_sd); what begin_mission() starts from and the non-adaptive
  /// rule keeps.
  [[nodiscard]] FieldScale prior_scale() const noexcept {
    return FieldScale(relabel_field_spread() ? params_.relabel_field_sd : params_.scale_prior_sd);
  }

  /// Whether each candidate's bound is capped by the frozen rule's (Params::learn_stop_only; only
  /// an adaptive rule learns).
  [[nodiscard]] bool caps_learning() const noexcept { return params_.online && params_.learn_stop_only; }

  /// Whether s, learnt from the relabelled share, has a prior spread of its own (ω_χ).
  [[nodiscard]] bool relabel_field_spread() const noexcept {
    return params_.field_factor == FieldFactorSource::relabelled && params_.relabel_field_sd > 0.0;
  }

  /// X̂, the field's mean input per field pixel (CurveSource::field): FieldShareEstimate::input
  /// towards the training fields' mean input at this top level with σ̂'s weight k.
  [[nodiscard]] double field_input_estimate(const DecisionContext& c) const {
    double prior_input = 0.0;  // the training fields' mean input at this top level (0: unknown)
    for (const auto& r : reference_) prior_input += r.input_at(c.top_gsd_cm) / static_cast<double>(reference_.size());
    return share_.input(prior_input, params_.sigma_prior_weight);
  }

  /// The lawnmower curve of this field as the cell gain model predicts it (CurveSource::field),
  /// relative to the top level's mIoU: at each lawnmower GSD g finer than the top level,
  /// s·β(top, g)·X̂·(1 / σ̂) (s = `scale`, FieldScale::scaled; none with
  /// FieldFactorSource::relabelled), `x` = X̂,
  /// `inv_sigma` = 1 / σ̂; 0 at the top level; its upper envelope. With a training field
  /// `corrected_by`, each rise times that field's real / predicted rise (CurveSource::corrected).
  [[nodiscard]] std::vector<CurvePoint> field_curve(const DecisionContext& c, double x, double inv_sigma,
                                                    const ReferenceCurve* corrected_by, const FieldScale& scale) const {
    std::vector<CurvePoint> curve;
    for (const auto& l : c.lawnmowers) {
      if (l.gsd_cm > c.top_gsd_cm) continue;  // coarser than the top level: not what it compares with
      const double slope = l.gsd_cm < c.top_gsd_cm ? model_.cells()->at(c.top_gsd_cm, l.gsd_cm).gain_slope : 0.0;
      const double ratio = corrected_by ? corrected_rise_ratio(*corrected_by, c.top_gsd_cm, l.gsd_cm, slope) : 1.0;
      const double rise = slope * x * inv_sigma * ratio;
      curve.push_back({l.time_s, params_.field_factor == FieldFactorSource::relabelled ? rise : scale.scaled(rise)});
    }
    return upper_envelope(std::move(curve));
  }

  /// a / σ̂ and Var σ̂ / σ̂² (FieldShareEstimate::gain_weight, with σ̂'s k and τ).
  [[nodiscard]] std::pair<double, double> gain_weight(const DecisionContext& c) const {
    return share_.gain_weight(c.region_share, params_.sigma_prior_weight, params_.sigma_prior_sd);
  }

  GainModel initial_;
  GainModel model_;
  std::vector<ReferenceCurve> reference_;
  Params params_;
  // Per mission (reset by begin_mission):
  FieldShareEstimate share_;        ///< σ̂ and X̂ from the top-level images so far
  FieldScale scale_;                ///< the field factor s
  double forecast_gain_ = 0.0;      ///< forecast field-level gain of the descents taken
  std::vector<Relabelled> chosen_;  ///< what each descent chosen was forecast to relabel (DescentOutcome::descent)
  JumpGuard guard_;                 ///< tripped by a descent image beyond Params::jump_bound
};

static_assert(DecisionPolicy<FrontAwarePolicy>);
static_assert(ChoosesTopLevel<FrontAwarePolicy>);
static_assert(ReadsFieldEntropy<FrontAwarePolicy>);
static_assert(GuardsDescentImages<FrontAwarePolicy>);

}  // namespace adaptseg
