#pragma once
/// @file
/// What a decision policy sees and says at a top-level waypoint (paper §3.2.2-3.2.3), and
/// the `DecisionPolicy` concept that the adaptive planner is templated on.
///
/// Models of the concept: UtilityPolicy (the paper's rule), FrontAwarePolicy (beyond the
/// paper), LinearDecision (the conference version's), and DecisionFunction (whichever of the
/// first two a calibrated model file holds). Each passes the conformance suite in
/// tests/policy_conformance.hpp.

#include <adaptseg/core/decision_inputs.hpp>

#include <concepts>
#include <cstddef>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

/// What a re-mapping changed in a map region, seen without ground truth (`relabelling()` in
/// metrics.hpp measures it): the share of the region's field pixels whose label differs before
/// and after, and the share whose label changed with a label of interest on either side (a
/// change into, out of, or within L); of those, the shares that entered L (added: not in L
/// before, in L after) and that left it (removed), which raise and lower the map's L by the
/// closer look's word, whichever of its labels is right.
struct Relabelling {
  double share = 0.0;           ///< label changed [0, 1]
  double interest_share = 0.0;  ///< label changed, old or new label in L [0, 1]
  double added_share = 0.0;     ///< not in L before, in L after [0, 1]
  double removed_share = 0.0;   ///< in L before, not in L after [0, 1]
};

/// One region seen from h_max and from h' (paper Eq. `eq:veg2h`: a row of O and of I).
struct RegionSample {
  double top_gsd_cm = 0.0;
  double sub_gsd_cm = 0.0;
  double delta_h_m = 0.0;  ///< Δh = h_max − h' [m]
  double sigma_top = 0.0;  ///< σ_{h_max}
  double sigma_sub = 0.0;  ///< σ_{h'} (fused sub-lawnmower images over the region)
  double miou_top = 0.0;   ///< mIoU_{h_max} over L on the region
  double miou_sub = 0.0;   ///< mIoU_{h'} over L on the region
  /// What the descent changed in the region's map (a row of C; observable in flight).
  Relabelling relabelled{};
  // The sample in field terms (calibration knows the whole field's top-level map and truth):
  double region_share = 0.0;  ///< the region's field pixels / the field's
  double field_sigma = 0.0;   ///< σ of the field's top-level map (share of L over its field pixels)
  /// Field mIoU over L of the top-level map with this region re-mapped, minus without: what
  /// this descent alone adds to a top-level lawnmower's result.
  double field_gain = 0.0;
  std::size_t field = 0;  ///< which calibration field it comes from (index)
  /// The field gain per unit of region share and per unit of the field's σ:
  /// field_gain · field_sigma / region_share (≈ the share of the region's pixels corrected).
  [[nodiscard]] double normalized_field_gain() const noexcept {
    return region_share > 0.0 ? field_gain * field_sigma / region_share : 0.0;
  }
  [[nodiscard]] double delta_sigma() const noexcept { return sigma_top - sigma_sub; }
  [[nodiscard]] double delta_miou() const noexcept { return miou_top - miou_sub; }
};

/// One lower altitude the UAV could re-map the current region from, with its exact cost.
struct Candidate {
  double gsd_cm = 0.0;        ///< GSD at the lower altitude h' [cm/px]
  double altitude_m = 0.0;    ///< h' [m]
  int images = 0;             ///< waypoints of the sub-lawnmower over the region
  double extra_time_s = 0.0;  ///< mission time added by the sub-lawnmower [s] (flight, segmentation, planning)
  /// Costed as deferred to the tour after the survey or the row (DescentSchedule::tour, row),
  /// not flown at once.
  bool deferred = false;
  /// DescentCoverage::ranked: the cells it re-maps, as the top-level image saw them (their
  /// decision inputs and field pixels); empty for the other coverages.
  std::vector<CellInputs> cells{};
};

/// What a fixed-altitude lawnmower over the whole field at one GSD would take, known from the
/// geometry before flying (a front-aware policy's yardstick; see DecisionFunction).
struct LawnmowerForecast {
  double gsd_cm = 0.0;  ///< GSD of the lawnmower [cm/px]
  double time_s = 0.0;  ///< its mission time [s]: flight plus per-image segmentation and planning estimates
};

/// The situation at a top-level waypoint, after its image has been segmented.
struct DecisionContext {
  double sigma = 0.0;                     ///< semantic ratio σ of the current image (paper Eq. `eq:vr`)
  double valid_fraction = 1.0;            ///< share of the image's ground inside the field (0..1]
  double top_gsd_cm = 0.0;                ///< GSD at h_max [cm/px]
  double top_altitude_m = 0.0;            ///< h_max [m]
  std::span<const Candidate> candidates;  ///< affordable lower altitudes (may be empty)
  // The mission so far and ahead (used by front-aware policies; the paper's rule ignores it).
  double elapsed_s = 0.0;     ///< mission time so far, this image included [s]
  double rest_s = 0.0;        ///< time to finish the top-level coverage from here without descending [s]
  double region_share = 0.0;  ///< the region's ground inside the field / the field's (0..1]
  /// The region's field pixels on the map grid (Candidate::cells' pixels are shares of it).
  double region_px = 0.0;
  /// DescentCoverage::ranked: the ranking decision input's value over the region's field pixels,
  /// as the top-level image saw them (NaN otherwise).
  double region_input = std::numeric_limits<double>::quiet_NaN();
  /// The region's mean normalised entropy of the class probabilities in the top-level image
  /// (DecisionInput::entropy), where the policy reads the field's entropy (ReadsFieldEntropy;
  /// NaN otherwise).
  double region_entropy = std::numeric_limits<double>::quiet_NaN();
  std::span<const LawnmowerForecast> lawnmowers{};  ///< this field's lawnmowers at the top and candidate GSDs
};

/// A policy's assessment of one candidate.
struct CandidateScore {
  double gsd_cm = 0.0;
  double predicted_delta_sigma = 0.0;     ///< μ_O: σ_{h_max} − σ_{h'}
  double predicted_delta_miou = 0.0;      ///< μ_I(μ_O): mIoU_{h_max} − mIoU_{h'} (< 0: lower is better)
  double predicted_delta_miou_std = 0.0;  ///< predictive standard deviation of the latter
  double utility = 0.0;                   ///< gain per second of extra time
  /// The policy's forecast of the descent's gain in field mIoU over L (NaN where the policy
  /// makes none; see FrontAwarePolicy).
  double predicted_field_gain = std::numeric_limits<double>::quiet_NaN();
  /// The policy's forecast of the share of the region's field pixels the descent relabels with
  /// a label of interest involved (compare DescentOutcome::relabelled; NaN where none is made).
  double predicted_relabelled = std::numeric_limits<double>::quiet_NaN();
  /// Front-aware policies: the predicted front margin of the mission if it descends here
  /// (NaN otherwise; see FrontAwarePolicy).
  double predicted_front_margin = std::numeric_limits<double>::quiet_NaN();
  /// Front-aware policies: the predicted lawnmower curve's rise over the descent's extra time,
  /// ΔD̄ of the lower bound (the mean over the predicted curves' upper envelopes from the
  /// mission's forecast end without the descent to `predicted_end_s`; NaN otherwise).
  double predicted_curve_rise = std::numeric_limits<double>::quiet_NaN();
  /// Front-aware policies: the mission's forecast end if it descends here [s]: elapsed time,
  /// the rest of the top-level path and the descent's extra time (NaN otherwise).
  double predicted_end_s = std::numeric_limits<double>::quiet_NaN();
};

/// The outcome of a decision: continue (`descend == false`) or re-map the region from `gsd_cm`.
struct Decision {
  bool descend = false;
  double gsd_cm = 0.0;  ///< chosen GSD when descending
  /// The chosen candidate's index in the context's order, where several share a GSD
  /// (DescentCoverage::ranked: one candidate per number of cells). A policy that leaves it at 0
  /// names its candidate by `gsd_cm` alone: the first candidate of that GSD (chosen_candidate()).
  std::size_t candidate = 0;
  std::vector<CandidateScore> scores;  ///< one per candidate, in the context's order
};

/// What the UAV saw after re-mapping a region from a lower altitude (paper §3.2.3).
struct DescentOutcome {
  double top_altitude_m = 0.0;  ///< h_max [m]
  double sub_altitude_m = 0.0;  ///< h' [m]
  double sigma_top = 0.0;       ///< σ_{h_max} of the region
  double sigma_sub = 0.0;       ///< σ_{h'} of the region (fused sub-lawnmower images)
  /// What the descent changed in the region's map (field pixels; no ground truth needed).
  Relabelling relabelled{};
  /// DescentCoverage::ranked: the ranking input over the re-mapped cells as the top-level image
  /// saw it, and as the finer images see the same ground (Σ_c value_c·CellInputs::gain_px / the
  /// region's field pixels, as Candidate::cells' forecasts); NaN where unknown (the finer images
  /// came without probabilities). The scene check compares them (CellGainModel::proxy_gain).
  double top_input = std::numeric_limits<double>::quiet_NaN();
  double fine_input = std::numeric_limits<double>::quiet_NaN();
  /// Which descent this is: 0, 1, ... in the order the policy chose them. The planner flies
  /// them in that order, except a survey-then-inspect tour (DescentSchedule::tour, row), which
  /// chooses them during the survey (or the row) and flies them in its own order.
  std::size_t descent = 0;
  /// The budget ended the descent before its last planned image (a bound of the steps' time
  /// learned in flight outgrew what was reserved when it was chosen): what it flew is what the
  /// other members describe.
  bool cut_short = false;
};

/// Decides at each top-level waypoint. Rationale: the planner owns geometry and time, the
/// policy only weighs gain against cost.
///
/// Lifecycle and laws, for one mission:
/// - `begin_mission()` first (AdaptivePlanner's constructor calls it): it forgets whatever the
///   policy learnt or kept during a previous mission, so one object can fly many missions and
///   two missions given the same contexts take the same decisions;
/// - `decide(context)` at every top-level image, in flight order: a Decision that, when
///   descending, names one of `context.candidates` by its `gsd_cm` (and, where several share
///   it, by its index `candidate`; the planner checks it and throws std::logic_error otherwise);
///   never descending without candidates; `scores` one per candidate, in order;
/// - `observe(outcome)` after every descent (a policy that does not adapt ignores it). With the
///   paper's immediate descents it comes before the next `decide`; a tour
///   (DescentSchedule::tour, row) takes every decision of the survey (of the row) first and
///   reports the outcomes afterwards, in its flight order: `outcome.descent` says which of the
///   chosen descents it is;
/// - `name()` names the strategy (e.g. in results).
template <typename P>
concept DecisionPolicy = requires(P& policy, const DecisionContext& context, const DescentOutcome& outcome) {
  policy.begin_mission();
  { policy.decide(context) } -> std::same_as<Decision>;
  policy.observe(outcome);
  { policy.name() } -> std::convertible_to<std::string>;
};

/// Optionally, a policy chooses the GSD the top-level lawnmower is flown at, once per mission
/// before it starts: `top_gsd(lawnmowers, nominal)` gets the area's lawnmowers at the nominal
/// top GSD and every candidate GSD (times known from the geometry) and returns one of their
/// GSDs (AdaptivePlanner checks it, and descends only to the candidates finer than it).
/// Rationale: where a finer lawnmower is faster than the nominal top level over the area (its
/// grid fits the area better) and maps better, starting at the nominal top gives away accuracy
/// and time that no descent needs to buy back (FrontAwarePolicy::top_gsd).
template <typename P>
concept ChoosesTopLevel = requires(P& policy, std::span<const LawnmowerForecast> lawnmowers, double nominal) {
  { policy.top_gsd(lawnmowers, nominal) } -> std::convertible_to<double>;
};

/// A policy whose forecasts read the field's mean top-level entropy (DecisionContext::
/// region_entropy): the planner computes it only for such a policy, and only where it says so.
template <class P>
concept ReadsFieldEntropy = requires(const P& policy) {
  { policy.reads_field_entropy() } -> std::convertible_to<bool>;
};

/// A policy that may refuse a descent image (FrontAwarePolicy's jump guard, jump_guard.hpp):
/// AdaptivePlanner asks it with the top-level map's σ over the image's cell and the image's σ
/// before fusing each descent image; one refused is not fused and ends its descent.
template <class P>
concept GuardsDescentImages = requires(P& policy, double sigma_top, double sigma_image) {
  { policy.trusts_descent_image(sigma_top, sigma_image) } -> std::convertible_to<bool>;
};

/// The index of the candidate a descending `decision` names: `decision.candidate` if that
/// candidate has the decision's `gsd_cm`, else the first candidate of that GSD; checked.
/// @throws std::logic_error naming `policy` if the decision descends to a GSD that is not one
///         of `candidates` (a policy breaking the DecisionPolicy contract).
[[nodiscard]] inline std::size_t chosen_candidate(const Decision& decision, std::span<const Candidate> candidates,
                                                  const std::string& policy) {
  if (decision.candidate < candidates.size() && candidates[decision.candidate].gsd_cm == decision.gsd_cm)
    return decision.candidate;
  for (std::size_t k = 0; k < candidates.size(); ++k)
    if (candidates[k].gsd_cm == decision.gsd_cm) return k;
  throw std::logic_error("decision policy '" + policy + "' descends to " + std::to_string(decision.gsd_cm) +
                         " cm/px, which is not one of the " + std::to_string(candidates.size()) +
                         " candidates it was offered");
}

}  // namespace adaptseg
