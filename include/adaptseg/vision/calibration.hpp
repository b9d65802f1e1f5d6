#pragma once
/// @file
/// Offline initialisation on training fields (paper §3.2.2; method.md §4): collect the O, I and
/// C samples, fit the gain model, and choose the decision rule's settings on the training
/// fields only, by the front margin over each field's own lawnmower curve.

#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/mission.hpp>
#include <adaptseg/vision/region_samples.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace adaptseg {

/// The confidence levels z the front-aware rule's calibration tries by default.
inline const std::vector<double> kDefaultConfidences{0.0, 0.5, 1.0, 1.5, 2.0};

/// How to calibrate.
struct CalibrationOptions {
  /// Camera, timing, labels of interest (empty: the first field's), top and candidate GSDs,
  /// descent coverage. Its fixed segmentation and planning times are replaced by the two below.
  AdaptiveOptions adaptive{};
  /// GSDs of the training fields' lawnmower curves; empty: the candidate GSDs and the top GSD
  /// (lawnmower_gsds()), the curve the adaptive mission is compared with.
  std::vector<double> lawnmower_gsd_cm{};
  /// Segmentation time charged per image during calibration [s]: declared, not measured, so
  /// that the same inputs give the same model on any machine (recorded in the model file).
  double segmentation_time_s = 0.1;
  double planning_time_s = 0.0;            ///< planning time charged per waypoint [s]

  /// The lawnmower curve's GSDs: `lawnmower_gsd_cm`, or if it is empty the candidate GSDs
  /// and the top GSD, ascending.
  [[nodiscard]] std::vector<double> lawnmower_gsds() const {
    if (!lawnmower_gsd_cm.empty()) return lawnmower_gsd_cm;
    std::vector<double> g = adaptive.candidate_gsd_cm;
    g.push_back(adaptive.top_gsd_cm);
    std::sort(g.begin(), g.end());
    g.erase(std::unique(g.begin(), g.end()), g.end());
    return g;
  }
  /// DescentCoverage::ranked (`adaptive.coverage`): the decision inputs the cells may be ranked
  /// and forecast by; the one whose ranking captures most of the training fields' achievable
  /// gain is chosen (cell_ranking_capture(), each field scored on its own) and set as
  /// `adaptive.cell_input`; those the backend does not give (probabilities from a labels-only
  /// backend) are left out. Empty: the inputs about L (sigma, boundary, ambiguity,
  /// expected_error, second_choice); the generic ones, blind to which errors matter for L, are
  /// tried only when named.
  std::vector<DecisionInput> cell_inputs{};
  /// DescentCoverage::ranked: other top-level GSDs the cell gain model is calibrated for, so
  /// that a mission may fly its top level at one of them where the predicted lawnmower curve
  /// shows the model's top lawnmower dominated by a faster one on the field flown
  /// (FrontAwarePolicy::top_gsd). nullopt: the coarsest candidate GSD (the one that can be
  /// faster than the top where its grid fits the field better). Each must be a candidate GSD
  /// with a finer candidate below it.
  std::optional<std::vector<double>> alternative_top_gsd_cm{};
  GainModel::FitOptions fit{};             ///< what I predicts from, hyperparameter restarts
  int refit_every = 0;                     ///< O's scheduled re-optimisation (GainModel)

  /// Which rule the model holds: the FrontAwarePolicy (default; its confidence level z is
  /// chosen below) or the paper's UtilityPolicy (its threshold chosen below).
  enum class Rule { front_aware, utility };
  Rule rule = Rule::front_aware;

  /// Front-aware rule: `min_sigma`, `scale_prior_sd`, `sigma_prior_weight`
  /// and `sigma_prior_sd` as given (with several fields `scale_prior_sd` is estimated from
  /// their spread instead, and the last two as `sigma_prior` says); `confidence`
  /// chosen among `confidences` by the mean front margin over the training fields, each flown
  /// with a model fitted without it (one field: the field and its halves, with the model of
  /// the whole field). Ties (several z at which no training fold descends, or which take the
  /// same descents there) go to the larger z, the more cautious of settings the training
  /// fields cannot tell apart: whatever a smaller z would add on a new field has not been seen
  /// to pay on any of them (docs/results.md, "What any choice of z can buy").
  FrontAwarePolicy::Params front_aware{};
  std::vector<double> confidences = kDefaultConfidences;
  /// Front-aware rule, σ̂'s prior (FrontAwarePolicy `sigma_prior_weight` k, `sigma_prior_sd` τ)
  /// with several training fields: `given` keeps `front_aware`'s; `spread` estimates τ on the
  /// training fields (estimate_sigma_prior) and keeps k; `estimated` estimates both. Each fold
  /// of the z choice uses the values estimated without its field. One field: as given.
  enum class SigmaPriorSource { given, spread, estimated };
  SigmaPriorSource sigma_prior = SigmaPriorSource::given;

  /// Utility rule: `exploration` and `min_sigma` as given; thresholds searched (quantiles of
  /// the utilities seen, absolute and relative, σ weighting on and off, "never descend"), each
  /// flown over every layout (the fields; one field: the field and its halves) and scored by
  /// its worst front margin (ties: larger mean margin, then the relative rule, then shorter time).
  UtilityPolicy::Params utility{};
  int threshold_steps = 10;                ///< utility thresholds tried per weighting
};

/// One setting of the rule tried on the training fields.
struct RuleTrial {
  std::string description;      ///< e.g. "front-aware z=1" or "utility weight=1 relative=0 min_utility=..."
  double time_s = 0.0;          ///< mean over the layouts
  double miou_interest = 0.0;   ///< mean over the layouts
  double front_margin = 0.0;    ///< mean over the layouts
  double worst_margin = 0.0;    ///< smallest over the layouts
  int descents = 0;             ///< total over the layouts
  std::vector<double> margins;  ///< per layout
};

/// Everything calibration produced.
struct CalibrationResult {
  std::vector<RegionSample> samples;               ///< pooled over the fields (RegionSample::field)
  /// DescentCoverage::ranked: the cell samples, pooled (CellSample::field), and every input
  /// tried with its capture on the training fields (the chosen one first).
  std::vector<CellSample> cell_samples{};
  std::vector<std::pair<DecisionInput, double>> cell_input_scores{};
  DecisionFunction decision_function;              ///< fitted, with the chosen rule and settings
  LinearDecision::Params linear{};                 ///< σ range of the training fields' top-level images
  std::vector<std::vector<CurvePoint>> lawnmower_curves;  ///< per training field, at lawnmower_gsds()
  std::vector<RuleTrial> trials;                   ///< every setting tried, the chosen one first
};

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

/// An adaptive mission of `policy` over `field`, scored against `curve`.
template <SegmentationBackend Backend, DecisionPolicy Policy>
AdaptiveResult fly_scored(const Field& field, Backend& backend, Policy& policy, const AdaptiveOptions& options,
                          const std::vector<CurvePoint>& curve, double& margin) {
  AdaptiveResult r = run_adaptive_mission(field, backend, policy, options, policy.name());
  margin = front_margin(curve, r.mission.total_s(), r.mission.miou_interest().value_or(0.0));
  return r;
}

/// Adds one layout's run to a trial.
inline void add_to_trial(RuleTrial& t, const AdaptiveResult& r, double margin) {
  const double k = static_cast<double>(t.margins.size());
  t.time_s = (t.time_s * k + r.mission.total_s()) / (k + 1.0);
  t.miou_interest = (t.miou_interest * k + r.mission.miou_interest().value_or(0.0)) / (k + 1.0);
  t.front_margin = (t.front_margin * k + margin) / (k + 1.0);
  t.worst_margin = t.margins.empty() ? margin : std::min(t.worst_margin, margin);
  t.descents += r.descents();
  t.margins.push_back(margin);
}

/// A utility threshold for people: 4 significant digits; the lowest and highest doubles,
/// which stand for "descend whenever the rule can" and "never descend", by name.
inline std::string threshold_text(double t) {
  if (t <= std::numeric_limits<double>::lowest()) return "-inf (always)";
  if (t >= std::numeric_limits<double>::max()) return "+inf (never)";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.4g", t);
  return buf;
}

inline std::string z_text(double z) {
  std::string s = format_number(z);
  return "front-aware z=" + s;
}

}  // namespace detail

/// Calibrates on the training `fields` with `backend` (the backend the missions will use).
///
/// 1. Region samples at every top-level region × candidate GSD of every field, pooled
///    (collect_region_samples).
/// 2. The gain model fitted to them (GainModel::fit).
/// 3. Each field's lawnmower curve at `lawnmower_gsds()`: the front-aware rule's reference curves.
/// 4. The rule's settings chosen on the training fields (CalibrationOptions::rule).
/// 5. The linear baseline's σ range: the 5th and 95th percentiles of σ at h_max.
/// @throws std::invalid_argument for no field, fields with other class sets, invalid options
///         (see run_adaptive_mission and collect_region_samples), or fields without a sample.
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationResult calibrate(std::span<const Field> fields, Backend& backend,
                                          const CalibrationOptions& options) {
  detail::require(!fields.empty(), "calibrate: at least one training field is needed; count", fields.size());
  const std::vector<double> lawnmower_gsd = options.lawnmower_gsds();
  detail::require(options.threshold_steps >= 1, "calibrate: threshold_steps must be >= 1", options.threshold_steps);
  detail::require(std::isfinite(options.segmentation_time_s) && options.segmentation_time_s >= 0.0,
                  "calibrate: segmentation_time_s must be finite and >= 0", options.segmentation_time_s);
  detail::require(!options.confidences.empty(), "calibrate: confidences must not be empty", 0);
  const auto names = [](const Field& f) {
    std::vector<std::string> v;
    for (const auto& c : f.classes()) v.push_back(c.name);
    return v;
  };
  for (const Field& f : fields)
    detail::require(names(f) == names(fields.front()),
                    "calibrate: every training field must have the first field's classes; field", f.name());
  AdaptiveOptions adaptive = options.adaptive;
  if (adaptive.mission.interest.empty()) adaptive.mission.interest = fields.front().interest();
  detail::require(!adaptive.mission.interest.empty(), "calibrate: no labels of interest", 0);
  adaptive.mission.fixed_segmentation_time_s = options.segmentation_time_s;
  adaptive.mission.fixed_planning_time_s = options.planning_time_s;
  const std::vector<int>& interest = adaptive.mission.interest;
  const CameraModel camera(adaptive.mission.camera);

  const bool ranked = adaptive.coverage == DescentCoverage::ranked;
  std::vector<double> alternative_tops;
  if (ranked) {
    std::vector<double> c = adaptive.candidate_gsd_cm;
    std::sort(c.begin(), c.end());
    if (options.alternative_top_gsd_cm)
      alternative_tops = *options.alternative_top_gsd_cm;
    else if (c.size() >= 2)
      alternative_tops = {c.back()};
    for (double a : alternative_tops)
      detail::require(std::find(c.begin(), c.end(), a) != c.end() && a > c.front(),
                      "calibrate: an alternative top GSD must be a candidate GSD with a finer candidate below it", a);
  }
  std::vector<RegionSample> samples;
  std::vector<std::vector<RegionSample>> by_field;
  std::vector<CellSample> cell_samples;
  std::vector<std::vector<CellSample>> cells_by_field;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    CalibrationSamples c = collect_samples(fields[k], backend, camera, adaptive.top_gsd_cm, adaptive.candidate_gsd_cm,
                                           interest, adaptive.coverage, k);
    by_field.push_back(std::move(c.regions));
    detail::require(!by_field.back().empty(), "calibrate: the training field gave no region sample", fields[k].name());
    samples.insert(samples.end(), by_field.back().begin(), by_field.back().end());
    cells_by_field.push_back(std::move(c.cells));
    // The cells as seen from the alternative top levels, re-mapped at the candidates below them.
    for (double top : ranked ? alternative_tops : std::vector<double>{}) {
      std::vector<double> below;
      for (double g : adaptive.candidate_gsd_cm)
        if (g < top) below.push_back(g);
      CalibrationSamples alt = collect_samples(fields[k], backend, camera, top, below, interest, adaptive.coverage, k);
      cells_by_field.back().insert(cells_by_field.back().end(), alt.cells.begin(), alt.cells.end());
    }
    cell_samples.insert(cell_samples.end(), cells_by_field.back().begin(), cells_by_field.back().end());
  }
  // DescentCoverage::ranked: the input that ranks the training fields' cells best.
  std::vector<std::pair<DecisionInput, double>> input_scores;
  if (ranked) {
    detail::require(!cell_samples.empty(), "calibrate: the training fields gave no cell sample", fields.front().name());
    std::vector<DecisionInput> tried = options.cell_inputs;
    if (tried.empty())
      tried = {DecisionInput::sigma, DecisionInput::boundary, DecisionInput::ambiguity, DecisionInput::expected_error,
               DecisionInput::second_choice};
    for (DecisionInput i : tried) {
      // An input the backend cannot give (probabilities from a labels-only backend) is unknown
      // on every cell.
      const bool known = std::any_of(cell_samples.begin(), cell_samples.end(),
                                     [&](const CellSample& c) { return std::isfinite(c.top.value(i)); });
      if (known) input_scores.emplace_back(i, cell_ranking_capture(cell_samples, i));
    }
    detail::require(!input_scores.empty(), "calibrate: no decision input to rank the cells by is known from this backend; inputs tried",
                    tried.size());
    // Best capture first; ties keep the table's order; an input without a score last.
    const auto score = [](double v) { return std::isnan(v) ? -std::numeric_limits<double>::infinity() : v; };
    std::stable_sort(input_scores.begin(), input_scores.end(),
                     [&](const auto& a, const auto& b) { return score(a.second) > score(b.second); });
    adaptive.cell_input = input_scores.front().first;
  }
  const auto curve_of = [&](const Field& f) {
    std::vector<CurvePoint> c;
    for (double g : lawnmower_gsd) {
      const MissionResult r = run_lawnmower_mission(f, g, backend, adaptive.mission);
      c.push_back({r.total_s(), r.miou_interest().value_or(0.0)});
    }
    return c;
  };
  std::vector<std::vector<CurvePoint>> curves;
  std::vector<ReferenceCurve> reference;
  for (std::size_t f = 0; f < fields.size(); ++f) {
    curves.push_back(curve_of(fields[f]));
    ReferenceCurve r{fields[f].name(), {}, by_field[f].front().field_sigma};
    for (std::size_t k = 0; k < lawnmower_gsd.size(); ++k)
      r.points.push_back({lawnmower_gsd[k], curves.back()[k].miou});
    reference.push_back(std::move(r));
  }
  // What each training field's top-level images show along the flight, where σ̂'s prior is
  // estimated from them (one top-level mission per field).
  std::vector<TopLevelTrace> traces;
  const bool fit_sigma_prior = options.rule == CalibrationOptions::Rule::front_aware && fields.size() >= 2 &&
                               options.sigma_prior != CalibrationOptions::SigmaPriorSource::given;
  for (std::size_t f = 0; fit_sigma_prior && f < fields.size(); ++f) {
    detail::TopLevelRecorder recorder;
    (void)run_adaptive_mission(fields[f], backend, recorder, adaptive, recorder.name());
    recorder.trace.field_sigma = reference[f].field_sigma;
    traces.push_back(std::move(recorder.trace));
  }
  GainModel::FitOptions fit = options.fit;
  GainModel model = GainModel::fit(samples, fit);
  model.set_refit_every(options.refit_every);
  if (ranked) {
    model.set_cells(CellGainModel::fit(cell_samples, adaptive.cell_input));
    // Each training field's mean input at each top level the cells were sampled from (the
    // prior of a new field's): the cells of one descent GSD tile its regions.
    for (std::size_t f = 0; f < fields.size(); ++f) {
      for (const double top : model.cells()->top_gsds()) {
        double sub = 0.0;  // the coarsest descent GSD sampled from this top
        for (const CellSample& c : cells_by_field[f])
          if (detail::same_gsd(c.top_gsd_cm, top)) sub = std::max(sub, c.sub_gsd_cm);
        double mass = 0.0, px = 0.0;
        for (const CellSample& c : cells_by_field[f])
          if (detail::same_gsd(c.top_gsd_cm, top) && detail::same_gsd(c.sub_gsd_cm, sub))
            mass += c.top.mass(adaptive.cell_input), px += c.top.field_px;
        const double input = px > 0.0 ? mass / px : 0.0;
        if (detail::same_gsd(top, adaptive.top_gsd_cm)) reference[f].field_input = input;
        reference[f].top_inputs.emplace_back(top, input);
      }
    }
  }

  // Layouts of a single field: the field and its halves across the longer axis.
  std::vector<Field> halves;
  std::vector<std::vector<CurvePoint>> half_curves;
  if (fields.size() == 1) {
    const Field& f = fields.front();
    const bool wide = f.width_px() >= f.height_px();
    halves.push_back(f.sub_field(wide ? FieldRegion{0, 0, 0.5, 1} : FieldRegion{0, 0, 1, 0.5}));
    halves.push_back(f.sub_field(wide ? FieldRegion{0.5, 0, 1, 1} : FieldRegion{0, 0.5, 1, 1}));
    for (const Field& h : halves) half_curves.push_back(curve_of(h));
  }

  std::vector<RuleTrial> trials;
  std::optional<DecisionFunction> chosen;
  if (options.rule == CalibrationOptions::Rule::front_aware) {
    FrontAwarePolicy::Params base = options.front_aware;
    base.online = true;
    // One fold per training field, its model fitted without it (one field: its layouts, the
    // whole field's model).
    struct Fold {
      const Field* field;
      const std::vector<CurvePoint>* curve;
      GainModel model;
      std::vector<ReferenceCurve> reference;
      std::optional<SigmaPrior> sigma_prior;  ///< estimated without the field
    };
    std::vector<Fold> folds;
    std::vector<double> field_scales;
    if (fields.size() == 1) {
      folds.push_back({&fields.front(), &curves.front(), model, reference, std::nullopt});
      for (std::size_t k = 0; k < halves.size(); ++k)
        folds.push_back({&halves[k], &half_curves[k], model, reference, std::nullopt});
    } else {
      for (std::size_t k = 0; k < fields.size(); ++k) {
        std::vector<RegionSample> rest;
        std::vector<ReferenceCurve> rest_reference;
        std::vector<TopLevelTrace> rest_traces;
        for (std::size_t j = 0; j < fields.size(); ++j)
          if (j != k) {
            rest.insert(rest.end(), by_field[j].begin(), by_field[j].end());
            rest_reference.push_back(reference[j]);
            if (fit_sigma_prior) rest_traces.push_back(traces[j]);
          }
        GainModel m = GainModel::fit(rest, fit);
        m.set_refit_every(options.refit_every);
        double num = 0.0, den = 0.0;
        if (ranked) {
          // The field factor s of this field under the cell model that did not see it: the
          // least-squares scale of the cells' forecast gains onto their realised gains.
          std::vector<CellSample> rest_cells;
          for (std::size_t j = 0; j < fields.size(); ++j)
            if (j != k) rest_cells.insert(rest_cells.end(), cells_by_field[j].begin(), cells_by_field[j].end());
          m.set_cells(CellGainModel::fit(rest_cells, adaptive.cell_input));
          for (const CellSample& c : cells_by_field[k]) {
            const double f = m.cells()->cell_gain(c.top_gsd_cm, c.sub_gsd_cm, c.top) * c.top.field_px;
            num += f * c.normalized_gain() * c.top.field_px;
            den += f * f;
          }
        } else {
          // The field factor s of this field under the model that did not see it: the
          // least-squares scale of C's forecasts onto what its descents relabelled.
          for (const RegionSample& s : by_field[k]) {
            const GainForecast f = m.forecast(s.delta_h_m, s.sigma_top);
            num += f.relabelled * s.relabelled.interest_share;
            den += f.relabelled * f.relabelled;
          }
        }
        if (den > 0.0) field_scales.push_back(num / den);
        folds.push_back({&fields[k], &curves[k], std::move(m), std::move(rest_reference),
                         estimate_sigma_prior(rest_traces)});
      }
    }
    if (field_scales.size() >= 2) {  // ω: the spread of s about 1 over the training fields
      double ss = 0.0;
      for (double s : field_scales) ss += (s - 1.0) * (s - 1.0);
      base.scale_prior_sd = std::max(0.1, std::sqrt(ss / static_cast<double>(field_scales.size())));
    }
    const auto apply_prior = [&](FrontAwarePolicy::Params& p, const std::optional<SigmaPrior>& prior) {
      if (!prior || options.sigma_prior == CalibrationOptions::SigmaPriorSource::given) return;
      p.sigma_prior_sd = prior->sd;
      if (options.sigma_prior == CalibrationOptions::SigmaPriorSource::estimated) p.sigma_prior_weight = prior->weight;
    };
    apply_prior(base, estimate_sigma_prior(traces));
    for (double z : options.confidences) {
      RuleTrial t;
      t.description = detail::z_text(z);
      FrontAwarePolicy::Params p = base;
      p.confidence = z;
      for (const Fold& fold : folds) {
        FrontAwarePolicy::Params fold_params = p;  // σ̂'s prior: the fold's estimate replaces all fields'
        apply_prior(fold_params, fold.sigma_prior);
        FrontAwarePolicy policy(fold.model, fold.reference, fold_params);
        double margin = 0.0;
        const AdaptiveResult r = detail::fly_scored(*fold.field, backend, policy, adaptive, *fold.curve, margin);
        detail::add_to_trial(t, r, margin);
      }
      trials.push_back(std::move(t));
    }
    std::size_t best = 0;
    for (std::size_t k = 1; k < trials.size(); ++k)
      if (trials[k].front_margin > trials[best].front_margin ||
          (trials[k].front_margin == trials[best].front_margin && options.confidences[k] > options.confidences[best]))
        best = k;
    base.confidence = options.confidences[best];
    chosen = DecisionFunction(FrontAwarePolicy(model, reference, base));
    std::rotate(trials.begin(), trials.begin() + static_cast<std::ptrdiff_t>(best),
                trials.begin() + static_cast<std::ptrdiff_t>(best) + 1);
  } else {
    std::vector<const Field*> layouts;
    std::vector<const std::vector<CurvePoint>*> layout_curves;
    for (std::size_t k = 0; k < fields.size(); ++k) layouts.push_back(&fields[k]), layout_curves.push_back(&curves[k]);
    for (std::size_t k = 0; k < halves.size(); ++k) layouts.push_back(&halves[k]), layout_curves.push_back(&half_curves[k]);
    struct Tried {
      RuleTrial trial;
      UtilityPolicy::Params params;
    };
    std::vector<Tried> tried;
    const auto fly = [&](const UtilityPolicy::Params& p, std::vector<double>* utilities) {
      Tried c{{}, p};
      c.trial.description = "utility weight=" + std::to_string(p.weight_by_sigma ? 1 : 0) +
                            " relative=" + std::to_string(p.relative_utility ? 1 : 0) +
                            " min_utility=" + detail::threshold_text(p.min_utility);
      for (std::size_t k = 0; k < layouts.size(); ++k) {
        UtilityPolicy policy(model, p);
        double margin = 0.0;
        const AdaptiveResult r = detail::fly_scored(*layouts[k], backend, policy, adaptive, *layout_curves[k], margin);
        if (utilities && k == 0)
          for (const auto& d : r.decisions)
            for (const auto& s : d.decision.scores)
              if (std::isfinite(s.utility) && s.utility > 0.0) utilities->push_back(s.utility);
        detail::add_to_trial(c.trial, r, margin);
      }
      tried.push_back(std::move(c));
    };
    UtilityPolicy::Params probe = options.utility;
    probe.online = true;
    probe.min_utility = -std::numeric_limits<double>::max();
    for (bool weight : {true, false}) {
      probe.weight_by_sigma = weight;
      probe.relative_utility = false;
      std::vector<double> utilities;
      fly(probe, &utilities);  // descends wherever the predicted gain is positive
      std::sort(utilities.begin(), utilities.end());
      // Absolute thresholds: quantiles spread evenly, plus the top tail where only the best
      // regions qualify.
      std::vector<double> quantiles;
      for (int k = 0; k < options.threshold_steps; ++k)
        quantiles.push_back(static_cast<double>(k) / options.threshold_steps);
      for (double q : {0.93, 0.96, 0.99}) quantiles.push_back(q);
      for (double q : quantiles) {
        if (utilities.empty()) break;
        UtilityPolicy::Params p = probe;
        p.min_utility = utilities[static_cast<std::size_t>(q * static_cast<double>(utilities.size() - 1))];
        fly(p, nullptr);
      }
      // Relative thresholds: a region's best utility over the mission's running mean.
      for (int k = 0; k < options.threshold_steps; ++k) {
        UtilityPolicy::Params p = probe;
        p.relative_utility = true;
        p.min_utility = 1.0 + 2.0 * static_cast<double>(k) / options.threshold_steps;
        fly(p, nullptr);
      }
      UtilityPolicy::Params never = probe;  // the top-level lawnmower alone
      never.min_utility = std::numeric_limits<double>::max();
      fly(never, nullptr);
    }
    std::stable_sort(tried.begin(), tried.end(), [](const Tried& a, const Tried& b) {
      if (a.trial.worst_margin != b.trial.worst_margin) return a.trial.worst_margin > b.trial.worst_margin;
      if (a.trial.front_margin != b.trial.front_margin) return a.trial.front_margin > b.trial.front_margin;
      // Equal on the training fields: prefer the scale-free rule, which transfers to fields
      // whose σ levels differ.
      if (a.params.relative_utility != b.params.relative_utility) return a.params.relative_utility;
      return a.trial.time_s < b.trial.time_s;
    });
    chosen = DecisionFunction(UtilityPolicy(model, tried.front().params));
    for (auto& c : tried) trials.push_back(std::move(c.trial));
  }

  std::vector<double> sig;
  for (const auto& s : samples) sig.push_back(s.sigma_top);
  std::sort(sig.begin(), sig.end());
  const auto pct = [&](double q) { return sig[static_cast<std::size_t>(q * static_cast<double>(sig.size() - 1))]; };
  LinearDecision::Params linear{pct(0.05), pct(0.95)};
  if (!(linear.sigma_high > linear.sigma_low)) linear = {0.0, std::max(1e-6, sig.back())};
  linear.sigma_high = std::min(1.0, linear.sigma_high);
  return CalibrationResult{std::move(samples),     std::move(cell_samples), std::move(input_scores),
                           std::move(*chosen),     linear,                  std::move(curves),
                           std::move(trials)};
}

/// The single-field case (the paper's).
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationResult calibrate(const Field& train, Backend& backend, const CalibrationOptions& options) {
  return calibrate(std::span<const Field>(&train, 1), backend, options);
}

/// The model file's content for a calibration on `fields` with the backend named `segmenter`:
/// the fitted decision function, the linear baseline, and what they were calibrated for.
[[nodiscard]] inline DecisionModel make_decision_model(std::span<const Field> fields, const std::string& segmenter,
                                                       const CalibrationOptions& options,
                                                       const CalibrationResult& calibration) {
  DecisionModel m{.calibration_fields = {},
                  .segmenter = segmenter,
                  .calibration_segmentation_time_s = options.segmentation_time_s,
                  .classes = {},
                  .interest = {},
                  .camera = options.adaptive.mission.camera,
                  .timing = options.adaptive.mission.timing,
                  .top_gsd_cm = options.adaptive.top_gsd_cm,
                  .candidate_gsd_cm = options.adaptive.candidate_gsd_cm,
                  .coverage = options.adaptive.coverage,
                  .decision_function = calibration.decision_function,
                  .linear = calibration.linear,
                  .samples = calibration.samples.size(),
                  .train_front_margin = calibration.trials.empty() ? 0.0 : calibration.trials.front().front_margin};
  const Field& first = fields.front();
  for (const Field& f : fields) m.calibration_fields.push_back(f.name());
  for (const auto& c : first.classes()) m.classes.push_back(c.name);
  const auto& interest = options.adaptive.mission.interest.empty() ? first.interest() : options.adaptive.mission.interest;
  for (int i : interest) m.interest.push_back(first.classes().at(static_cast<std::size_t>(i)).name);
  return m;
}

/// The single-field case.
[[nodiscard]] inline DecisionModel make_decision_model(const Field& train, const std::string& segmenter,
                                                       const CalibrationOptions& options,
                                                       const CalibrationResult& calibration) {
  return make_decision_model(std::span<const Field>(&train, 1), segmenter, options, calibration);
}

}  // namespace adaptseg
