#pragma once
/// @file
/// What calibration is told and gives (CalibrationOptions, CalibrationResult) and what a
/// decision rule's calibration search works from and gives (RuleSearchInputs, RuleTrial,
/// RuleSearchResult): shared by calibrate() (calibration.hpp) and each rule's own search
/// (front_aware_rule.hpp, utility_rule.hpp).

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/cell_input_scores.hpp>
#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/lawnmower_curve.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/region_samples.hpp>

#include <algorithm>
#include <array>
#include <optional>
#include <span>
#include <string>
#include <string_view>
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
  double planning_time_s = 0.0;  ///< planning time charged per waypoint [s]

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
  /// and forecast by; the one of best `cell_input_score` on the training fields is chosen and
  /// set as `adaptive.cell_input`; those the backend does not give (probabilities from a
  /// labels-only backend) are left out. Empty: the inputs about L (sigma, boundary, ambiguity,
  /// expected_error, second_choice); the generic ones, blind to which errors matter for L, are
  /// tried only when named.
  std::vector<DecisionInput> cell_inputs{};
  /// How the input is scored (CellInputScore): `ranking` (the default), how much of each
  /// training field's achievable gain its best cells capture (cell_ranking_capture()); `transfer`,
  /// the same where the model fitted without the field forecasts a gain (cell_transfer_capture()).
  CellInputScore cell_input_score = CellInputScore::ranking;
  /// DescentCoverage::ranked: other top-level GSDs the cell gain model is calibrated for, so
  /// that a mission may fly its top level at one of them where the predicted lawnmower curve
  /// shows the model's top lawnmower dominated by a faster one on the field flown
  /// (FrontAwarePolicy::top_gsd). nullopt: the coarsest candidate GSD (the one that can be
  /// faster than the top where its grid fits the field better). Each must be a candidate GSD
  /// with a finer candidate below it.
  std::optional<std::vector<double>> alternative_top_gsd_cm{};
  /// DescentCoverage::ranked: also fly each descent's sub-lawnmower shifted half a footprint
  /// along its rows, both ways, and record which of each cell's changes those frames make too
  /// (CellSample::reframed; what a forward overlap of one half would show in flight). About
  /// twice the descents' segmentations; the model is the same either way.
  bool frame_check = false;
  GainModel::FitOptions fit{};  ///< what I predicts from, hyperparameter restarts
  int refit_every = 0;          ///< O's scheduled re-optimisation (GainModel)

  /// Which rule the model holds, by name (decision_rules.hpp): `front-aware`, the
  /// FrontAwarePolicy (default; its confidence level z is chosen below), or `utility`, the
  /// paper's UtilityPolicy (its threshold chosen below).
  std::string rule = "front-aware";

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
  /// Front-aware rule, DescentCoverage::ranked, several training fields: how the cell gain
  /// model may pool its slopes over the fields (SlopePooling), each tried with every z of
  /// `confidences`, each fold's model fitted without its field with that pooling (and the field
  /// factor's prior spread estimated with it), each with its z of best mean front margin. The
  /// first pooling is kept unless another beats it on the folds by more than one standard error
  /// of their paired margins (detail::select_pooling). One training field: the first only (a
  /// field's own slope either way). SlopePooling::field_entropy is not tried where the fields'
  /// mean entropies do not spread or fewer than three fields count: it is the fields pooling
  /// there under another name (detail::distinct_poolings). With
  /// pooled maps (MapFusion::pooled) on new ground, `{field_entropy, cells, fields}` did best on
  /// the leave-one-tile-out folds, and the deployment's decision models are calibrated with it;
  /// with the default fusion it lost more there than `{cells, fields}` (docs/results.md).
  std::vector<SlopePooling> slope_poolings{SlopePooling::cells, SlopePooling::fields};
  /// Front-aware rule, DescentCoverage::ranked: the top-level choices tried (TopLevelChoice;
  /// each replaces `front_aware.top_level`), each with every pooling and z; the first is kept
  /// unless another's best setting beats it by more than one standard error of their paired
  /// margins on the folds (detail::select_pooling's rule). Without ranked cells: the first
  /// only. Empty (the default): `front_aware.top_level` alone.
  std::vector<TopLevelChoice> top_levels{};
  /// Front-aware rule: the finest GSDs a descent may be limited to
  /// (FrontAwarePolicy::Params::finest_descent_gsd_cm) [cm/px], tried on the folds after the
  /// rest of the search: every setting above is flown with the first, and with the setting
  /// kept each other one is flown over the same folds; the first is kept unless another beats
  /// it by more than one standard error of their paired margins (detail::select_pooling's
  /// rule). Which descent GSDs pay on a field the model never saw differs from what the cells
  /// forecast (docs/method.md, "The finest descent chosen by the folds"). Empty (the
  /// default): `front_aware.finest_descent_gsd_cm` alone, no such trial. 0 in the list: no limit.
  std::vector<double> finest_descent_gsd_cm{};
  /// Front-aware rule: the most extra seconds a descent may cost
  /// (FrontAwarePolicy::Params::longest_descent_s) [s], tried on the folds last: every setting
  /// above is flown with the first, and with the setting kept (its pooling, top level and finest
  /// descent GSD) each other one is flown with every z of `confidences`, its z of best mean front
  /// margin kept (ties to the larger z); the first is kept unless another beats it by more than
  /// one standard error of their paired margins (detail::select_pooling's rule). So a limit may
  /// bring a smaller z with it: on new ground the long descents lost where the short ones won
  /// (docs/method.md, "The longest descent chosen by the folds"). Empty (the default):
  /// `front_aware.longest_descent_s` alone, no such trial. 0 in the list: no limit.
  std::vector<double> longest_descent_s{};
  /// Front-aware rule, several training fields: per training field, the index of its ground
  /// (the first field of that ground), equal for the fields that are one field segmented by
  /// several networks (the programs' --calibration-network-each: each a look of a network on
  /// ground it never trained on). Fields of one ground leave the search's folds together, each
  /// fold's model fitted on the other grounds only, and the one-standard-error rule averages
  /// their paired differences before it counts the grounds (detail::select_pooling). Empty (the
  /// default): every field its own ground.
  std::vector<std::size_t> field_grounds{};
  /// Front-aware rule, several training fields: measure FrontAwarePolicy::Params::gain_ratios
  /// on the folds before the search. Each training field is flown with the model of the others
  /// (the first slope pooling and top-level choice, z = 0); per descent GSD, the ratio of what
  /// its descents realised in field gain (RealisedDescent::field_gain) to what they were
  /// forecast to gain, shrunk towards 1 by two descents' worth of forecast and kept in [0, 4],
  /// scales every forecast of a descent to that GSD (detail::fold_gain_ratios): in the model,
  /// the ratios of every fold's flight; in the search, each fold's trials those of the other
  /// folds' flights, as its model is fitted without its field. The training fields flown as new
  /// ground tell how the forecast's dependence on the descent GSD transfers to a field the model
  /// never saw (docs/method.md, "Gain ratios measured on the folds"). false (the default): none.
  bool gain_ratios = false;
  /// Front-aware rule, several training fields: measure FrontAwarePolicy::Params::margin_biases
  /// on the folds before the search, on the same flights as `gain_ratios` (those fly without
  /// ratios). Per descent GSD, how far its descents ended above their forecast margin (realised
  /// field gain less the real curve's rise over their seconds, against forecast gain less the
  /// predicted rise), per second of descent, shrunk towards 0 by two descents' worth
  /// (detail::fold_margin_biases): in the model, those of every fold's flight; in the search,
  /// each fold's trials those of the other folds' flights. The error of the gain and of the
  /// curve together, measured where the model never saw the field (docs/method.md, "Margin
  /// biases measured on the folds"). false (the default): none.
  bool margin_biases = false;
  /// Front-aware rule with ranked cells: the jump guard (FrontAwarePolicy::Params::jump_bound,
  /// jump_guard.hpp), its bound learned on the training fields' cell samples (jump_bound(): the
  /// jump of a finer image's σ over the cell's top-level σ above which re-mapping lost): in the
  /// model, every field's cells; in the search, each fold's the other fields' only. false (the
  /// default): no guard.
  bool jump_guard = false;
  /// Front-aware rule with ranked cells and FrontAwarePolicy::Params::field_factor relabelled:
  /// measure Params::relabel_transfer b on the training fields' cell samples
  /// (relabel_transfer(): how far a field's gain factor moved with its relabelled factor), in
  /// the model every field's cells, in the search each fold's the other fields' only. false
  /// (the default): `front_aware`'s b (1: s scales the gain whole).
  bool relabel_transfer = false;
  /// Front-aware rule with ranked cells and the relabelled field factor: measure
  /// FrontAwarePolicy::Params::relabel_region_sd τ_r on the training fields' cell samples
  /// (relabel_region_sd()), in the model every field's cells, in the search each fold's the
  /// other fields' only. false (the default): `front_aware`'s τ_r (0).
  bool relabel_region_spread = false;
  /// Front-aware rule with ranked cells and the relabelled field factor: measure
  /// FrontAwarePolicy::Params::relabel_field_sd ω_χ, s's own prior spread, on the training fields'
  /// cell samples (relabel_field_sd()), in the model every field's cells, in the search each
  /// fold's the other fields' only. false (the default): `front_aware`'s ω_χ (0: s's prior spread
  /// is ω).
  bool relabel_field_spread = false;
  /// Front-aware rule: the folds that choose the setting (and measure `gain_ratios` and
  /// `margin_biases`) fly the non-adaptive rule, so that what the field factor and O learn in a
  /// fold's flight cannot move the choice; the rule calibrated still learns in flight, and is
  /// judged against its frozen twin run by run (docs/method.md, "Folds flown frozen"). false (the
  /// default): the folds fly the adaptive rule, as the deployment does.
  bool frozen_folds = false;
  /// Front-aware rule, σ̂'s prior (FrontAwarePolicy `sigma_prior_weight` k, `sigma_prior_sd` τ)
  /// with several training fields: `given` keeps `front_aware`'s; `spread` estimates τ on the
  /// training fields (estimate_sigma_prior) and keeps k; `estimated` estimates both. Each fold
  /// of the z choice uses the values estimated without its field. One field: as given.
  enum class SigmaPriorSource { given, spread, estimated };
  static constexpr SigmaPriorSource kDefaultSigmaPrior = SigmaPriorSource::given;  ///< the default below
  SigmaPriorSource sigma_prior = kDefaultSigmaPrior;

  /// Utility rule: `exploration` and `min_sigma` as given; thresholds searched (quantiles of
  /// the utilities seen, absolute and relative, σ weighting on and off, "never descend"), each
  /// flown over every layout (the fields; one field: the field and its halves) and scored by
  /// its worst front margin (ties: larger mean margin, then the relative rule, then shorter time).
  UtilityPolicy::Params utility{};
  int threshold_steps = 10;  ///< utility thresholds tried per weighting
};

/// Every source of σ̂'s prior by name (`--sigma-prior` of the programs).
inline constexpr std::array<detail::NamedValue<CalibrationOptions::SigmaPriorSource>, 3> kSigmaPriorSources{{
    {CalibrationOptions::SigmaPriorSource::given, "given"},
    {CalibrationOptions::SigmaPriorSource::spread, "spread"},
    {CalibrationOptions::SigmaPriorSource::estimated, "estimated"},
}};

/// The name of a source of σ̂'s prior.
[[nodiscard]] inline std::string to_string(CalibrationOptions::SigmaPriorSource s) {
  return detail::name_of(kSigmaPriorSources, s, "sigma prior source");
}

/// Parses a source of σ̂'s prior by name.
/// @throws std::invalid_argument for anything but `given`, `spread` or `estimated`.
[[nodiscard]] inline CalibrationOptions::SigmaPriorSource parse_sigma_prior_source(std::string_view name) {
  return detail::value_named(kSigmaPriorSources, name, "sigma prior source");
}

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
  std::vector<RegionSample> samples;  ///< pooled over the fields (RegionSample::field)
  /// DescentCoverage::ranked: the cell samples, pooled (CellSample::field), and every input
  /// tried with its capture on the training fields (the chosen one first).
  std::vector<CellSample> cell_samples{};
  std::vector<std::pair<DecisionInput, double>> cell_input_scores{};
  DecisionFunction decision_function;                     ///< fitted, with the chosen rule and settings
  LinearDecision::Params linear{};                        ///< σ range of the training fields' top-level images
  std::vector<std::vector<CurvePoint>> lawnmower_curves;  ///< per training field, at lawnmower_gsds()
  std::vector<RuleTrial> trials;                          ///< every setting tried, the chosen one first
  /// Per training field, the name of the backend that segmented it (calibrate()'s `backends`).
  std::vector<std::string> field_backends{};
};

/// What a rule's calibration search works from (calibrate() fills it, the rule's `search`
/// reads it): the training fields, their lawnmower curves and samples, the gain model fitted on
/// all of them and the fields' reference curves.
struct RuleSearchInputs {
  const CalibrationOptions& options;
  /// The options the missions are flown with (labels of interest, fixed times, the cell input
  /// chosen).
  const AdaptiveOptions& adaptive;
  std::span<const Field> fields;
  std::span<const std::vector<CurvePoint>> curves;  ///< per field, at lawnmower_gsds()
  /// One training field: its halves across the longer axis and their curves (the layouts the
  /// utility rule is scored on, the folds of the front-aware rule's z); otherwise empty.
  std::span<const Field> halves;
  std::span<const std::vector<CurvePoint>> half_curves;
  std::span<const std::vector<RegionSample>> samples;  ///< per field
  std::span<const std::vector<CellSample>> cells;      ///< per field (DescentCoverage::ranked)
  const GainModel& model;                              ///< fitted on every field
  std::span<const ReferenceCurve> reference;           ///< per field
};

/// What a rule's calibration search gives.
struct RuleSearchResult {
  DecisionFunction chosen;        ///< the rule with the settings chosen
  std::vector<RuleTrial> trials;  ///< every setting tried, the chosen one first
};

namespace detail {

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

}  // namespace detail

}  // namespace adaptseg
