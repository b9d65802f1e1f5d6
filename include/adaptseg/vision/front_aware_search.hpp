#pragma once
/// @file
/// The front-aware rule's calibration search (FrontAwareRule::search, front_aware_rule.hpp):
/// its settings (the confidence level z, the cell gain model's slope pooling, the top-level
/// choice, the finest descent GSD, the longest descent) tried on the training fields, each
/// field flown with a model fitted without it, with σ̂'s prior estimated from their top-level
/// images (sigma_prior.hpp) and, where asked for, the jump guard's bound from the other fields'
/// cells. docs/method.md, "The front-aware rule".

#include <adaptseg/core/front_aware_policy.hpp>
#include <adaptseg/core/jump_guard.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/core/relabel_transfer.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/detail/fold_corrections.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/trial_choice.hpp>
#include <adaptseg/vision/sigma_prior.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

namespace detail {

/// Whether `options` asks for anything measured on the cells (measure_on_cells()).
[[nodiscard]] inline bool measures_on_cells(const CalibrationOptions& options) noexcept {
  return options.jump_guard || options.relabel_transfer || options.relabel_region_spread ||
         options.relabel_field_spread;
}

/// The jump guard's bound and the relabelled factor's b, τ_r and ω_χ measured on `cells` into
/// `c`, each where `options` asks for it (with ranked cells: the callers' test): a fold's from
/// the other fields' cells, the calibrated model's from every field's.
inline void measure_on_cells(FoldCorrection& c, std::span<const CellSample> cells, const CalibrationOptions& options,
                             DecisionInput input) {
  if (options.jump_guard) c.jump_bound = jump_bound(cells);
  if (options.relabel_transfer) c.relabel_transfer = relabel_transfer(cells, input);
  if (options.relabel_region_spread) c.relabel_region_sd = relabel_region_sd(cells, input);
  if (options.relabel_field_spread) c.relabel_field_sd = relabel_field_sd(cells, input);
}

/// One fold of the search: a training field flown with a model fitted without it (one field:
/// the field or one of its halves, with the whole field's model).
struct FrontAwareFold {
  const Field* field;
  const std::vector<CurvePoint>* curve;
  GainModel model;
  std::vector<ReferenceCurve> reference;
  std::optional<SigmaPrior> sigma_prior;  ///< estimated without the field
  std::vector<CellSample> cells;          ///< the other fields' (ranked, several fields)
};

/// The slope poolings of `poolings` that are not another under a second name: `field-entropy`
/// is left out where its line is flat at every pair of GSDs on the training fields' cells
/// `cells` (fewer than three fields count, or their mean entropies do not spread), where it is
/// `fields`; the order of the others then decides which is kept first. None is left out of a
/// list of one.
inline std::vector<SlopePooling> distinct_poolings(std::vector<SlopePooling> poolings,
                                                   std::span<const std::vector<CellSample>> cells,
                                                   DecisionInput input) {
  const auto entropy = std::find(poolings.begin(), poolings.end(), SlopePooling::field_entropy);
  if (entropy == poolings.end() || poolings.size() == 1) return poolings;
  const std::vector<CellSample> all = cells_of_every_field(cells);
  if (all.empty() || !CellGainModel::fit(all, input, SlopePooling::field_entropy).reads_field_entropy())
    poolings.erase(entropy);
  return poolings;
}

/// `p` with σ̂'s prior `prior` as `source` says (`given`, or no estimate: unchanged).
inline void apply_sigma_prior(FrontAwarePolicy::Params& p, const std::optional<SigmaPrior>& prior,
                              CalibrationOptions::SigmaPriorSource source) {
  if (!prior || source == CalibrationOptions::SigmaPriorSource::given) return;
  p.sigma_prior_sd = prior->sd;
  if (source == CalibrationOptions::SigmaPriorSource::estimated) p.sigma_prior_weight = prior->weight;
}

/// What each training field's top-level images show along the flight, where σ̂'s prior is
/// estimated from them (one top-level mission per field; otherwise none).
template <class Fly>
std::vector<TopLevelTrace> top_level_traces(const RuleSearchInputs& in, std::span<const ReferenceCurve> reference,
                                            Fly& fly) {
  std::vector<TopLevelTrace> traces;
  if (in.fields.size() < 2 || in.options.sigma_prior == CalibrationOptions::SigmaPriorSource::given) return traces;
  for (std::size_t f = 0; f < in.fields.size(); ++f) {
    TopLevelRecorder recorder;
    double unused = 0.0;
    (void)fly(in.fields[f], recorder, in.curves[f], unused);
    recorder.trace.field_sigma = reference[f].field_sigma;
    traces.push_back(std::move(recorder.trace));
  }
  return traces;
}

/// One fold per training field, its model fitted without it (one field: its layouts, the whole
/// field's model); each fold's σ̂ prior from the other fields' `traces` (where there are any)
/// and, with ranked cells, the other fields' cells. The fields of one ground
/// (CalibrationOptions::field_grounds) leave each one's fold together.
inline std::vector<FrontAwareFold> front_aware_folds(const RuleSearchInputs& in,
                                                     std::span<const ReferenceCurve> reference,
                                                     std::span<const TopLevelTrace> traces, bool ranked) {
  std::vector<FrontAwareFold> folds;
  const std::vector<ReferenceCurve> all(reference.begin(), reference.end());
  if (in.fields.size() == 1) {
    folds.push_back({&in.fields.front(), &in.curves.front(), in.model, all, std::nullopt, {}});
    for (std::size_t k = 0; k < in.halves.size(); ++k)
      folds.push_back({&in.halves[k], &in.half_curves[k], in.model, all, std::nullopt, {}});
    return folds;
  }
  const std::vector<std::size_t> grounds = fold_grounds(in);
  for (std::size_t k = 0; k < in.fields.size(); ++k) {
    std::vector<RegionSample> rest;
    std::vector<ReferenceCurve> rest_reference;
    std::vector<TopLevelTrace> rest_traces;
    std::vector<CellSample> rest_cells;
    for (std::size_t j = 0; j < in.fields.size(); ++j) {
      if (j == k || (!grounds.empty() && grounds[j] == grounds[k])) continue;  // k, or its ground by another network
      rest.insert(rest.end(), in.samples[j].begin(), in.samples[j].end());
      rest_reference.push_back(reference[j]);
      if (!traces.empty()) rest_traces.push_back(traces[j]);
      if (ranked) rest_cells.insert(rest_cells.end(), in.cells[j].begin(), in.cells[j].end());
    }
    GainModel m = GainModel::fit(rest, in.options.fit);
    m.set_refit_every(in.options.refit_every);
    folds.push_back({&in.fields[k], &in.curves[k], std::move(m), std::move(rest_reference),
                     estimate_sigma_prior(rest_traces), std::move(rest_cells)});
  }
  return folds;
}

/// Field k's factor s under `model`, which did not see it: the least-squares scale of the
/// model's forecasts onto what was realised (with `cells`: the cells' forecast gains onto their
/// realised gains; otherwise C's relabelled shares onto the region samples'); nullopt where
/// nothing was forecast.
inline std::optional<double> field_scale(const GainModel& model, bool cells, std::span<const CellSample> cell_samples,
                                         std::span<const RegionSample> samples) {
  double num = 0.0, den = 0.0;
  if (cells) {
    for (const CellSample& c : cell_samples) {
      const double f = model.cells()->cell_gain(c.top_gsd_cm, c.sub_gsd_cm, c.top) * c.top.gain_px();
      num += f * c.normalized_gain() * c.top.gain_px();
      den += f * f;
    }
  } else {
    for (const RegionSample& s : samples) {
      const GainForecast f = model.forecast(s.delta_h_m, s.sigma_top);
      num += f.relabelled * s.relabelled.interest_share;
      den += f.relabelled * f.relabelled;
    }
  }
  if (!(den > 0.0)) return std::nullopt;
  return num / den;
}

/// The folds' models with slope pooling `pooling` (with several fields pooled, each fold's
/// cell gain model refitted so), and `base` with the field factor's prior spread ω estimated
/// from them: the spread of s about 1 over the training fields (at least 0.1).
inline std::vector<GainModel> pooled_fold_models(const RuleSearchInputs& in, std::span<const FrontAwareFold> folds,
                                                 const FrontAwareGrid& grid, SlopePooling pooling,
                                                 FrontAwarePolicy::Params& base) {
  std::vector<GainModel> models;
  std::vector<double> scales;
  for (std::size_t k = 0; k < folds.size(); ++k) {
    GainModel m = folds[k].model;
    if (grid.pools) m.set_cells(CellGainModel::fit(folds[k].cells, in.adaptive.cell_input, pooling));
    if (in.fields.size() >= 2)  // several fields (grid.pools implies them)
      if (const auto s =
              field_scale(m, grid.pools, in.cells.empty() ? std::span<const CellSample>{} : in.cells[k], in.samples[k]))
        scales.push_back(*s);
    models.push_back(std::move(m));
  }
  if (scales.size() >= 2) {
    double ss = 0.0;
    for (double s : scales) ss += (s - 1.0) * (s - 1.0);
    base.scale_prior_sd = std::max(0.1, std::sqrt(ss / static_cast<double>(scales.size())));
  }
  return models;
}

/// One fold (every trial's and measuring flight's) flown by `fly` with the front-aware rule over
/// `model` and `params`, learning in flight unless CalibrationOptions::frozen_folds, σ̂'s prior
/// the fold's own estimate (estimated without its field) where asked for; `margin` its margin.
template <class Fly>
AdaptiveResult fly_fold(const RuleSearchInputs& in, const FrontAwareFold& fold, const GainModel& model,
                        FrontAwarePolicy::Params params, Fly& fly, double& margin) {
  params.online = !in.options.frozen_folds;
  apply_sigma_prior(params, fold.sigma_prior, in.options.sigma_prior);
  FrontAwarePolicy policy(model, fold.reference, params);
  return fly(*fold.field, policy, *fold.curve, margin);
}

/// The flights the gain ratios and margin biases are measured on: each training field flown
/// with the model of the others, the first slope pooling and top-level choice, z = 0 (the most
/// descents to learn from), no ratio or bias of its own.
template <class Fly>
std::vector<AdaptiveResult> measuring_flights(const RuleSearchInputs& in, std::span<const FrontAwareFold> folds,
                                              const FrontAwareGrid& grid, const FrontAwarePolicy::Params& base,
                                              Fly& fly) {
  FrontAwarePolicy::Params first = base;
  const std::vector<GainModel> models = pooled_fold_models(in, folds, grid, grid.poolings.front(), first);
  first.confidence = 0.0;
  first.top_level = grid.top_levels.front();
  first.gain_ratios.clear();
  first.margin_biases.clear();
  std::vector<AdaptiveResult> flights;
  for (std::size_t k = 0; k < folds.size(); ++k) {
    double margin = 0.0;
    flights.push_back(fly_fold(in, folds[k], models[k], first, fly, margin));
  }
  return flights;
}

/// The search's grid beyond z from the calibration options: the slope poolings (distinct ones,
/// several only where the cell gain model pools several fields) and the top-level choices
/// (several only with ranked cells).
[[nodiscard]] inline FrontAwareGrid front_aware_grid(const RuleSearchInputs& in) {
  const CalibrationOptions& options = in.options;
  FrontAwareGrid grid;
  grid.ranked = descent_coverage_info(in.adaptive.coverage).ranks_cells;
  grid.pools = grid.ranked && in.fields.size() >= 2;
  grid.poolings = grid.ranked ? distinct_poolings(options.slope_poolings, in.cells, in.adaptive.cell_input)
                              : options.slope_poolings;
  if (!grid.pools) grid.poolings.resize(1);
  grid.top_levels =
      options.top_levels.empty() ? std::vector<TopLevelChoice>{options.front_aware.top_level} : options.top_levels;
  if (!grid.ranked) grid.top_levels.resize(1);
  return grid;
}

/// Every fold's correction: the gain ratios and margin biases measured on the other folds'
/// flights only, as its model was fitted without its field, and the model's own (on every
/// fold's flight) into `base`; without `gain_ratios` and `margin_biases`, or with one field,
/// `base`'s for every fold. The jump bound, b, τ_r and ω_χ from the other fields' cells
/// (measure_on_cells()).
template <class Fly>
[[nodiscard]] std::vector<FoldCorrection> fold_corrections(const RuleSearchInputs& in,
                                                           std::span<const FrontAwareFold> folds,
                                                           const FrontAwareGrid& grid, FrontAwarePolicy::Params& base,
                                                           Fly& fly) {
  const CalibrationOptions& options = in.options;
  std::vector<FoldCorrection> c(folds.size(), FoldCorrection::of(base));
  if (grid.ranked && measures_on_cells(options))
    for (std::size_t k = 0; k < folds.size(); ++k)
      measure_on_cells(c[k], folds[k].cells, options, in.adaptive.cell_input);
  if (!(options.gain_ratios || options.margin_biases) || in.fields.size() < 2) return c;
  const std::vector<AdaptiveResult> flights = measuring_flights(in, folds, grid, base, fly);
  std::vector<const std::vector<CurvePoint>*> curves;
  for (const FrontAwareFold& f : folds) curves.push_back(f.curve);
  if (options.gain_ratios) {
    base.gain_ratios = fold_gain_ratios(flights);
    for (std::size_t k = 0; k < folds.size(); ++k) c[k].gain_ratios = fold_gain_ratios(flights, k);
  }
  if (options.margin_biases) {
    base.margin_biases = fold_margin_biases(flights, curves);
    for (std::size_t k = 0; k < folds.size(); ++k) c[k].margin_biases = fold_margin_biases(flights, curves, k);
  }
  return c;
}

/// Every fold flown with `params` (each with its own correction), into `t`.
template <class Fly>
void fly_trial(const RuleSearchInputs& in, std::span<const FrontAwareFold> folds, std::span<const GainModel> models,
               std::span<const FoldCorrection> corrections, const FrontAwarePolicy::Params& params, RuleTrial& t,
               Fly& fly) {
  for (std::size_t k = 0; k < folds.size(); ++k) {
    FrontAwarePolicy::Params fold_params = params;
    corrections[k].apply_to(fold_params);
    double margin = 0.0;
    const AdaptiveResult r = fly_fold(in, folds[k], models[k], fold_params, fly, margin);
    add_to_trial(t, r, margin);
  }
}

/// Setting `s` flown over `folds` (their `models` of its pooling, their `corrections`) as a
/// trial appended to `trials`, and `s` to `settings`; returns its index.
template <class Fly>
std::size_t add_trial(const RuleSearchInputs& in, std::span<const FrontAwareFold> folds,
                      std::span<const GainModel> models, std::span<const FoldCorrection> corrections,
                      const FrontAwareGrid& grid, std::vector<RuleTrial>& trials,
                      std::vector<FrontAwareSetting>& settings, FrontAwareSetting s, Fly& fly) {
  RuleTrial t;
  t.description = setting_text(in, grid, s);
  fly_trial(in, folds, models, corrections, s.params, t, fly);
  trials.push_back(std::move(t));
  settings.push_back(std::move(s));
  return trials.size() - 1;
}

/// The finest descent GSD kept (CalibrationOptions::finest_descent_gsd_cm, two or more): the
/// setting kept, `trials[best]` (flown with the first GSD of the list), flown over the same
/// `folds` (their `models` of its pooling, their `corrections`) with each other GSD, each a
/// trial and a setting appended to `trials` and `settings`; of them and `trials[best]`, the
/// first unless another beats it by more than one standard error of their paired margins
/// (select_pooling's rule, a gain on one fold alone never enough). Returns the index kept.
/// Which descent GSDs pay on new ground is a property of the candidates that no forecast of a
/// cell has shown to transfer (docs/method.md, "The finest descent chosen by the folds"); the
/// folds, each flown as new ground, see it.
template <class Fly>
std::size_t choose_finest_descent(const RuleSearchInputs& in, std::span<const FrontAwareFold> folds,
                                  std::span<const GainModel> models, std::span<const FoldCorrection> corrections,
                                  const FrontAwareGrid& grid, std::vector<RuleTrial>& trials,
                                  std::vector<FrontAwareSetting>& settings, std::size_t best, Fly& fly) {
  const std::vector<double>& finest = in.options.finest_descent_gsd_cm;
  std::vector<std::size_t> tried{best};
  for (std::size_t g = 1; g < finest.size(); ++g) {
    FrontAwareSetting s = settings[best];
    s.params.finest_descent_gsd_cm = finest[g];
    tried.push_back(add_trial(in, folds, models, corrections, grid, trials, settings, std::move(s), fly));
  }
  std::vector<const RuleTrial*> candidates;
  for (std::size_t k : tried) candidates.push_back(&trials[k]);
  return tried[select_pooling(candidates, fold_grounds(in))];
}

/// The longest descent kept (CalibrationOptions::longest_descent_s, two or more): with the
/// setting kept, `trials[best]` (flown with the first limit), each other limit flown over the
/// same `folds` with every z of the options' confidences, each a trial and a setting appended
/// to `trials` and `settings`, its z of best mean front margin kept (keeps_z_over); of
/// those and `trials[best]`, the first unless another beats it by more than one standard error
/// of their paired margins (select_pooling's rule). Returns the index kept. z is chosen again
/// with each limit: a limit that drops the long descents may pay with more of the short ones,
/// which only a smaller z takes (docs/method.md, "The longest descent chosen by the folds").
template <class Fly>
std::size_t choose_longest_descent(const RuleSearchInputs& in, std::span<const FrontAwareFold> folds,
                                   std::span<const GainModel> models, std::span<const FoldCorrection> corrections,
                                   const FrontAwareGrid& grid, std::vector<RuleTrial>& trials,
                                   std::vector<FrontAwareSetting>& settings, std::size_t best, Fly& fly) {
  const std::vector<double>& longest = in.options.longest_descent_s;
  std::vector<std::size_t> kept{best};
  for (std::size_t g = 1; g < longest.size(); ++g) {
    std::size_t of_limit = trials.size();
    for (double z : in.options.confidences) {
      FrontAwareSetting s = settings[best];
      s.z = z;
      s.params.confidence = z;
      s.params.longest_descent_s = longest[g];
      const std::size_t k = add_trial(in, folds, models, corrections, grid, trials, settings, std::move(s), fly);
      if (k == of_limit || keeps_z_over(trials, settings, k, of_limit)) of_limit = k;
    }
    kept.push_back(of_limit);
  }
  std::vector<const RuleTrial*> candidates;
  for (std::size_t k : kept) candidates.push_back(&trials[k]);
  return kept[select_pooling(candidates, fold_grounds(in))];
}

}  // namespace detail

/// The front-aware rule's calibration search (FrontAwareRule::search, which documents it):
/// every setting of `in.options` flown over the folds by `fly` (then, with several finest
/// descent GSDs, the one kept with each: detail::choose_finest_descent; with several longest
/// descents, each with every z: detail::choose_longest_descent), the one kept first in the
/// trials, the rule with it over the model of every field.
template <class Fly>
[[nodiscard]] RuleSearchResult search_front_aware(const RuleSearchInputs& in, Fly&& fly) {
  const CalibrationOptions& options = in.options;
  const std::vector<ReferenceCurve> reference(in.reference.begin(), in.reference.end());
  const detail::FrontAwareGrid grid = detail::front_aware_grid(in);
  const std::vector<TopLevelTrace> traces = detail::top_level_traces(in, reference, fly);
  const std::vector<detail::FrontAwareFold> folds = detail::front_aware_folds(in, reference, traces, grid.ranked);
  FrontAwarePolicy::Params base = options.front_aware;
  base.online = true;
  if (!options.finest_descent_gsd_cm.empty()) base.finest_descent_gsd_cm = options.finest_descent_gsd_cm.front();
  if (!options.longest_descent_s.empty()) base.longest_descent_s = options.longest_descent_s.front();
  detail::apply_sigma_prior(base, estimate_sigma_prior(traces), options.sigma_prior);
  const std::vector<detail::FoldCorrection> corrections = detail::fold_corrections(in, folds, grid, base, fly);
  std::vector<RuleTrial> trials;
  std::vector<detail::FrontAwareSetting> settings;
  std::vector<std::vector<GainModel>> models_of_pooling;
  for (std::size_t pi = 0; pi < grid.poolings.size(); ++pi) {
    FrontAwarePolicy::Params pooled = base;
    models_of_pooling.push_back(detail::pooled_fold_models(in, folds, grid, grid.poolings[pi], pooled));
    for (std::size_t ti = 0; ti < grid.top_levels.size(); ++ti)
      for (double z : options.confidences) {
        FrontAwarePolicy::Params p = pooled;
        p.confidence = z;
        p.top_level = grid.top_levels[ti];
        (void)detail::add_trial(in, folds, models_of_pooling.back(), corrections, grid, trials, settings,
                                {pi, ti, z, p}, fly);
      }
  }
  std::size_t best = detail::choose_setting(trials, settings, grid, detail::fold_grounds(in));
  if (options.finest_descent_gsd_cm.size() > 1)
    best = detail::choose_finest_descent(in, folds, models_of_pooling[settings[best].pooling], corrections, grid,
                                         trials, settings, best, fly);
  if (options.longest_descent_s.size() > 1)
    best = detail::choose_longest_descent(in, folds, models_of_pooling[settings[best].pooling], corrections, grid,
                                          trials, settings, best, fly);
  std::rotate(trials.begin(), trials.begin() + static_cast<std::ptrdiff_t>(best),
              trials.begin() + static_cast<std::ptrdiff_t>(best) + 1);
  // The model of every field, its cell gain model pooled as chosen.
  GainModel model = in.model;
  const SlopePooling pooling = grid.poolings[settings[best].pooling];
  if (grid.ranked && model.cells() && model.cells()->pooling() != pooling) {
    model.set_cells(CellGainModel::fit(cells_of_every_field(in.cells), in.adaptive.cell_input, pooling));
  }
  // Its jump bound, b, τ_r and ω_χ from every field's cells.
  FrontAwarePolicy::Params params = settings[best].params;
  if (grid.ranked && detail::measures_on_cells(options)) {
    detail::FoldCorrection whole = detail::FoldCorrection::of(params);
    detail::measure_on_cells(whole, cells_of_every_field(in.cells), options, in.adaptive.cell_input);
    whole.apply_to(params);
  }
  return {DecisionFunction(FrontAwarePolicy(std::move(model), reference, params)), std::move(trials)};
}

}  // namespace adaptseg
