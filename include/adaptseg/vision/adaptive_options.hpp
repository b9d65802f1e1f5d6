#pragma once
/// @file
/// The adaptive planner's vocabulary (adaptive_planner.hpp): its settings (AdaptiveOptions),
/// the ground it covers (SurveyArea), and what it hands out step by step
/// (PlannedWaypoint, PlannerStep, DecisionRecord). Apart from the planner so that code that
/// only configures or records missions (model files, exports, result writers) need not
/// compile it.

#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/descent_schedule.hpp>
#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/mission_options.hpp>
#include <adaptseg/vision/descent_coverage.hpp>
#include <adaptseg/vision/gain_extent.hpp>

#include <opencv2/core.hpp>

#include <array>
#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg {

/// Where the top-level lawnmower's grid is laid on the area, and each descent's sub-lawnmower on
/// its region.
enum class GridAnchor {
  /// From the area's corner (x_min, y_min), the whole overhang of the last column and row on the
  /// far sides (the paper's grid, LawnmowerPlanner::plan); a sub-lawnmower from its region's
  /// corner nearest the UAV.
  corner,
  /// Centred on the area, the overhang split evenly between opposite sides, so that every
  /// waypoint lies inside the area (LawnmowerPlanner::centred_grid; the grid adaptseg_plan lays
  /// on a new site, plan_site_survey); a sub-lawnmower centred on the part of its region inside
  /// the area, so that its waypoints lie inside the area too and the same site in another frame
  /// (its axes turned half a turn, or the origin moved) asks for the same waypoints on the ground.
  centred,
};

/// Every grid anchor and its name (the programs' `--grid`).
inline constexpr std::array<detail::NamedValue<GridAnchor>, 2> kGridAnchors{{
    {GridAnchor::corner, "corner"},
    {GridAnchor::centred, "centred"},
}};

/// "corner" or "centred".
[[nodiscard]] inline const char* to_string(GridAnchor a) { return detail::name_of(kGridAnchors, a, "grid anchor"); }

/// Parses a grid anchor's name.
/// @throws std::invalid_argument naming both for anything else.
[[nodiscard]] inline GridAnchor parse_grid_anchor(const std::string& s) {
  return detail::value_named(kGridAnchors, s, "grid anchor");
}

/// How a descent's sub-lawnmower is laid (beyond the paper).
enum class DescentGrid {
  /// On its region, as AdaptiveOptions::grid_anchor says (the paper's W^{h'}): where the finer
  /// footprint does not divide the region (15 to 10 cm/px: 1.5 footprints a side) the grid
  /// overhangs it, 2 x 2 images covering 1.78 regions, and neighbouring descents fly over the
  /// same ground.
  region,
  /// The cells of the whole area's lawnmower at the descent's GSD (laid as the top level's is)
  /// whose centres lie in the region (LawnmowerPlanner::cells_centred_in): each cell belongs to
  /// one region, so descents share out the finer lawnmower without flying any ground twice; a
  /// region may get fewer images than a side of it needs (15 to 10 cm/px: 1 to 4, 2.25 on average).
  field,
};

/// Every descent grid and its name (the programs' `--descent-grid`; model files' `descent_grid`).
inline constexpr std::array<detail::NamedValue<DescentGrid>, 2> kDescentGrids{{
    {DescentGrid::region, "region"},
    {DescentGrid::field, "field"},
}};

/// "region" or "field".
[[nodiscard]] inline const char* to_string(DescentGrid g) { return detail::name_of(kDescentGrids, g, "descent grid"); }

/// Parses a descent grid's name.
/// @throws std::invalid_argument naming both for anything else.
[[nodiscard]] inline DescentGrid parse_descent_grid(const std::string& s) {
  return detail::value_named(kDescentGrids, s, "descent grid");
}

/// Settings of an adaptive mission.
struct AdaptiveOptions {
  /// Camera, timing, labels of interest, fixed per-image/waypoint times. AdaptivePlanner needs
  /// `interest` set; run_adaptive_mission fills an empty one from the field.
  MissionOptions mission{};
  double top_gsd_cm = 3.0;  ///< GSD at h_max [cm/px]
  /// Lower GSDs a sub-lawnmower may fly [cm/px]; at least one not finer than the map is
  /// required (AdaptivePlanner rejects an empty list: it could never descend).
  std::vector<double> candidate_gsd_cm{};
  /// Mission-time budget [s] (flight + segmentation + planning). The planner only descends
  /// when the descent and the rest of the mission still fit, every image to come reserved at a
  /// bound of one step's processing: with fixed segmentation and planning times their sum
  /// (exact), otherwise learned from the mission clock in flight (the largest step so far, times
  /// (k + 1) / k after k steps); and it cuts a descent short where the rest of it no longer fits.
  std::optional<double> budget_s{};
  /// What a descent re-maps: the whole region (the paper) or only its cells that show a label
  /// of interest (DescentCoverage). A decision model must be calibrated with the same.
  DescentCoverage coverage = DescentCoverage::region;
  /// Where the top-level grid (and the lawnmowers the front-aware rule compares with) is laid on
  /// the area, and each sub-lawnmower on its region: a mission time choice, not part of a
  /// decision model.
  GridAnchor grid_anchor = GridAnchor::corner;
  /// DescentCoverage::ranked: the decision input whose mass over a cell ranks the cells
  /// (decision_inputs.hpp); a decision model sets the one it was calibrated with.
  DecisionInput cell_input = DecisionInput::expected_error;
  /// When the chosen descents are flown: at once (the paper), or deferred to a tour after the
  /// survey or after each lawnmower row where that is cheaper.
  DescentSchedule schedule = DescentSchedule::immediate;
  /// How each descent's sub-lawnmower is laid (DescentGrid). A decision model must be calibrated
  /// with the same (its samples are flown so; DecisionModel::descent_grid).
  DescentGrid descent_grid = DescentGrid::region;
  /// Which pixels a descent's gain is counted over (GainExtent): in calibration its samples'
  /// field gains, in flight the pixels each ranked cell is forecast for. A decision model must
  /// be calibrated with the same (DecisionModel::gain_extent).
  GainExtent gain_extent = GainExtent::region;
};

/// The decision taken at one top-level waypoint.
struct DecisionRecord {
  std::size_t waypoint_index = 0;  ///< index into the path (= MissionResult::waypoints in simulation)
  double sigma = 0.0;              ///< σ of the top-level image
  Decision decision;
  std::vector<Candidate> candidates;      ///< what was affordable, with exact costs
  std::optional<DescentOutcome> outcome;  ///< after a descent
  bool budget_limited = false;            ///< some candidate was dropped because of the budget
};

/// The ground a mission covers, as a real mission knows it: no labels, only where the field is.
///
/// The map grid is the field frame's (docs/data_format.md): origin at the grid's bottom-left
/// corner, x along its columns, y up its rows, `map_gsd_cm` per pixel; it is what the planner
/// fuses segmentations into and what `valid_mask` is drawn on.
struct SurveyArea {
  Area area{};              ///< the rectangle to cover [m], x_min, y_min >= 0
  double map_gsd_cm = 1.0;  ///< resolution of the fused map (and of `valid_mask`) [cm/px]
  /// Optional CV_8UC1 over the map grid, non-zero where there is field; its size sets the
  /// grid's. Empty: every pixel under `area` is field, and the grid just covers `area`.
  cv::Mat valid_mask{};
  int ignore_label = 255;  ///< "no class" in segmentations and in the map (0..255)
  /// Size of the class set the backend labels with (1..255; labels 0 .. num_classes - 1).
  /// Required: every segmentation reported to the planner is checked against it
  /// (check_segmentation()); 0, the default, is rejected by the planner with a message.
  int num_classes = 0;

  /// A Field's area, GSD, valid mask, ignore label and class count (what the simulation
  /// knows). A template so that the live planner does not depend on field.hpp (and its YAML
  /// and image-file readers): any type with Field's five accessors will do.
  template <typename FieldLike>
  [[nodiscard]] static SurveyArea of(const FieldLike& field) {
    return {field.area(), field.gsd_cm(), field.valid_mask(), field.ignore_label(), field.num_classes()};
  }
};

/// One waypoint the planner asks the UAV to fly to and take an image at.
struct PlannedWaypoint {
  Waypoint waypoint;
  int level = 0;              ///< 0: top-level lawnmower W^{h_max}; 1: sub-lawnmower W^{h'} (a descent)
  std::size_t index = 0;      ///< visiting order: 0, 1, ... over the whole path
  std::size_t top_index = 0;  ///< the top-level waypoint whose region it maps
  /// Level 1: the index of the decision (AdaptivePlanner::decisions()) whose descent it flies,
  /// and its place in that descent's sub-lawnmower (0: the first waypoint).
  std::size_t decision = 0;
  std::size_t step = 0;
};

/// What the planner made of one reported image.
struct PlannerStep {
  PlannedWaypoint waypoint;  ///< the waypoint the image was reported for
  double sigma = 0.0;        ///< semantic ratio σ of the image's segmentation (paper Eq. `eq:vr`)
  /// False for a descent image the policy did not trust (GuardsDescentImages): not fused into
  /// the map, and its descent ended there.
  bool trusted = true;
  /// At a top-level waypoint: the decision taken (descend or continue).
  std::optional<DecisionRecord> decision;
  /// After the last image of a descent: what the region showed, fed back to the policy.
  std::optional<DescentOutcome> outcome;
};

}  // namespace adaptseg
