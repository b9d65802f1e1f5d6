#pragma once
/// @file
/// Offline initialisation on training fields (paper §3.2.2; docs/method.md, "The decision
/// function"): collect the O, I and
/// C samples, fit the gain model, and choose the decision rule's settings on the training
/// fields only, by the front margin over each field's own lawnmower curve.

#include <adaptseg/core/cell_input_scores.hpp>
#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/detail/gsd.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/calibration_options.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/decision_rules.hpp>
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

/// Refuses options calibrate() cannot use, before it reads a field: a declared segmentation
/// time that is negative or not finite, an unknown rule, or settings the rule cannot search
/// (the rule's check_options, e.g. an empty or repeated list of settings to try).
/// @throws std::invalid_argument naming the option.
inline void check_calibration_options(const CalibrationOptions& options) {
  detail::require(std::isfinite(options.segmentation_time_s) && options.segmentation_time_s >= 0.0,
                  "calibrate: segmentation_time_s must be finite and >= 0", options.segmentation_time_s);
  detail::require(is_rule_name(options.rule), "calibrate: the rule must be " + rule_names_text() + "; rule",
                  options.rule);
  for_each_rule([&]<class Rule>() {
    if (options.rule == Rule::kName) Rule::check_options(options);
  });
}

namespace detail {

/// calibrate()'s settings of the adaptive missions it flies: `options.adaptive` with the labels
/// of interest filled from the first field, and the declared segmentation and planning times.
/// @throws std::invalid_argument for no field, fields with other class sets than the first's,
///         invalid options (check_calibration_options), gain ratios or margin biases asked of
///         one field or with field grounds, field grounds not one per field or all one (the
///         folds need two), or no label of interest.
[[nodiscard]] inline AdaptiveOptions calibration_settings(std::span<const Field> fields,
                                                          const CalibrationOptions& options) {
  require(!fields.empty(), "calibrate: at least one training field is needed; count", fields.size());
  check_calibration_options(options);
  require(fields.size() >= 2 || !(options.gain_ratios || options.margin_biases),
          "calibrate: gain_ratios and margin_biases are measured by flying each training field with the model of "
          "the others, which needs at least two training fields; count",
          fields.size());
  require(options.field_grounds.empty() || options.field_grounds.size() == fields.size(),
          "calibrate: field_grounds needs one ground per training field (or none); count",
          options.field_grounds.size());
  require(fields.size() < 2 || options.field_grounds.empty() ||
              std::any_of(options.field_grounds.begin(), options.field_grounds.end(),
                          [&](std::size_t g) { return g != options.field_grounds.front(); }),
          "calibrate: every training field is of one ground (field_grounds: one field seen by several networks), "
          "and each fold leaves its ground out: give another field; fields",
          fields.size());
  require(options.field_grounds.empty() || !(options.gain_ratios || options.margin_biases),
          "calibrate: gain_ratios and margin_biases leave one fold's flight out, not its ground's: not with "
          "field_grounds; grounds",
          options.field_grounds.size());
  const auto names = [](const Field& f) {
    std::vector<std::string> v;
    for (const auto& c : f.classes()) v.push_back(c.name);
    return v;
  };
  for (const Field& f : fields)
    require(names(f) == names(fields.front()),
            "calibrate: every training field must have the first field's classes; field", f.name());
  AdaptiveOptions adaptive = options.adaptive;
  if (adaptive.mission.interest.empty()) adaptive.mission.interest = fields.front().interest();
  require(!adaptive.mission.interest.empty(), "calibrate: no labels of interest", 0);
  adaptive.mission.fixed_segmentation_time_s = options.segmentation_time_s;
  adaptive.mission.fixed_planning_time_s = options.planning_time_s;
  return adaptive;
}

/// A coverage that ranks cells: the other top levels its cells are also sampled from
/// (CalibrationOptions::alternative_top_gsd_cm, by default the coarsest candidate when there
/// are two or more).
/// @throws std::invalid_argument for one that is not a candidate with a finer candidate below it.
[[nodiscard]] inline std::vector<double> alternative_top_gsds(const CalibrationOptions& options) {
  std::vector<double> c = options.adaptive.candidate_gsd_cm;
  std::sort(c.begin(), c.end());
  std::vector<double> tops;
  if (options.alternative_top_gsd_cm)
    tops = *options.alternative_top_gsd_cm;
  else if (c.size() >= 2)
    tops = {c.back()};
  for (double a : tops)
    require(std::find(c.begin(), c.end(), a) != c.end() && a > c.front(),
            "calibrate: an alternative top GSD must be a candidate GSD with a finer candidate below it", a);
  return tops;
}

/// The decision inputs `tried` (empty: the inputs about L) that the pooled training cells know,
/// each with its `score` (cell_input_score(): the share of the achievable gain its ranking
/// captures), best first; ties keep the order tried, an input without a score comes last.
/// @throws std::invalid_argument for no cell, or no input the backend gives.
[[nodiscard]] inline std::vector<std::pair<DecisionInput, double>> score_cell_inputs(
    const std::vector<CellSample>& cells, std::vector<DecisionInput> tried, CellInputScore score,
    const std::string& field) {
  require(!cells.empty(), "calibrate: the training fields gave no cell sample", field);
  if (tried.empty())
    tried = {DecisionInput::sigma, DecisionInput::boundary, DecisionInput::ambiguity, DecisionInput::expected_error,
             DecisionInput::second_choice};
  std::vector<std::pair<DecisionInput, double>> scores;
  for (DecisionInput i : tried) {
    // An input the backend cannot give (probabilities from a labels-only backend) is unknown
    // on every cell.
    const bool known =
        std::any_of(cells.begin(), cells.end(), [&](const CellSample& c) { return std::isfinite(c.top.value(i)); });
    if (known) scores.emplace_back(i, cell_input_score(score, cells, i));
  }
  require(!scores.empty(), "calibrate: no decision input to rank the cells by is known from this backend; inputs tried",
          tried.size());
  const auto value = [](double v) { return std::isnan(v) ? -std::numeric_limits<double>::infinity() : v; };
  std::stable_sort(scores.begin(), scores.end(),
                   [&](const auto& a, const auto& b) { return value(a.second) > value(b.second); });
  return scores;
}

/// Each training field's mean `input` at each top level its cells were sampled from (the cell
/// gain model's top GSDs; the prior of a new field's), into `reference` (ReferenceCurve::
/// top_inputs, and field_input at `top_gsd_cm`): over the cells of the coarsest descent GSD,
/// which tile the field's regions.
inline void set_field_inputs(std::vector<ReferenceCurve>& reference,
                             const std::vector<std::vector<CellSample>>& cells_by_field, const CellGainModel& cells,
                             DecisionInput input, double top_gsd_cm) {
  for (std::size_t f = 0; f < reference.size(); ++f) {
    for (const double top : cells.top_gsds()) {
      double sub = 0.0;  // the coarsest descent GSD sampled from this top
      for (const CellSample& c : cells_by_field[f])
        if (same_gsd(c.top_gsd_cm, top)) sub = std::max(sub, c.sub_gsd_cm);
      double mass = 0.0, px = 0.0;
      for (const CellSample& c : cells_by_field[f])
        if (same_gsd(c.top_gsd_cm, top) && same_gsd(c.sub_gsd_cm, sub)) mass += c.top.mass(input), px += c.top.field_px;
      const double value = px > 0.0 ? mass / px : 0.0;
      if (same_gsd(top, top_gsd_cm)) reference[f].field_input = value;
      reference[f].top_inputs.emplace_back(top, value);
    }
  }
}

/// The linear baseline's σ range: the 5th and 95th percentiles of σ at h_max over `samples`
/// (non-empty).
[[nodiscard]] inline LinearDecision::Params linear_sigma_range(const std::vector<RegionSample>& samples) {
  std::vector<double> sig;
  for (const auto& s : samples) sig.push_back(s.sigma_top);
  std::sort(sig.begin(), sig.end());
  const auto pct = [&](double q) { return sig[static_cast<std::size_t>(q * static_cast<double>(sig.size() - 1))]; };
  LinearDecision::Params linear{pct(0.05), pct(0.95)};
  if (!(linear.sigma_high > linear.sigma_low)) linear = {0.0, std::max(1e-6, sig.back())};
  linear.sigma_high = std::min(1.0, linear.sigma_high);
  return linear;
}

/// Every training field's samples (collect_samples): the regions pooled and per field, the cells
/// per field (cells_of_every_field pools them); with a coverage that ranks cells, the cells also
/// as seen from the alternative top levels (alternative_top_gsds), re-mapped at the candidates
/// below them.
struct TrainingSamples {
  std::vector<RegionSample> samples;
  std::vector<std::vector<RegionSample>> by_field;
  std::vector<std::vector<CellSample>> cells_by_field;
};

template <SegmentationBackend Backend>
[[nodiscard]] TrainingSamples collect_training_samples(std::span<const Field> fields,
                                                       std::span<Backend* const> backends, const CameraModel& camera,
                                                       const AdaptiveOptions& adaptive,
                                                       const CalibrationOptions& options) {
  const std::vector<int>& interest = adaptive.mission.interest;
  const bool ranked = descent_coverage_info(adaptive.coverage).ranks_cells;
  const std::vector<double> alternative_tops = ranked ? alternative_top_gsds(options) : std::vector<double>{};
  TrainingSamples t;
  for (std::size_t k = 0; k < fields.size(); ++k) {
    CalibrationSamples c = collect_samples(
        fields[k], *backends[k], camera, adaptive.top_gsd_cm, adaptive.candidate_gsd_cm, interest, adaptive.coverage, k,
        adaptive.mission.map_fusion, options.frame_check, adaptive.descent_grid, adaptive.gain_extent);
    t.by_field.push_back(std::move(c.regions));
    require(!t.by_field.back().empty(), "calibrate: the training field gave no region sample", fields[k].name());
    t.samples.insert(t.samples.end(), t.by_field.back().begin(), t.by_field.back().end());
    t.cells_by_field.push_back(std::move(c.cells));
    for (double top : alternative_tops) {
      std::vector<double> below;
      for (double g : adaptive.candidate_gsd_cm)
        if (g < top) below.push_back(g);
      CalibrationSamples alt = collect_samples(fields[k], *backends[k], camera, top, below, interest, adaptive.coverage,
                                               k, adaptive.mission.map_fusion, options.frame_check,
                                               adaptive.descent_grid, adaptive.gain_extent);
      t.cells_by_field.back().insert(t.cells_by_field.back().end(), alt.cells.begin(), alt.cells.end());
    }
  }
  return t;
}

/// The training fields' backends as the rule search flies them: a field's own, or the single
/// field's for its halves; and a field's lawnmower curve at the lawnmower GSDs.
template <SegmentationBackend Backend>
struct TrainingBackends {
  std::span<const Field> fields;
  std::span<Backend* const> backends;
  const std::vector<double>& lawnmower_gsd;
  const MissionOptions& mission;

  [[nodiscard]] Backend& of(const Field& f) const {
    for (std::size_t k = 0; k < fields.size(); ++k)
      if (&f == &fields[k]) return *backends[k];
    require(fields.size() == 1, "calibrate: the rule search flew a field that is not a training field", f.name());
    return *backends.front();
  }
  [[nodiscard]] std::vector<CurvePoint> curve(const Field& f) const {
    std::vector<CurvePoint> c;
    for (double g : lawnmower_gsd) {
      const MissionResult r = run_lawnmower_mission(f, g, of(f), mission);
      c.push_back({r.total_s(), r.miou_interest().value_or(0.0)});
    }
    return c;
  }
};

/// A single training field's halves across its longer axis (the rule search flies the field
/// and its halves); none for several fields.
[[nodiscard]] inline std::vector<Field> single_field_halves(std::span<const Field> fields) {
  std::vector<Field> halves;
  if (fields.size() != 1) return halves;
  const Field& f = fields.front();
  const bool wide = f.width_px() >= f.height_px();
  halves.push_back(f.sub_field(wide ? FieldRegion{0, 0, 0.5, 1} : FieldRegion{0, 0, 1, 0.5}));
  halves.push_back(f.sub_field(wide ? FieldRegion{0.5, 0, 1, 1} : FieldRegion{0, 0.5, 1, 1}));
  return halves;
}

}  // namespace detail

/// Calibrates on the training `fields`, `backends[k]` segmenting `fields[k]`.
///
/// 1. Region samples at every top-level region × candidate GSD of every field, pooled
///    (collect_samples); with a coverage that ranks cells also cell samples, from the top level
///    and the alternative ones (detail::alternative_top_gsds), and the input that ranks them
///    best (detail::score_cell_inputs).
/// 2. The gain model fitted to them (GainModel::fit; CellGainModel::fit for the cells).
/// 3. Each field's lawnmower curve at `lawnmower_gsds()`: the front-aware rule's reference curves.
/// 4. The rule's settings chosen on the training fields by its own search (the entry of
///    DecisionRules named by CalibrationOptions::rule: FrontAwareRule::search,
///    UtilityRule::search).
/// 5. The linear baseline's σ range: the 5th and 95th percentiles of σ at h_max.
///
/// One backend per field, of one type (the overload below gives every field the backend the
/// missions will use). A network maps the fields it was trained on nearly as well from high up
/// as from low down, so calibrated there the decision learns that flying lower gains little,
/// which on new ground is false; a field may therefore be segmented by a network of the same
/// recipe that never saw it (cross-fitting, docs/method.md "Calibration fields the network
/// never saw"). The missions fly the model with the one backend it names.
/// @throws std::invalid_argument for no field, a backend count other than the field count, a
///         null backend, fields with other class sets, an unknown rule, invalid options (see the
///         rule's check_options, run_adaptive_mission and collect_region_samples), or fields
///         without a sample.
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationResult calibrate(std::span<const Field> fields, std::span<Backend* const> backends,
                                          const CalibrationOptions& options) {
  detail::require(backends.size() == fields.size(), "calibrate: one backend per training field is needed, backends",
                  backends.size());
  for (Backend* b : backends) detail::require(b != nullptr, "calibrate: a training field's backend is null", "nullptr");
  AdaptiveOptions adaptive = detail::calibration_settings(fields, options);
  const std::vector<double> lawnmower_gsd = options.lawnmower_gsds();
  const CameraModel camera(adaptive.mission.camera);
  const bool ranked = descent_coverage_info(adaptive.coverage).ranks_cells;
  detail::TrainingSamples train = detail::collect_training_samples(fields, backends, camera, adaptive, options);
  std::vector<RegionSample>& samples = train.samples;
  const std::vector<std::vector<RegionSample>>& by_field = train.by_field;
  const std::vector<std::vector<CellSample>>& cells_by_field = train.cells_by_field;
  std::vector<CellSample> cell_samples = cells_of_every_field(cells_by_field);
  // A coverage that ranks cells: the input that ranks the training fields' cells best.
  std::vector<std::pair<DecisionInput, double>> input_scores;
  if (ranked) {
    input_scores =
        detail::score_cell_inputs(cell_samples, options.cell_inputs, options.cell_input_score, fields.front().name());
    adaptive.cell_input = input_scores.front().first;
  }
  const detail::TrainingBackends<Backend> flights{fields, backends, lawnmower_gsd, adaptive.mission};
  std::vector<std::vector<CurvePoint>> curves;
  std::vector<ReferenceCurve> reference;
  for (std::size_t f = 0; f < fields.size(); ++f) {
    curves.push_back(flights.curve(fields[f]));
    ReferenceCurve r{fields[f].name(), {}, by_field[f].front().field_sigma};
    for (std::size_t k = 0; k < lawnmower_gsd.size(); ++k)
      r.points.push_back({lawnmower_gsd[k], curves.back()[k].miou});
    reference.push_back(std::move(r));
  }
  GainModel::FitOptions fit = options.fit;
  GainModel model = GainModel::fit(samples, fit);
  model.set_refit_every(options.refit_every);
  if (ranked) {
    model.set_cells(CellGainModel::fit(cell_samples, adaptive.cell_input));
    detail::set_field_inputs(reference, cells_by_field, *model.cells(), adaptive.cell_input, adaptive.top_gsd_cm);
  }

  // Layouts of a single field: the field and its halves across the longer axis.
  const std::vector<Field> halves = detail::single_field_halves(fields);
  std::vector<std::vector<CurvePoint>> half_curves;
  for (const Field& h : halves) half_curves.push_back(flights.curve(h));

  // The rule's settings, chosen by its own search (decision_rules.hpp).
  const RuleSearchInputs inputs{options,     adaptive, fields,         curves, halves,
                                half_curves, by_field, cells_by_field, model,  reference};
  const auto fly = [&](const Field& f, auto& policy, const std::vector<CurvePoint>& curve, double& margin) {
    return detail::fly_scored(f, flights.of(f), policy, adaptive, curve, margin);
  };
  std::optional<RuleSearchResult> searched;
  for_each_rule([&]<class Rule>() {
    if (options.rule == Rule::kName) searched.emplace(Rule::search(inputs, fly));
  });

  const LinearDecision::Params linear = detail::linear_sigma_range(samples);
  CalibrationResult result{
      std::move(samples), std::move(cell_samples),    std::move(input_scores), std::move(searched->chosen), linear,
      std::move(curves),  std::move(searched->trials)};
  for (Backend* b : backends) result.field_backends.push_back(b->name());
  return result;
}

/// Calibrates on the training `fields`, each segmented by `backend` (the backend the missions
/// will use); see the overload above.
template <SegmentationBackend Backend>
[[nodiscard]] CalibrationResult calibrate(std::span<const Field> fields, Backend& backend,
                                          const CalibrationOptions& options) {
  const std::vector<Backend*> backends(fields.size(), &backend);
  return calibrate(fields, std::span<Backend* const>(backends), options);
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
                  .descent_grid = options.adaptive.descent_grid,
                  .gain_extent = options.adaptive.gain_extent,
                  .decision_function = calibration.decision_function,
                  .linear = calibration.linear,
                  .samples = calibration.samples.size(),
                  .train_front_margin = calibration.trials.empty() ? 0.0 : calibration.trials.front().front_margin};
  const Field& first = fields.front();
  for (const Field& f : fields) m.calibration_fields.push_back(f.name());
  // Recorded only where a field was segmented by another backend than the missions' (cross-fitting).
  const auto& backends = calibration.field_backends;
  if (std::any_of(backends.begin(), backends.end(), [&](const std::string& b) { return b != segmenter; }))
    m.field_segmenters = backends;
  for (const auto& c : first.classes()) m.classes.push_back(c.name);
  m.map_fusion = options.adaptive.mission.map_fusion;
  const auto& interest =
      options.adaptive.mission.interest.empty() ? first.interest() : options.adaptive.mission.interest;
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
