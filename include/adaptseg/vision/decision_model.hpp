#pragma once
/// @file
/// The initialised decision model as a file (`adaptseg_calibrate --out model.yaml`): the
/// decision function (gain model and rule), the linear baseline's parameters, and what they
/// were calibrated for (fields, class set, labels of interest, camera, GSDs, backend). Plain
/// YAML: every fitted quantity, the Gaussian processes' data and hyperparameters included, is
/// a key that any YAML tool reads and edits; numbers are written and read by one
/// locale-independent codec (detail/number_text.hpp). Files of format 1 (adaptseg 0.1, with
/// the decision function as an embedded text block) are no longer read (since 0.2.0): load()
/// says so, and the model is calibrated again.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/core/timing.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/decision_rules.hpp>
#include <adaptseg/vision/detail/cell_model_io.hpp>
#include <adaptseg/vision/detail/number_text.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/gp_io.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace adaptseg {

namespace detail {

using ModelGp = GainModel::Gp;

}  // namespace detail

/// A calibrated decision model and its provenance.
struct DecisionModel {
  std::vector<std::string> calibration_fields;  ///< names of the training fields (with regions)
  std::string segmenter;                        ///< backend used for calibration
  /// Segmentation time charged per image during calibration [s]: declared, not measured, so
  /// that the model is a function of its inputs.
  double calibration_segmentation_time_s = 0.0;
  std::vector<std::string> classes;   ///< class names, index order
  std::vector<std::string> interest;  ///< labels of interest L
  CameraParams camera{};
  TimingParams timing{};
  double top_gsd_cm = 0.0;
  std::vector<double> candidate_gsd_cm;
  /// What the model's descents re-map (its samples were taken so); files without the key are
  /// `region`, the paper's.
  DescentCoverage coverage = DescentCoverage::region;
  DescentGrid descent_grid = DescentGrid::region;  ///< how its descents were laid; files without the key: region
  GainExtent gain_extent = GainExtent::region;     ///< what its gains count; files without the key: region
  DecisionFunction decision_function;
  LinearDecision::Params linear{};
  std::size_t samples = 0;          ///< region samples the GPs were fitted to
  double train_front_margin = 0.0;  ///< of the chosen rule, on the training fields (mean)
  /// Cross-fitted calibration: per calibration field, the backend that segmented it, where one
  /// differs from `segmenter` (a network that never saw that field; calibrate()); empty when
  /// `segmenter` segmented every field (the file then has no `field_segmenters`).
  std::vector<std::string> field_segmenters{};
  /// How the missions' maps combine images (its samples and curves were measured so); files
  /// without the key are `finest`, the paper's.
  MapFusion map_fusion = MapFusion::finest;

  /// The planner options of a mission flown with this model: its camera, timing, top and
  /// candidate GSDs, descent coverage, grid and gain extent and map fusion, with `mission`'s labels of interest and
  /// fixed times.
  [[nodiscard]] AdaptiveOptions adaptive_options(MissionOptions mission,
                                                 std::optional<double> budget_s = std::nullopt) const {
    mission.camera = camera;
    mission.timing = timing;
    mission.map_fusion = map_fusion;
    AdaptiveOptions o{std::move(mission), top_gsd_cm, candidate_gsd_cm, budget_s, coverage};
    o.descent_grid = descent_grid;
    o.gain_extent = gain_extent;
    if (const auto& cells = decision_function.model().cells()) o.cell_input = cells->input();
    return o;
  }

  /// The labels of interest as class indices of the model's class set (the labels the
  /// backend it was calibrated with gives): what MissionOptions::interest takes.
  [[nodiscard]] std::vector<int> interest_indices() const {
    std::vector<int> out;
    for (const auto& n : interest) {
      const auto it = std::find(classes.begin(), classes.end(), n);
      detail::require(it != classes.end(), "DecisionModel: a label of interest is not one of its classes", n);
      out.push_back(static_cast<int>(it - classes.begin()));
    }
    return out;
  }

  /// The model's class set is the field's (same names, same order): a model calibrated on
  /// one class set cannot score or fly another.
  /// @throws std::invalid_argument naming both class sets.
  void check_classes(const Field& field) const {
    std::vector<std::string> names;
    for (const auto& c : field.classes()) names.push_back(c.name);
    if (names != classes)
      throw std::invalid_argument("decision model was calibrated for classes [" + join(classes) + "] but field '" +
                                  field.name() + "' has [" + join(names) +
                                  "]: calibrate a model on a field with the same classes");
  }

  /// Throws unless `field` has the model's class set and `interest` (class indices of
  /// `field`) equals the model's labels of interest.
  /// @throws std::invalid_argument naming the mismatch.
  void check_compatible(const Field& field, const std::vector<int>& interest_indices) const {
    check_classes(field);
    std::vector<std::string> names;
    for (const auto& c : field.classes()) names.push_back(c.name);
    std::vector<std::string> in;
    for (int i : interest_indices) in.push_back(names.at(static_cast<std::size_t>(i)));
    if (in != interest)
      throw std::invalid_argument("decision model was calibrated for labels of interest [" + join(interest) +
                                  "] but the mission uses [" + join(in) + "]");
  }

  /// Writes the model as YAML (format 2).
  /// @throws std::runtime_error if the file cannot be written.
  void save(const std::filesystem::path& path) const {
    YAML::Emitter e;
    e << YAML::BeginMap;
    e << YAML::Key << "format" << YAML::Value << "adaptseg.decision_model/2";
    emit_calibration(e);
    emit_setup(e);
    emit_gain_model(e);
    e << YAML::Key << "rule" << YAML::Value << YAML::BeginMap;
    std::visit(
        [&](const auto& rule) {
          using Rule = RuleFor<std::decay_t<decltype(rule)>>;
          e << YAML::Key << "kind" << YAML::Value << std::string(Rule::kName);
          e << YAML::Key << "online" << YAML::Value << detail::flag_text(rule.params().online);
          e << YAML::Key << "min_sigma" << YAML::Value << detail::format_number(rule.params().min_sigma);
          Rule::write_keys(e, rule);
        },
        decision_function.rule());
    e << YAML::EndMap;
    e << YAML::EndMap;
    std::ofstream os(path);
    if (!os) throw std::runtime_error("cannot write " + path.string());
    os << e.c_str() << '\n';
    if (!os) throw std::runtime_error("error writing " + path.string());
  }

  /// Reads a model written by save() (format 2). A file of format 1 (adaptseg 0.1) is refused
  /// with a message saying to calibrate the model again.
  /// @throws std::invalid_argument naming the file and the problem (missing, not YAML,
  ///         another format, a missing or mistyped key, a broken decision function).
  [[nodiscard]] static DecisionModel load(const std::filesystem::path& path) {
    const std::string where = path.string();
    if (!std::filesystem::is_regular_file(path)) detail::yaml_error(where, "decision model file not found");
    const YAML::Node root =
        detail::yaml_mapping(where, "a decision model", [&] { return YAML::LoadFile(path.string()); });
    return detail::naming_file(where, [&] {
      const std::string format = root["format"] && root["format"].IsScalar() ? root["format"].Scalar() : "";
      const detail::YamlReader r(root, where);
      if (format == "adaptseg.decision_model/1")
        throw std::invalid_argument(where +
                                    ": a decision model of format 1 (adaptseg 0.1) is no longer read since "
                                    "adaptseg 0.2.0; calibrate the model again (adaptseg_calibrate)");
      if (format != "adaptseg.decision_model/2")
        throw std::invalid_argument(where +
                                    ": not an adaptseg decision model (format must be adaptseg.decision_model/2)");
      DecisionModel m = read_v2(r);
      m.check(where);
      return m;
    });
  }

 private:
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  }

  /// save()'s calibration record.
  void emit_calibration(YAML::Emitter& e) const {
    const auto num = [](double v) { return detail::format_number(v); };
    e << YAML::Key << "calibration" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "fields" << YAML::Value << YAML::Flow << calibration_fields;
    e << YAML::Key << "segmenter" << YAML::Value << segmenter;
    if (!field_segmenters.empty())
      e << YAML::Key << "field_segmenters" << YAML::Value << YAML::Flow << field_segmenters;
    e << YAML::Key << "segmentation_time_s" << YAML::Value << num(calibration_segmentation_time_s);
    e << YAML::Key << "samples" << YAML::Value << std::to_string(samples);
    e << YAML::Key << "train_front_margin" << YAML::Value << num(train_front_margin);
    e << YAML::EndMap;
  }

  /// save()'s class set, camera, timing, GSDs, coverage, fusion and linear baseline (read_setup).
  void emit_setup(YAML::Emitter& e) const {
    const auto num = [](double v) { return detail::format_number(v); };
    e << YAML::Key << "classes" << YAML::Value << YAML::Flow << classes;
    e << YAML::Key << "interest" << YAML::Value << YAML::Flow << interest;
    e << YAML::Key << "camera" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "image_width_px"
      << YAML::Value << std::to_string(camera.image_width_px) << YAML::Key << "image_height_px" << YAML::Value
      << std::to_string(camera.image_height_px) << YAML::Key << "sensor_width_mm" << YAML::Value
      << num(camera.sensor_width_mm) << YAML::Key << "focal_length_mm" << YAML::Value << num(camera.focal_length_mm)
      << YAML::EndMap;
    e << YAML::Key << "timing" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "max_speed_mps"
      << YAML::Value << num(timing.max_speed_mps) << YAML::Key << "max_accel_mps2" << YAML::Value
      << num(timing.max_accel_mps2);
    // Written only when set, so that models of the isotropic model keep their bytes.
    if (timing.max_vertical_speed_mps > 0.0)
      e << YAML::Key << "max_vertical_speed_mps" << YAML::Value << num(timing.max_vertical_speed_mps);
    e << YAML::EndMap;
    e << YAML::Key << "top_gsd_cm" << YAML::Value << num(top_gsd_cm);
    e << YAML::Key << "candidate_gsd_cm" << YAML::Value;
    detail::emit_numbers(e, candidate_gsd_cm);
    e << YAML::Key << "descent_coverage" << YAML::Value << to_string(coverage);
    // Written only when not the paper's, so that earlier models keep their bytes.
    if (descent_grid != DescentGrid::region) e << YAML::Key << "descent_grid" << YAML::Value << to_string(descent_grid);
    if (gain_extent != GainExtent::region) e << YAML::Key << "gain_extent" << YAML::Value << to_string(gain_extent);
    if (map_fusion != MapFusion::finest) e << YAML::Key << "map_fusion" << YAML::Value << to_string(map_fusion);
    e << YAML::Key << "linear" << YAML::Value << YAML::Flow << YAML::BeginMap << YAML::Key << "sigma_low" << YAML::Value
      << num(linear.sigma_low) << YAML::Key << "sigma_high" << YAML::Value << num(linear.sigma_high) << YAML::EndMap;
  }

  /// save()'s gain model: O, I, C and its efficiencies, the cell gain model.
  void emit_gain_model(YAML::Emitter& e) const {
    using detail::emit_numbers;
    const GainModel& gm = decision_function.model();
    e << YAML::Key << "gain_model" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "gain_inputs" << YAML::Value
      << (gm.gain_inputs() == GainModel::GainInputs::delta_sigma ? "delta-sigma" : "delta-sigma-height");
    e << YAML::Key << "refit_every" << YAML::Value << std::to_string(gm.refit_every());
    e << YAML::Key << "O" << YAML::Value;
    detail::emit_gp(e, gm.o_model());
    e << YAML::Key << "I" << YAML::Value;
    detail::emit_gp(e, gm.i_model());
    if (gm.c_model()) {
      e << YAML::Key << "C" << YAML::Value;
      detail::emit_gp(e, *gm.c_model());
      std::vector<double> h, v;
      for (const auto& p : gm.efficiency_points()) h.push_back(p.delta_h_m), v.push_back(p.efficiency);
      e << YAML::Key << "efficiency" << YAML::Value << YAML::BeginMap << YAML::Key << "delta_h_m" << YAML::Value;
      emit_numbers(e, h);
      e << YAML::Key << "eta" << YAML::Value;
      emit_numbers(e, v);
      e << YAML::EndMap;
    }
    if (const auto& cells = gm.cells()) {
      e << YAML::Key << "cells" << YAML::Value;
      detail::emit_cell_model(e, *cells);
    }
    e << YAML::EndMap;
  }

  /// The keys after the calibration record and the decision function (class set, camera,
  /// timing, GSDs, coverage, linear baseline), read into `m` (read_v2).
  static void read_setup(const detail::YamlReader& r, DecisionModel& m) {
    m.classes = r.texts("classes");
    m.interest = r.texts("interest");
    const auto cam = r.map("camera");
    m.camera = {static_cast<int>(cam.integer("image_width_px", 1, 1'000'000)),
                static_cast<int>(cam.integer("image_height_px", 1, 1'000'000)), cam.number("sensor_width_mm"),
                cam.number("focal_length_mm")};
    (void)CameraModel(m.camera);
    const auto tim = r.map("timing");
    m.timing = {tim.number("max_speed_mps"), tim.number("max_accel_mps2"),
                tim.has("max_vertical_speed_mps") ? tim.number("max_vertical_speed_mps") : 0.0};
    (void)TimingModel(m.timing);
    m.top_gsd_cm = r.number("top_gsd_cm");
    m.candidate_gsd_cm = r.numbers("candidate_gsd_cm");
    if (r.has("descent_coverage")) m.coverage = parse_descent_coverage(r.text("descent_coverage"));
    if (r.has("descent_grid")) m.descent_grid = parse_descent_grid(r.text("descent_grid"));
    if (r.has("gain_extent")) m.gain_extent = parse_gain_extent(r.text("gain_extent"));
    if (r.has("map_fusion")) m.map_fusion = parse_map_fusion(r.text("map_fusion"));
    const auto lin = r.map("linear");
    m.linear = {lin.number("sigma_low"), lin.number("sigma_high")};
    (void)LinearDecision(m.linear);
  }

  /// read_v2's gain model (`gain_model`: O, I, C and its efficiencies, the cells).
  static GainModel read_gain_model(const detail::YamlReader& r) {
    const auto gm = r.map("gain_model");
    const std::string inputs = gm.text("gain_inputs");
    if (inputs != "delta-sigma" && inputs != "delta-sigma-height")
      detail::yaml_error(r.where(),
                         "'gain_model.gain_inputs' must be delta-sigma or delta-sigma-height (got '" + inputs + "')");
    const bool with_c = gm.has("C");
    std::vector<GainModel::EfficiencyPoint> efficiency;
    if (with_c) {
      const auto eff = gm.map("efficiency");
      const auto h = eff.numbers("delta_h_m");
      const auto v = eff.numbers("eta");
      if (h.size() != v.size() || h.empty())
        detail::yaml_error(r.where(), "'gain_model.efficiency' needs as many 'eta' as 'delta_h_m' values (>= 1)");
      for (std::size_t k = 0; k < h.size(); ++k) efficiency.push_back({h[k], v[k]});
    }
    const auto gp = [&](const char* key, Eigen::Index dimension) {
      return detail::read_gp<detail::ModelGp::KernelType>(gm.map(key), dimension);
    };
    GainModel model(gp("O", 2), gp("I", inputs == "delta-sigma" ? 1 : 2),
                    with_c ? std::optional(gp("C", 2)) : std::nullopt, std::move(efficiency),
                    static_cast<int>(gm.integer("refit_every", 0, 1'000'000'000)));
    if (gm.has("cells")) model.set_cells(detail::read_cell_model(r.where(), gm.map("cells")));
    return model;
  }

  // The reader reads keys in the order of the model's members: a file with several faults
  // reports the first in that order.
  static DecisionModel read_v2(const detail::YamlReader& r) {
    const auto cal = r.map("calibration");
    GainModel model = read_gain_model(r);
    const auto rule = r.map("rule");
    const std::string kind = rule.text("kind");
    const bool online = rule.flag("online");
    const double min_sigma = rule.number("min_sigma");
    std::vector<std::string> fields = cal.texts("fields");
    std::string segmenter = cal.text("segmenter");
    const double segmentation_time_s = cal.number("segmentation_time_s");
    std::optional<DecisionFunction> function;
    for_each_rule([&]<class Rule>() {
      if (!function && kind == Rule::kName)
        function.emplace(Rule::read_keys(rule, std::move(model), min_sigma, online));
    });
    if (!function) detail::yaml_error(r.where(), "'rule.kind' must be " + rule_names_text() + " (got '" + kind + "')");
    const auto samples = static_cast<std::size_t>(cal.integer("samples", 0, 1'000'000'000));
    // The calibration record and the decision function; read_setup fills in the rest.
    DecisionModel m{.calibration_fields = std::move(fields),
                    .segmenter = std::move(segmenter),
                    .calibration_segmentation_time_s = segmentation_time_s,
                    .classes = {},
                    .interest = {},
                    .camera = {},
                    .timing = {},
                    .top_gsd_cm = 0.0,
                    .candidate_gsd_cm = {},
                    .coverage = DescentCoverage::region,
                    .decision_function = std::move(*function),
                    .linear = {},
                    .samples = samples,
                    .train_front_margin = cal.number("train_front_margin")};
    if (cal.has("field_segmenters")) m.field_segmenters = cal.texts("field_segmenters");
    read_setup(r, m);
    return m;
  }

  /// What the model must satisfy beyond each key's own check.
  void check(const std::string& where) const {
    if (calibration_fields.empty()) detail::yaml_error(where, "no calibration field is named");
    if (!field_segmenters.empty() && field_segmenters.size() != calibration_fields.size())
      detail::yaml_error(where, "'calibration.field_segmenters' needs one backend per calibration field (" +
                                    std::to_string(calibration_fields.size()) + "), got " +
                                    std::to_string(field_segmenters.size()));
    if (classes.empty()) detail::yaml_error(where, "'classes' is empty");
    if (interest.empty()) detail::yaml_error(where, "'interest' is empty");
    for (const auto& n : interest)
      if (std::find(classes.begin(), classes.end(), n) == classes.end())
        detail::yaml_error(where, "label of interest '" + n + "' is not among the classes");
    if (!(top_gsd_cm > 0.0)) detail::yaml_error(where, "'top_gsd_cm' must be > 0");
    if (candidate_gsd_cm.empty()) detail::yaml_error(where, "'candidate_gsd_cm' is empty");
    for (double g : candidate_gsd_cm)
      if (!(g > 0.0 && g < top_gsd_cm))
        detail::yaml_error(where, "candidate GSDs must be positive and finer than top_gsd_cm");
    if (!(calibration_segmentation_time_s >= 0.0))
      detail::yaml_error(where, "'calibration.segmentation_time_s' must be >= 0");
    if (descent_coverage_info(coverage).ranks_cells && !decision_function.model().cells())
      detail::yaml_error(where, "descent_coverage '" + std::string(to_string(coverage)) +
                                    "' needs a cell gain model ('gain_model.cells')");
  }
};

}  // namespace adaptseg
