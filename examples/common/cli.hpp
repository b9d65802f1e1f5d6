#pragma once
// Shared command-line plumbing of the example programs: camera/timing options, error
// reporting, and the result.json writer. Not part of the library.

#include <adaptseg/core/camera_presets.hpp>
#include <adaptseg/planner.hpp>
#include <adaptseg/vision/calibration.hpp>
#include <adaptseg/vision/decision_model.hpp>

#include "old_spelling.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg::examples {

/// `v` with `digits` decimals.
inline std::string fmt(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

/// The flag of `app` nearest to `word` by edit distance, if within 2 edits ("" otherwise).
inline std::string nearest_flag(const CLI::App& app, const std::string& word) {
  const auto distance = [](const std::string& a, const std::string& b) {
    std::vector<std::size_t> row(b.size() + 1);
    for (std::size_t j = 0; j <= b.size(); ++j) row[j] = j;
    for (std::size_t i = 1; i <= a.size(); ++i) {
      std::size_t diagonal = row[0];
      row[0] = i;
      for (std::size_t j = 1; j <= b.size(); ++j) {
        const std::size_t up = row[j];
        row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] == b[j - 1] ? 0 : 1)});
        diagonal = up;
      }
    }
    return row[b.size()];
  };
  std::string best;
  std::size_t best_distance = 3;
  for (const CLI::Option* o : app.get_options()) {
    if (o->get_group() == kOldSpellings) continue;  // not to be suggested (old_spelling.hpp)
    for (const std::string& name : o->get_lnames())
      if (const std::size_t d = distance(word, "--" + name); d < best_distance) best = "--" + name, best_distance = d;
  }
  return best;
}

/// Prints a command-line mistake of program `app` as one line on stderr; returns the exit code 2.
inline int command_line_error(const CLI::App& app, const std::string& what) {
  std::fprintf(stderr, "%s: error: %s (run %s --help for the options)\n", app.get_name().c_str(), what.c_str(),
               app.get_name().c_str());
  return 2;
}

/// Parses the command line into `app`. Returns nullopt to go on, else the exit code: 0 after
/// --help, 2 after a command-line mistake (unknown or misspelt flag, missing or malformed
/// value), with one error line on stderr naming the flag, as for every other bad input.
inline std::optional<int> parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    inherit_old_spellings(app);
    app.parse(argc, argv);
    tell_old_spellings(app);
    return std::nullopt;
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::string what = e.what();
    for (char& c : what)
      if (c == '\n') c = ' ';
    // An unknown flag is the mistake to name (CLI11 may report a missing required option
    // first), with the one that was probably meant.
    for (int k = 1; k < argc; ++k) {
      const std::string word = std::string(argv[k]).substr(0, std::string(argv[k]).find('='));
      if (word.rfind("--", 0) != 0 || word.size() < 3) continue;
      bool known = false;
      for (const CLI::Option* o : app.get_options())
        for (const std::string& name : o->get_lnames()) known = known || "--" + name == word;
      if (known) continue;
      const std::string near = nearest_flag(app, word);
      what = "unknown option " + word + (near.empty() ? "" : "; did you mean " + near + "?");
      break;
    }
    return command_line_error(app, what);
  }
}

/// Throws unless every GSD factor of `flag` is finite and >= 1: the factors multiply the
/// field's GSD, and the simulator cannot fly finer than its orthomosaic.
inline void check_gsd_factors(const std::vector<double>& factors, const std::string& flag) {
  if (factors.empty()) throw std::invalid_argument(flag + " needs at least one factor");
  for (double f : factors)
    if (!std::isfinite(f) || f < 1.0)
      throw std::invalid_argument(flag + " " + fmt(f, 3) +
                                  " is finer than the field: GSD factors multiply the field's GSD and must be >= 1");
}

/// Camera, speed and timing options shared by every program.
struct CommonOptions {
  MissionOptions mission;
  std::string camera_preset_name;  ///< `--camera`: empty, or a name of kCameraPresets
  std::vector<std::string> interest_names;
  std::optional<double> seg_time_s;
  std::optional<double> plan_time_s;
  std::string map_fusion = to_string(MissionOptions{}.map_fusion);

  void add_to(CLI::App& app) {
    auto& cam = mission.camera;
    std::string presets;
    for (const auto& p : kCameraPresets) presets += (presets.empty() ? "" : ", ") + std::string(p.name);
    app.add_option("--camera", camera_preset_name,
                   "a camera preset (" + presets +
                       "; include/adaptseg/core/camera_presets.hpp names each one's source): its sensor width, focal "
                       "length and image size; --image-width alone then scales the image, keeping its aspect ratio, "
                       "and other camera options override the preset's")
        ->check([](const std::string& name) {
          try {
            (void)camera_preset(name);
            return std::string();
          } catch (const std::invalid_argument& e) {
            return std::string(e.what());
          }
        });
    // After parsing: the preset, then the camera options given explicitly.
    app.parse_complete_callback([this, &app] { apply_camera_preset(app); });
    app.add_option("--image-width", cam.image_width_px, "camera image width [px]")->capture_default_str();
    app.add_option("--image-height", cam.image_height_px, "camera image height [px]")->capture_default_str();
    app.add_option("--sensor-width-mm", cam.sensor_width_mm, "sensor width [mm]")->capture_default_str();
    app.add_option("--focal-mm", cam.focal_length_mm, "focal length [mm]")->capture_default_str();
    app.add_option("--speed", mission.timing.max_speed_mps, "maximum speed [m/s]")->capture_default_str();
    app.add_option("--accel", mission.timing.max_accel_mps2, "maximum acceleration [m/s^2]")->capture_default_str();
    app.add_option("--vertical-speed", mission.timing.max_vertical_speed_mps,
                   "maximum climb and sink rate [m/s] (0: none, climbs as fast as level flight, the paper's model)")
        ->capture_default_str();
    app.add_option("--seg-time-s", seg_time_s, "fixed segmentation time per image [s] (default: measured)");
    app.add_option("--plan-time-s", plan_time_s, "fixed planning time per waypoint [s] (default: measured)");
    app.add_option("--interest", interest_names,
                   "labels of interest, comma-separated (default: the field's 'interest')")
        ->delimiter(',');
    app.add_option("--map-fusion", map_fusion,
                   "how the map combines the images of one pixel: 'finest' (the finest GSD's label, the paper's) or "
                   "'pooled' (the class probabilities pooled, each image weighted by 1 / GSD; needs a network) or "
                   "'pooled-interest' (pooled, but a pixel any image labelled with a label of interest keeps one)"
                   " or 'pooled-guarded' (pooled, but a pixel keeps its coarsest images' class where p > 0.75)")
        ->check(CLI::IsMember(detail::names_of(kMapFusions)))
        ->capture_default_str();
  }

  /// `--camera NAME`: the preset's camera, then the camera options given explicitly on top of it
  /// (`--image-width` alone scales the preset's image, its aspect ratio kept).
  void apply_camera_preset(const CLI::App& app) {
    if (camera_preset_name.empty()) return;
    const CameraParams given = mission.camera;
    CameraParams cam = camera_preset(camera_preset_name).params;
    if (app.count("--image-width") > 0 && app.count("--image-height") == 0) cam = at_width(cam, given.image_width_px);
    if (app.count("--image-width") > 0) cam.image_width_px = given.image_width_px;
    if (app.count("--image-height") > 0) cam.image_height_px = given.image_height_px;
    if (app.count("--sensor-width-mm") > 0) cam.sensor_width_mm = given.sensor_width_mm;
    if (app.count("--focal-mm") > 0) cam.focal_length_mm = given.focal_length_mm;
    mission.camera = cam;
  }

  /// Model-based strategies fly the model's camera and timing; explicit options must agree.
  /// @throws std::invalid_argument naming the option that differs.
  void check_camera_matches(const CLI::App& app, const DecisionModel& model) const {
    const auto& c = mission.camera;
    const auto& m = model.camera;
    const auto differs = [&](const char* opt, double mine, double theirs) {
      if (app.count(opt) > 0 && mine != theirs)
        throw std::invalid_argument(std::string(opt) + " " + fmt(mine, 4) + " differs from the decision model's " +
                                    fmt(theirs, 4) + " (the model was calibrated for its camera and speed)");
    };
    if (app.count("--camera") > 0 && (c.image_width_px != m.image_width_px || c.image_height_px != m.image_height_px ||
                                      c.sensor_width_mm != m.sensor_width_mm || c.focal_length_mm != m.focal_length_mm))
      throw std::invalid_argument("--camera " + camera_preset_name + " (" + std::to_string(c.image_width_px) + "x" +
                                  std::to_string(c.image_height_px) + " px, " + fmt(c.sensor_width_mm, 2) +
                                  " mm sensor, " + fmt(c.focal_length_mm, 2) +
                                  " mm focal) differs from the decision model's camera (" +
                                  std::to_string(m.image_width_px) + "x" + std::to_string(m.image_height_px) + " px, " +
                                  fmt(m.sensor_width_mm, 2) + " mm sensor, " + fmt(m.focal_length_mm, 2) +
                                  " mm focal): the model was calibrated for its camera");
    differs("--image-width", c.image_width_px, m.image_width_px);
    differs("--image-height", c.image_height_px, m.image_height_px);
    differs("--sensor-width-mm", c.sensor_width_mm, m.sensor_width_mm);
    differs("--focal-mm", c.focal_length_mm, m.focal_length_mm);
    differs("--speed", mission.timing.max_speed_mps, model.timing.max_speed_mps);
    differs("--accel", mission.timing.max_accel_mps2, model.timing.max_accel_mps2);
    differs("--vertical-speed", mission.timing.max_vertical_speed_mps, model.timing.max_vertical_speed_mps);
    if (app.count("--map-fusion") > 0 && map_fusion != to_string(model.map_fusion))
      throw std::invalid_argument("--map-fusion " + map_fusion + " differs from the decision model's " +
                                  to_string(model.map_fusion) + " (the model was calibrated with its maps)");
  }

  /// Resolves names against the field and validates the values (throws invalid_argument).
  MissionOptions resolve(const Field& field) const {
    MissionOptions out = mission;
    (void)CameraModel(out.camera);
    (void)TimingModel(out.timing);
    // The velocity-ramp model is a multicopter's: far beyond one, its times mean nothing
    // (--speed 1e308 flew a field in no time).
    const auto realistic = [](const char* flag, double v, const char* unit) {
      if (!(v > 100.0)) return;
      char text[32];
      std::snprintf(text, sizeof text, "%g", v);
      throw std::invalid_argument(std::string(flag) + " " + text + " " + unit +
                                  " is beyond any UAV the timing model describes (at most 100)");
    };
    realistic("--speed", out.timing.max_speed_mps, "m/s");
    realistic("--accel", out.timing.max_accel_mps2, "m/s^2");
    realistic("--vertical-speed", out.timing.max_vertical_speed_mps, "m/s");
    out.fixed_segmentation_time_s = seg_time_s;
    out.fixed_planning_time_s = plan_time_s;
    out.map_fusion = parse_map_fusion(map_fusion);
    if (!interest_names.empty()) out.interest = field.class_indices(interest_names);
    if (out.interest.empty() && field.interest().empty())
      throw std::invalid_argument("no labels of interest: field '" + field.name() + "' names none; pass --interest");
    return out;
  }
};

/// Calibration choices shared by adaptseg_calibrate and adaptseg_evaluate: the decision rule,
/// the settings tried, what a descent re-maps, and the time charged per image.
struct CalibrationCli {
  std::string rule = "front-aware";
  int threshold_steps = 10;
  std::string coverage = "ranked";
  std::string descent_grid = to_string(DescentGrid::region);
  std::string gain_extent = to_string(GainExtent::region);
  std::string gain_inputs = "delta-sigma-height";
  std::vector<double> confidences = kDefaultConfidences;
  std::string sigma_prior = to_string(CalibrationOptions::kDefaultSigmaPrior);
  std::optional<double> segmentation_time_s;
  std::vector<std::string> cell_inputs;
  std::string cell_input_score = to_string(CellInputScore::ranking);
  std::vector<std::string> slope_poolings{"cells", "fields"};
  std::string curve = to_string(CurveSource::corrected);  // the programs' default, not the struct's
  std::vector<std::string> top_levels{"undominated"};
  std::string field_factor = to_string(FieldFactorSource::scene_check);
  bool gain_ratios = false;
  bool margin_biases = false;
  bool jump_guard = false;
  bool relabel_transfer = false;
  bool relabel_region_spread = false;
  bool relabel_field_spread = false;
  bool learn_stop_only = false;
  bool frozen_folds = false;
  double curve_agreement = 0.0;
  std::vector<double> finest_descent_factors;
  std::vector<double> longest_descent_s;

  void add_to(CLI::App& app) {
    options_ = {
        app.add_option("--rule", rule,
                       "decision rule: front-aware (descend while descents beat the lawnmower curve; no threshold) "
                       "or utility (the paper's: utility against a threshold calibrated on the training fields)")
            ->check(CLI::IsMember(rule_names()))
            ->capture_default_str(),
        app.add_option("--threshold-steps", threshold_steps, "utility thresholds tried per weighting")
            ->capture_default_str(),
        app.add_option("--coverage", coverage,
                       "what a descent re-maps: region (the whole top-level footprint, the paper's), interest "
                       "(only the cells where the top-level image shows a label of interest) or ranked (the cells "
                       "ranked by a decision input of the top-level image, e.g. the network's expected error about "
                       "L; the number of cells chosen in flight); saved in the model")
            ->check(CLI::IsMember(detail::names_of(kDescentCoverages)))
            ->capture_default_str(),
        app.add_option(
               "--descent-grid", descent_grid,
               "how a descent's sub-lawnmower is laid: region (on its top-level footprint, the paper's; where "
               "the finer footprint does not divide it, neighbouring descents fly over the same ground) or field "
               "(the cells of the whole field's lawnmower at the descent's GSD whose centres lie in the region: "
               "no ground flown twice); saved in the model")
            ->check(CLI::IsMember(detail::names_of(kDescentGrids)))
            ->capture_default_str(),
        app.add_option("--gain-extent", gain_extent,
                       "which pixels a descent's field gain is counted over: region (its region's, the paper's) or "
                       "images (every pixel its images cover, fused into the field's map with the neighbouring "
                       "top-level images: what a flight realises; each ranked cell is then forecast for its whole "
                       "footprint); saved in the model")
            ->check(CLI::IsMember(detail::names_of(kGainExtents)))
            ->capture_default_str(),
        app.add_option("--cell-input", cell_inputs,
                       "coverage ranked: the decision inputs tried for ranking and forecasting cells, comma-separated "
                       "(default: sigma, boundary, ambiguity, expected_error, second_choice, those the backend gives; "
                       "the one that ranks the training fields' cells best is saved in the model)")
            ->delimiter(',')
            ->check(CLI::IsMember(detail::names_of(kDecisionInputs))),
        app.add_option("--cell-input-score", cell_input_score,
                       "coverage ranked: how the input is chosen, by the share of each training field's achievable "
                       "gain its best cells capture (ranking), or the same counted only where the cell gain model "
                       "fitted on the other training fields forecasts a gain (transfer)")
            ->check(CLI::IsMember(detail::names_of(kCellInputScores)))
            ->capture_default_str(),
        app.add_option("--slope-pooling", slope_poolings,
                       "coverage ranked, several training fields: how the cell gain model's slopes may pool the "
                       "fields, tried with every confidence level on the training fields, comma-separated: cells "
                       "(one fit over every field's cells) and fields (each field's own slope, pooled as random "
                       "effects) and field-entropy (as fields, the slope a line in the field's mean top-level entropy, "
                       "read in flight from the images so far); the first is kept unless another beats it on the "
                       "folds beyond their noise (one standard error), and the one kept is saved in the model")
            ->delimiter(',')
            ->check(CLI::IsMember(detail::names_of(kSlopePoolings)))
            ->capture_default_str(),
        app.add_option("--curve", curve,
                       "front-aware rule with --coverage ranked: the lawnmower curve a descent is compared with, "
                       "the training fields' (training), this field's as the cell gain model predicts it from "
                       "the top-level images (field), or that prediction scaled per training field by its real "
                       "lawnmowers' rise against the predicted one (corrected), or the corrected curves and the "
                       "training fields' together, their disagreement part of the curve's spread (mixture)")
            ->check(CLI::IsMember(detail::names_of(kCurveSources)))
            ->capture_default_str(),
        app.add_option("--field-factor", field_factor,
                       "front-aware rule with --coverage ranked: what the field factor (how much more or less "
                       "than forecast a closer look gains on this field) learns from in flight, each descent's "
                       "scene check, scaling the gain and the field's curve alike (scene-check), or its "
                       "relabelled share against the forecast one, scaling the gain only (relabelled)")
            ->check(CLI::IsMember(detail::names_of(kFieldFactorSources)))
            ->capture_default_str(),
        app.add_option("--top-level", top_levels,
                       "front-aware rule with --coverage ranked: how the top-level GSD is chosen among those "
                       "calibrated, the one whose lawnmower falls least short of the faster ones on the training "
                       "fields' curves, field by field (undominated), or from there a finer one while the predicted "
                       "curve rises faster per second up to it than beyond it (hull); comma-separated, each tried "
                       "with every confidence level on the training fields, the first kept unless another beats it "
                       "by more than one standard error of their paired fold margins; the one kept is saved in "
                       "the model")
            ->delimiter(',')
            ->check(CLI::IsMember(detail::names_of(kTopLevelChoices)))
            ->capture_default_str(),
        app.add_option("--gain-inputs", gain_inputs,
                       "what the GP I predicts the accuracy gain from: delta-sigma (the paper's) or "
                       "delta-sigma-height (the change of semantic ratio and of altitude)")
            ->check(CLI::IsMember({"delta-sigma", "delta-sigma-height"}))
            ->capture_default_str(),
        app.add_option("--confidence", confidences,
                       "front-aware rule: confidence levels z tried on the training fields (a descent must beat "
                       "the curve by z standard deviations); the best is saved in the model")
            ->delimiter(',')
            ->check(CLI::NonNegativeNumber)
            ->capture_default_str(),
        app.add_flag("--gain-ratios", gain_ratios,
                     "front-aware rule, several training fields: scale each forecast of a descent by what "
                     "descents to its GSD realised of their forecast when the training fields were flown with "
                     "the model of the others (measured before the search; saved in the model)"),
        app.add_flag("--jump-guard", jump_guard,
                     "front-aware rule with ranked cells: descend no more after a descent image whose share of "
                     "the labels of interest lies so far above the top-level map's over its cell that re-mapping "
                     "such cells lost on the training fields (that image not fused; saved in the model)"),
        app.add_flag("--relabel-transfer", relabel_transfer,
                     "front-aware rule with --field-factor relabelled: scale a descent's gain by the field "
                     "factor learnt from the relabelled share only as far as a field's gain moved with its "
                     "relabelled share on the training fields' cells (measured; saved in the model)"),
        app.add_flag("--relabel-region-spread", relabel_region_spread,
                     "front-aware rule with --field-factor relabelled: count how far one region's relabelled "
                     "share strayed from its field's on the training fields' cells as noise of each descent's "
                     "observation, so that one region does not carry the field factor with it (measured; saved "
                     "in the model)"),
        app.add_flag("--relabel-field-spread", relabel_field_spread,
                     "front-aware rule with --field-factor relabelled: the field factor's prior spread from how "
                     "far the training fields' relabelled shares strayed from the forecast on their cells, not "
                     "from how far their gains did (measured; saved in the model)"),
        app.add_flag("--learn-stop-only", learn_stop_only,
                     "front-aware rule: what the field factor learns in flight may only stop descents, never add "
                     "one: each candidate's bound is capped by the non-adaptive rule's (saved in the model)"),
        app.add_flag("--frozen-folds", frozen_folds,
                     "front-aware rule: the folds that choose the setting fly the non-adaptive rule, so that "
                     "what is learnt in a fold's flight cannot move the choice (the rule calibrated still "
                     "learns in flight)"),
        app.add_flag("--margin-biases", margin_biases,
                     "front-aware rule, several training fields: add to each descent's forecast margin what "
                     "descents to its GSD ended above theirs per second when the training fields were flown "
                     "with the model of the others (gain and lawnmower curve both; measured before the search; "
                     "saved in the model)"),
        app.add_option("--curve-agreement", curve_agreement,
                       "front-aware rule: descend to a GSD only where the lawnmower at it mapped better than the "
                       "top level's on at least this share of the training fields (0: no such check; saved in "
                       "the model)")
            ->check(CLI::Range(0.0, 1.0))
            ->capture_default_str(),
        app.add_option("--finest-descent", finest_descent_factors,
                       "front-aware rule: the finest GSDs a descent may be limited to, as multiples of the "
                       "training fields' GSD (0: no limit), comma-separated, each tried on the training fields' "
                       "folds with the setting the rest of the search kept; the first is kept unless another "
                       "beats it beyond the folds' noise (one standard error), and the one kept is saved in the "
                       "model (default: no limit, not searched)")
            ->delimiter(','),
        app.add_option("--longest-descent", longest_descent_s,
                       "front-aware rule: the most extra seconds a descent may cost (0: no limit), "
                       "comma-separated; every setting is searched with the first, then each other is tried on "
                       "the training fields' folds with every --confidence and the setting the rest of the search "
                       "kept; the first is kept unless another beats it beyond the folds' noise (one standard "
                       "error), and the one kept is saved in the model (default: no limit, not searched)")
            ->delimiter(','),
        app.add_option("--sigma-prior", sigma_prior,
                       "front-aware rule with several training fields: the prior of the field's share of L "
                       "(sigma-hat): given (weight 0.25 fields, no spread), spread (its spread over the training "
                       "fields enters the lower bound) or estimated (weight and spread from the training fields)")
            ->check(CLI::IsMember(detail::names_of(kSigmaPriorSources)))
            ->capture_default_str(),
        app.add_option("--calibration-seg-time-s", segmentation_time_s,
                       "segmentation time charged per image during calibration [s], recorded in the model "
                       "(default: --seg-time-s if given, else 0.1)")
            ->check(CLI::NonNegativeNumber),
    };
  }

  /// Makes giving any calibration flag together with `other` (e.g. `--decision-model`, which loads a
  /// calibrated model) a command-line error instead of a silently ignored flag.
  void exclude(CLI::Option* other) {
    for (CLI::Option* o : options_) o->excludes(other);
  }

  /// Sets the rule and the settings it tries, the descent coverage, I's inputs and the time
  /// charged per image of `options` (`common`: the programs' --seg-time-s and --plan-time-s;
  /// `field_gsd_cm`: the training fields' GSD, which --finest-descent's factors multiply).
  /// @throws std::invalid_argument as check_calibration_options (a choice given twice).
  void apply(CalibrationOptions& options, const CommonOptions& common, double field_gsd_cm) const {
    options.threshold_steps = threshold_steps;
    options.rule = rule;
    options.confidences = confidences;
    options.sigma_prior = parse_sigma_prior_source(sigma_prior);
    options.adaptive.coverage = parse_descent_coverage(coverage);
    options.adaptive.descent_grid = parse_descent_grid(descent_grid);
    options.adaptive.gain_extent = parse_gain_extent(gain_extent);
    options.front_aware.curve = parse_curve_source(curve);
    options.front_aware.field_factor = parse_field_factor_source(field_factor);
    options.gain_ratios = gain_ratios;
    options.margin_biases = margin_biases;
    options.jump_guard = jump_guard;
    options.relabel_transfer = relabel_transfer;
    options.relabel_region_spread = relabel_region_spread;
    options.relabel_field_spread = relabel_field_spread;
    options.front_aware.curve_agreement = curve_agreement;
    options.front_aware.learn_stop_only = learn_stop_only;
    options.frozen_folds = frozen_folds;
    options.finest_descent_gsd_cm.clear();
    for (std::size_t k = 0; k < finest_descent_factors.size(); ++k) {
      const double f = finest_descent_factors[k];
      if (!(std::isfinite(f) && f >= 0.0))
        throw std::invalid_argument("--finest-descent " + fmt(f, 3) +
                                    " is not a GSD factor: give multiples of the field's GSD, 0 for no limit");
      if (std::find(finest_descent_factors.begin(), finest_descent_factors.begin() + static_cast<std::ptrdiff_t>(k),
                    f) != finest_descent_factors.begin() + static_cast<std::ptrdiff_t>(k))
        throw std::invalid_argument("--finest-descent names the factor " + fmt(f, 3) +
                                    " twice: give each limit once (0: no limit)");
      options.finest_descent_gsd_cm.push_back(f * field_gsd_cm);
    }
    options.longest_descent_s.clear();
    for (const double s : longest_descent_s) {
      if (!(std::isfinite(s) && s >= 0.0))
        throw std::invalid_argument("--longest-descent " + fmt(s, 3) +
                                    " is not a number of seconds: give seconds >= 0, 0 for no limit");
      if (std::find(options.longest_descent_s.begin(), options.longest_descent_s.end(), s) !=
          options.longest_descent_s.end())
        throw std::invalid_argument("--longest-descent names " + fmt(s, 3) +
                                    " s twice: give each limit once (0: no limit)");
      options.longest_descent_s.push_back(s);
    }
    options.top_levels.clear();
    for (const auto& name : top_levels) options.top_levels.push_back(parse_top_level_choice(name));
    options.cell_inputs.clear();
    for (const auto& name : cell_inputs) options.cell_inputs.push_back(parse_decision_input(name));
    options.cell_input_score = parse_cell_input_score(cell_input_score);
    options.slope_poolings.clear();
    for (const auto& name : slope_poolings) options.slope_poolings.push_back(parse_slope_pooling(name));
    options.fit.gain_inputs = gain_inputs == "delta-sigma-height" ? GainModel::GainInputs::delta_sigma_and_height
                                                                  : GainModel::GainInputs::delta_sigma;
    options.segmentation_time_s = segmentation_time_s.value_or(common.seg_time_s.value_or(0.1));
    options.planning_time_s = common.plan_time_s.value_or(0.0);
    check_calibration_options(options);  // a repeated choice refused before any field is read
  }

 private:
  std::vector<CLI::Option*> options_;
};

inline nlohmann::json opt_json(const std::optional<double>& v) {
  return v && std::isfinite(*v) ? nlohmann::json(*v) : nlohmann::json(nullptr);
}

/// Adds a mission's decisions to its result.json document `j` (schema in docs/data_format.md):
/// each under its top-level image in `j["waypoints"]` (`decision`: the action, σ, the candidates
/// with their forecasts and, after a descent, the region's σ at the finer GSD), and their counts
/// as `j["decisions"]`. The one writer of both adaptseg_mission's and adaptseg_live's. A decision
/// whose image is not among `j["waypoints"]` (a live mission stopped on an error between the
/// report and its record) is counted, not attached: what stops a mission must not stop its record.
inline void add_decisions(nlohmann::json& j, const std::vector<DecisionRecord>& decisions, const std::string& policy) {
  using nlohmann::json;
  int descend = 0, limited = 0;
  for (const auto& d : decisions) {
    descend += d.decision.descend ? 1 : 0;
    limited += d.budget_limited ? 1 : 0;
    json dj{{"action", d.decision.descend ? "descend" : "continue"},
            {"sigma", d.sigma},
            {"budget_limited", d.budget_limited}};
    if (d.decision.descend) {
      dj["gsd_cm"] = d.decision.gsd_cm;
      dj["candidate"] = chosen_candidate(d.decision, d.candidates, policy);
    }
    json cands = json::array();
    for (std::size_t k = 0; k < d.candidates.size(); ++k) {
      json cj{{"gsd_cm", d.candidates[k].gsd_cm},
              {"images", d.candidates[k].images},
              {"extra_time_s", d.candidates[k].extra_time_s}};
      if (k < d.decision.scores.size()) {
        const auto& sc = d.decision.scores[k];
        cj["predicted_delta_sigma"] = sc.predicted_delta_sigma;
        cj["predicted_delta_miou"] = sc.predicted_delta_miou;
        cj["predicted_delta_miou_std"] = sc.predicted_delta_miou_std;
        cj["utility"] = std::isfinite(sc.utility) ? json(sc.utility) : json(nullptr);
        if (std::isfinite(sc.predicted_front_margin)) cj["predicted_front_margin"] = sc.predicted_front_margin;
      }
      cands.push_back(cj);
    }
    dj["candidates"] = cands;
    if (d.outcome) dj["observed_sigma_sub"] = d.outcome->sigma_sub;
    if (d.waypoint_index < j["waypoints"].size()) j["waypoints"][d.waypoint_index]["decision"] = dj;
  }
  j["decisions"] = {
      {"descend", descend}, {"continue", static_cast<int>(decisions.size()) - descend}, {"budget_limited", limited}};
}

/// The result.json document of a mission (schema in docs/data_format.md).
inline nlohmann::json result_json(const Field& field, const MissionResult& r, const MissionOptions& opt,
                                  const std::vector<DecisionRecord>* decisions = nullptr) {
  using nlohmann::json;
  json j;
  j["field"] = r.field;
  j["strategy"] = r.strategy;
  j["segmenter"] = r.segmenter;
  json interest = json::array();
  for (int c : r.interest) interest.push_back(field.classes()[static_cast<std::size_t>(c)].name);
  j["interest"] = interest;
  j["miou_interest"] = opt_json(r.miou_interest());
  j["miou_all"] = opt_json(r.miou_all());
  json per_class = json::object();
  for (int c = 0; c < field.num_classes(); ++c)
    per_class[field.classes()[static_cast<std::size_t>(c)].name] = opt_json(r.confusion.iou(c));
  j["iou_per_class"] = per_class;
  j["images"] = r.waypoints.size();
  j["time_s"] = {{"total", r.total_s()},
                 {"flight", r.time.flight_s},
                 {"segmentation", r.time.segmentation_s},
                 {"planning", r.time.planning_s}};
  // Coverage: share of valid field pixels that received a label.
  const cv::Mat observed = (r.fused_labels != field.ignore_label()) & field.valid_mask();
  const int valid = field.valid_pixels();
  j["coverage"] = valid > 0 ? static_cast<double>(cv::countNonZero(observed)) / valid : 0.0;
  json wps = json::array();
  for (const auto& w : r.waypoints) {
    wps.push_back({{"x", w.waypoint.position.x()},
                   {"y", w.waypoint.position.y()},
                   {"z", w.waypoint.position.z()},
                   {"gsd_cm", w.waypoint.gsd_cm},
                   {"level", w.level},
                   {"semantic_ratio", w.semantic_ratio},
                   {"image_miou_interest", opt_json(w.image_miou_interest)},
                   {"image_miou_all", opt_json(w.image_miou_all)},
                   {"truth_ratio", opt_json(w.truth_ratio)},
                   {"segmentation_s", w.segmentation_s}});
  }
  j["waypoints"] = wps;
  if (decisions) add_decisions(j, *decisions, r.strategy);
  const auto& cam = opt.camera;
  j["camera"] = {{"image_width_px", cam.image_width_px},
                 {"image_height_px", cam.image_height_px},
                 {"sensor_width_mm", cam.sensor_width_mm},
                 {"focal_length_mm", cam.focal_length_mm}};
  j["timing"] = {{"max_speed_mps", opt.timing.max_speed_mps},
                 {"max_accel_mps2", opt.timing.max_accel_mps2},
                 {"max_vertical_speed_mps", opt.timing.max_vertical_speed_mps}};
  j["map_fusion"] = to_string(opt.map_fusion);
  j["adaptseg_version"] = kVersion;
  return j;
}

inline void write_text(const std::filesystem::path& file, const std::string& text) {
  std::ofstream os(file);
  if (!os) throw std::runtime_error("cannot write " + file.string());
  os << text;
  if (!os) throw std::runtime_error("error writing " + file.string());
}

inline void write_png(const std::filesystem::path& file, const cv::Mat& img) {
  if (!cv::imwrite(file.string(), img)) throw std::runtime_error("cannot write " + file.string());
}

}  // namespace adaptseg::examples
