#pragma once
/// @file
/// The front-aware rule (FrontAwarePolicy, core/front_aware_policy.hpp) beyond deciding: its
/// name, its keys in the model file's `rule` mapping and its calibration search (the
/// confidence level z chosen on the training fields, each flown with a model fitted without
/// it; σ̂'s prior estimated from their top-level images). One entry of DecisionRules
/// (decision_rules.hpp); docs/method.md, "Calibration".

#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// The prior of a new field's σ the front-aware rule's σ̂ shrinks towards
/// (FrontAwarePolicy::Params `sigma_prior_weight` k and `sigma_prior_sd` τ).
struct SigmaPrior {
  double weight = 0.25;  ///< k = v / τ² [fields]
  double sd = 0.0;       ///< τ
};

/// The top-level images of one training field as the UAV sees them, in flight order: each
/// image's σ and its region's share of the field (DecisionContext::sigma, region_share).
struct TopLevelTrace {
  double field_sigma = 0.0;  ///< σ of the field's top-level map (ReferenceCurve::field_sigma)
  std::vector<double> sigma;
  std::vector<double> share;
};

/// k and τ of σ̂'s hierarchical model (FrontAwarePolicy) estimated on training fields:
/// τ² the sample variance of the fields' σ; v, the spread of the mean σ of a seen share S
/// (variance v / S about the field's, hence v·(1 − S) / S about the whole field's mean m), is
/// the mean over the fields and over the prefixes of each flight (0 < S <= 0.9) of
/// (m_S − m)²·S / (1 − S), so that it holds the fields' spatial correlation along the flight
/// as the UAV meets it; k = v / τ², kept in [0.01, 100]. std::nullopt for fewer than two
/// fields or a field without a top-level image.
[[nodiscard]] inline std::optional<SigmaPrior> estimate_sigma_prior(std::span<const TopLevelTrace> fields) {
  if (fields.size() < 2) return std::nullopt;
  double mean = 0.0;
  for (const auto& f : fields) mean += f.field_sigma / static_cast<double>(fields.size());
  double tau2 = 0.0, v = 0.0;
  std::size_t prefixes = 0;
  for (const auto& f : fields) {
    tau2 += (f.field_sigma - mean) * (f.field_sigma - mean) / static_cast<double>(fields.size() - 1);
    double total = 0.0, total_interest = 0.0;
    for (std::size_t i = 0; i < f.share.size(); ++i) total += f.share[i], total_interest += f.share[i] * f.sigma[i];
    if (!(total > 0.0)) return std::nullopt;
    const double m = total_interest / total;
    double seen = 0.0, seen_interest = 0.0;
    for (std::size_t i = 0; i + 1 < f.share.size(); ++i) {
      seen += f.share[i] / total;
      seen_interest += f.share[i] / total * f.sigma[i];
      if (seen <= 0.0 || seen > 0.9) continue;  // near the end (m_S − m)² / (1 − S) is all noise
      const double d = seen_interest / seen - m;
      v += d * d * seen / (1.0 - seen);
      ++prefixes;
    }
  }
  if (prefixes > 0) v /= static_cast<double>(prefixes);
  const double k = tau2 > 0.0 ? std::clamp(v / tau2, 0.01, 100.0) : 100.0;
  return SigmaPrior{k, std::sqrt(tau2)};
}

namespace detail {

/// Records what each top-level image shows (σ, region share) and never descends.
struct TopLevelRecorder {
  TopLevelTrace trace;
  void begin_mission() {
    trace.sigma.clear();
    trace.share.clear();
  }
  Decision decide(const DecisionContext& c) {
    trace.sigma.push_back(c.sigma);
    trace.share.push_back(c.region_share);
    return {};
  }
  void observe(const DescentOutcome&) {}
  [[nodiscard]] std::string name() const { return "top-level"; }
};

/// Which of several settings of the same folds to keep (`trials`, the best of each slope
/// pooling, CalibrationOptions::slope_poolings' order): the first, unless another beats it on
/// the folds by more than one standard error of their paired differences, m̄ − m̄₁ >
/// sd(m − m₁) / sqrt(n) over the n folds (the one-standard-error rule of cross-validation,
/// Breiman et al. 1984, towards the first, the default); of those that do, the best mean.
/// Five training fields tell two poolings apart poorly, and a setting the folds prefer by less
/// than their own scatter is as likely to lose on a new field (docs/results.md, "Slopes pooled
/// over the cells or over the fields, chosen by the folds").
inline std::size_t select_pooling(std::span<const RuleTrial* const> trials) {
  std::size_t best = 0;
  const std::vector<double>& first = trials.front()->margins;
  for (std::size_t k = 1; k < trials.size(); ++k) {
    const std::vector<double>& m = trials[k]->margins;
    if (m.size() != first.size() || m.size() < 2) continue;
    const double n = static_cast<double>(m.size());
    double mean = 0.0;
    for (std::size_t f = 0; f < m.size(); ++f) mean += (m[f] - first[f]) / n;
    double ss = 0.0;
    for (std::size_t f = 0; f < m.size(); ++f) ss += std::pow(m[f] - first[f] - mean, 2);
    if (mean > std::sqrt(ss / (n - 1.0) / n) && trials[k]->front_margin > trials[best]->front_margin) best = k;
  }
  return best;
}

/// A trial's name: its z, and its slope pooling where the search tried several.
inline std::string z_text(double z, const SlopePooling* pooling = nullptr) {
  std::string s = "front-aware z=" + format_number(z);
  if (pooling) s += " slopes=" + to_string(*pooling);
  return s;
}

}  // namespace detail

/// The front-aware rule in the model file and in calibration.
struct FrontAwareRule {
  using Policy = FrontAwarePolicy;
  /// Its name: `kind` in the model file, `--rule` of the programs, CalibrationOptions::rule.
  static constexpr std::string_view kName = "front-aware";

  /// Writes the rule's own keys into the open `rule` mapping (after `kind`, `online` and
  /// `min_sigma`, which every rule has).
  static void write_keys(YAML::Emitter& e, const FrontAwarePolicy& rule) {
    using detail::emit_numbers;
    const auto num = [](double v) { return detail::format_number(v); };
    const FrontAwarePolicy::Params& p = rule.params();
    e << YAML::Key << "confidence" << YAML::Value << num(p.confidence);
    e << YAML::Key << "scale_prior_sd" << YAML::Value << num(p.scale_prior_sd);
    e << YAML::Key << "sigma_prior_weight" << YAML::Value << num(p.sigma_prior_weight);
    e << YAML::Key << "sigma_prior_sd" << YAML::Value << num(p.sigma_prior_sd);
    if (p.field_curve) e << YAML::Key << "field_curve" << YAML::Value << detail::flag_text(true);
    if (p.curve_ratio) e << YAML::Key << "curve_ratio" << YAML::Value << detail::flag_text(true);
    if (p.top_level != TopLevelChoice::undominated)
      e << YAML::Key << "top_level" << YAML::Value << to_string(p.top_level);
    e << YAML::Key << "reference" << YAML::Value << YAML::BeginSeq;
    for (const auto& r : rule.reference()) {
      std::vector<double> g, m;
      for (const auto& pt : r.points) g.push_back(pt.gsd_cm), m.push_back(pt.miou);
      e << YAML::BeginMap << YAML::Key << "field" << YAML::Value << r.field << YAML::Key << "field_sigma" << YAML::Value
        << num(r.field_sigma);
      if (r.field_input > 0.0) e << YAML::Key << "field_input" << YAML::Value << num(r.field_input);
      if (!r.top_inputs.empty()) {
        std::vector<double> tg, tx;
        for (const auto& [gsd, x] : r.top_inputs) tg.push_back(gsd), tx.push_back(x);
        e << YAML::Key << "top_input_gsd_cm" << YAML::Value;
        emit_numbers(e, tg);
        e << YAML::Key << "top_input" << YAML::Value;
        emit_numbers(e, tx);
      }
      e << YAML::Key << "gsd_cm" << YAML::Value;
      emit_numbers(e, g);
      e << YAML::Key << "miou" << YAML::Value;
      emit_numbers(e, m);
      e << YAML::EndMap;
    }
    e << YAML::EndSeq;
  }

  /// Reads what write_keys wrote: the rule over `model` with the keys every rule has.
  /// @throws std::invalid_argument naming the file and the key.
  [[nodiscard]] static FrontAwarePolicy read_keys(const detail::YamlReader& rule, GainModel model, double min_sigma,
                                                  bool online) {
    const YAML::Node refs = rule.node("reference");
    if (!refs.IsSequence()) detail::yaml_error(rule.where(), "'rule.reference' must be a list of curves");
    std::vector<ReferenceCurve> reference;
    for (std::size_t k = 0; k < refs.size(); ++k) {
      if (!refs[k].IsMap()) detail::yaml_error(rule.where(), "'rule.reference' entries must be mappings");
      const detail::YamlReader c(refs[k], rule.where());
      const auto g = c.numbers("gsd_cm");
      const auto v = c.numbers("miou");
      if (g.size() != v.size())
        detail::yaml_error(rule.where(), "a 'rule.reference' curve needs as many 'miou' as 'gsd_cm' values");
      ReferenceCurve curve{c.text("field"),
                           {},
                           c.has("field_sigma") ? c.number("field_sigma") : 0.0,
                           c.has("field_input") ? c.number("field_input") : 0.0};
      for (std::size_t i = 0; i < g.size(); ++i) curve.points.push_back({g[i], v[i]});
      if (c.has("top_input_gsd_cm") || c.has("top_input")) {
        const auto tg = c.numbers("top_input_gsd_cm");
        const auto tx = c.numbers("top_input");
        if (tg.size() != tx.size())
          detail::yaml_error(rule.where(),
                             "a 'rule.reference' curve needs as many 'top_input' as 'top_input_gsd_cm' values");
        for (std::size_t i = 0; i < tg.size(); ++i) curve.top_inputs.emplace_back(tg[i], tx[i]);
      }
      reference.push_back(std::move(curve));
    }
    return FrontAwarePolicy(std::move(model), std::move(reference),
                            {.min_sigma = min_sigma,
                             .online = online,
                             .confidence = rule.number("confidence"),
                             .scale_prior_sd = rule.number("scale_prior_sd"),
                             .sigma_prior_weight = rule.number("sigma_prior_weight"),
                             .sigma_prior_sd = rule.has("sigma_prior_sd") ? rule.number("sigma_prior_sd") : 0.0,
                             .field_curve = rule.has("field_curve") && rule.flag("field_curve"),
                             .curve_ratio = rule.has("curve_ratio") && rule.flag("curve_ratio"),
                             .top_level = rule.has("top_level") ? read_top_level(rule) : TopLevelChoice::undominated});
  }

  /// `rule.top_level`, naming the file where it is not a TopLevelChoice.
  [[nodiscard]] static TopLevelChoice read_top_level(const detail::YamlReader& rule) {
    const std::string name = rule.text("top_level");
    try {
      return parse_top_level_choice(name);
    } catch (const std::invalid_argument&) {
      detail::yaml_error(rule.where(), "'rule.top_level' must be undominated or hull (got '" + name + "')");
    }
  }

  /// Refuses options its search cannot use (before calibrate() samples anything).
  /// @throws std::invalid_argument if `confidences` or `slope_poolings` is empty, or names a
  ///         pooling twice.
  static void check_options(const CalibrationOptions& options) {
    detail::require(!options.confidences.empty(), "calibrate: confidences must not be empty", 0);
    detail::require(!options.slope_poolings.empty(), "calibrate: slope_poolings must not be empty", 0);
    for (std::size_t k = 0; k < options.slope_poolings.size(); ++k)
      for (std::size_t j = 0; j < k; ++j)
        detail::require(options.slope_poolings[j] != options.slope_poolings[k],
                        "calibrate: slope_poolings names a pooling twice:", to_string(options.slope_poolings[k]));
  }

  /// The calibration search (CalibrationOptions: `front_aware`, `confidences`, `sigma_prior`):
  /// `min_sigma` and the σ̂ prior's settings as given (with several fields `scale_prior_sd` is
  /// estimated from their spread instead, and the prior as `sigma_prior` says); z chosen among
  /// `confidences` by the mean front margin over the training fields, each flown with a model
  /// fitted without it (one field: the field and its halves, with the model of the whole
  /// field), ties to the larger z; with ranked cells and several fields this for each of
  /// `slope_poolings`, and the first pooling kept unless another beats it by more than the
  /// folds' noise (detail::select_pooling). `fly(field, policy, curve, margin)` flies an adaptive
  /// mission of `policy` and scores it against `curve` (detail::fly_scored).
  /// @throws std::invalid_argument as check_options.
  template <class Fly>
  [[nodiscard]] static RuleSearchResult search(const RuleSearchInputs& in, Fly&& fly) {
    const CalibrationOptions& options = in.options;
    const std::span<const Field> fields = in.fields;
    check_options(options);
    const bool ranked = descent_coverage_info(in.adaptive.coverage).ranks_cells;
    const std::vector<ReferenceCurve> reference(in.reference.begin(), in.reference.end());
    // What each training field's top-level images show along the flight, where σ̂'s prior is
    // estimated from them (one top-level mission per field).
    std::vector<TopLevelTrace> traces;
    const bool fit_sigma_prior =
        fields.size() >= 2 && options.sigma_prior != CalibrationOptions::SigmaPriorSource::given;
    for (std::size_t f = 0; fit_sigma_prior && f < fields.size(); ++f) {
      detail::TopLevelRecorder recorder;
      double unused = 0.0;
      (void)fly(fields[f], recorder, in.curves[f], unused);
      recorder.trace.field_sigma = reference[f].field_sigma;
      traces.push_back(std::move(recorder.trace));
    }
    FrontAwarePolicy::Params base = options.front_aware;
    base.online = true;
    // One fold per training field, its model fitted without it (one field: its layouts, the
    // whole field's model), the cell gain model (ranked) fitted below with each pooling tried.
    struct Fold {
      const Field* field;
      const std::vector<CurvePoint>* curve;
      GainModel model;
      std::vector<ReferenceCurve> reference;
      std::optional<SigmaPrior> sigma_prior;  ///< estimated without the field
      std::vector<CellSample> cells;          ///< the other fields' (ranked, several fields)
    };
    std::vector<Fold> folds;
    if (fields.size() == 1) {
      folds.push_back({&fields.front(), &in.curves.front(), in.model, reference, std::nullopt, {}});
      for (std::size_t k = 0; k < in.halves.size(); ++k)
        folds.push_back({&in.halves[k], &in.half_curves[k], in.model, reference, std::nullopt, {}});
    } else {
      for (std::size_t k = 0; k < fields.size(); ++k) {
        std::vector<RegionSample> rest;
        std::vector<ReferenceCurve> rest_reference;
        std::vector<TopLevelTrace> rest_traces;
        std::vector<CellSample> rest_cells;
        for (std::size_t j = 0; j < fields.size(); ++j)
          if (j != k) {
            rest.insert(rest.end(), in.samples[j].begin(), in.samples[j].end());
            rest_reference.push_back(reference[j]);
            if (fit_sigma_prior) rest_traces.push_back(traces[j]);
            if (ranked) rest_cells.insert(rest_cells.end(), in.cells[j].begin(), in.cells[j].end());
          }
        GainModel m = GainModel::fit(rest, options.fit);
        m.set_refit_every(options.refit_every);
        folds.push_back({&fields[k], &in.curves[k], std::move(m), std::move(rest_reference),
                         estimate_sigma_prior(rest_traces), std::move(rest_cells)});
      }
    }
    const auto apply_prior = [&](FrontAwarePolicy::Params& p, const std::optional<SigmaPrior>& prior) {
      if (!prior || options.sigma_prior == CalibrationOptions::SigmaPriorSource::given) return;
      p.sigma_prior_sd = prior->sd;
      if (options.sigma_prior == CalibrationOptions::SigmaPriorSource::estimated) p.sigma_prior_weight = prior->weight;
    };
    apply_prior(base, estimate_sigma_prior(traces));
    // The poolings tried: several only where the cell gain model pools several fields.
    const bool pools = ranked && fields.size() >= 2;
    const std::vector<SlopePooling> poolings =
        pools ? options.slope_poolings : std::vector<SlopePooling>{options.slope_poolings.front()};
    struct Setting {
      std::size_t pooling;  ///< index into poolings
      double z;
      FrontAwarePolicy::Params params;
    };
    std::vector<RuleTrial> trials;
    std::vector<Setting> settings;
    for (std::size_t pi = 0; pi < poolings.size(); ++pi) {
      FrontAwarePolicy::Params pooled = base;
      std::vector<GainModel> models;
      std::vector<double> field_scales;
      for (std::size_t k = 0; k < folds.size(); ++k) {
        GainModel m = folds[k].model;
        if (pools) {
          m.set_cells(CellGainModel::fit(folds[k].cells, in.adaptive.cell_input, poolings[pi]));
          // The field factor s of this field under the cell model that did not see it: the
          // least-squares scale of the cells' forecast gains onto their realised gains.
          double num = 0.0, den = 0.0;
          for (const CellSample& c : in.cells[k]) {
            const double f = m.cells()->cell_gain(c.top_gsd_cm, c.sub_gsd_cm, c.top) * c.top.field_px;
            num += f * c.normalized_gain() * c.top.field_px;
            den += f * f;
          }
          if (den > 0.0) field_scales.push_back(num / den);
        } else if (fields.size() >= 2) {
          // The field factor s of this field under the model that did not see it: the
          // least-squares scale of C's forecasts onto what its descents relabelled.
          double num = 0.0, den = 0.0;
          for (const RegionSample& s : in.samples[k]) {
            const GainForecast f = m.forecast(s.delta_h_m, s.sigma_top);
            num += f.relabelled * s.relabelled.interest_share;
            den += f.relabelled * f.relabelled;
          }
          if (den > 0.0) field_scales.push_back(num / den);
        }
        models.push_back(std::move(m));
      }
      if (field_scales.size() >= 2) {  // ω: the spread of s about 1 over the training fields
        double ss = 0.0;
        for (double s : field_scales) ss += (s - 1.0) * (s - 1.0);
        pooled.scale_prior_sd = std::max(0.1, std::sqrt(ss / static_cast<double>(field_scales.size())));
      }
      for (double z : options.confidences) {
        RuleTrial t;
        t.description = detail::z_text(z, poolings.size() > 1 ? &poolings[pi] : nullptr);
        FrontAwarePolicy::Params p = pooled;
        p.confidence = z;
        for (std::size_t k = 0; k < folds.size(); ++k) {
          FrontAwarePolicy::Params fold_params = p;  // σ̂'s prior: the fold's estimate replaces all fields'
          apply_prior(fold_params, folds[k].sigma_prior);
          FrontAwarePolicy policy(models[k], folds[k].reference, fold_params);
          double margin = 0.0;
          const AdaptiveResult r = fly(*folds[k].field, policy, *folds[k].curve, margin);
          detail::add_to_trial(t, r, margin);
        }
        trials.push_back(std::move(t));
        settings.push_back({pi, z, p});
      }
    }
    // Per pooling, its z of best mean margin (ties to the larger z); then the first pooling's,
    // unless another beats it by more than the noise of the folds (select_pooling).
    std::vector<std::size_t> best_of(poolings.size(), trials.size());
    for (std::size_t k = 0; k < trials.size(); ++k) {
      std::size_t& b = best_of[settings[k].pooling];
      if (b == trials.size() || trials[k].front_margin > trials[b].front_margin ||
          (trials[k].front_margin == trials[b].front_margin && settings[k].z > settings[b].z))
        b = k;
    }
    std::vector<const RuleTrial*> candidates;
    for (std::size_t b : best_of) candidates.push_back(&trials[b]);
    const std::size_t best = best_of[detail::select_pooling(candidates)];
    base = settings[best].params;
    std::rotate(trials.begin(), trials.begin() + static_cast<std::ptrdiff_t>(best),
                trials.begin() + static_cast<std::ptrdiff_t>(best) + 1);
    // The model of every field, its cell gain model pooled as chosen.
    GainModel model = in.model;
    const SlopePooling pooling = poolings[settings[best].pooling];
    if (ranked && model.cells() && model.cells()->pooling() != pooling) {
      std::vector<CellSample> all;
      for (const auto& c : in.cells) all.insert(all.end(), c.begin(), c.end());
      model.set_cells(CellGainModel::fit(all, in.adaptive.cell_input, pooling));
    }
    return {DecisionFunction(FrontAwarePolicy(std::move(model), reference, base)), std::move(trials)};
  }
};

}  // namespace adaptseg
