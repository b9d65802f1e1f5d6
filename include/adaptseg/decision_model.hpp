#pragma once
/// @file
/// The initialised decision model as a file (`adaptseg_calibrate --out model.yaml`): the
/// decision function (GPs and thresholds), the linear baseline's parameters, and what they
/// were calibrated for (class set, labels of interest, camera, GSDs, backend).

#include <adaptseg/adaptive_planner.hpp>
#include <adaptseg/camera.hpp>
#include <adaptseg/decision_function.hpp>
#include <adaptseg/field.hpp>
#include <adaptseg/lawnmower_planner.hpp>
#include <adaptseg/linear_decision.hpp>
#include <adaptseg/timing.hpp>

#include <yaml-cpp/yaml.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// A calibrated decision model and its provenance.
struct DecisionModel {
  std::string calibration_field;          ///< name of the training field (with region)
  std::string segmenter;                  ///< backend used for calibration
  std::vector<std::string> classes;       ///< class names, index order
  std::vector<std::string> interest;      ///< labels of interest L
  CameraParams camera{};
  TimingParams timing{};
  double top_gsd_cm = 0.0;
  std::vector<double> candidate_gsd_cm;
  /// What the model's descents re-map (its samples were taken so); files without the key
  /// are `region`, the paper's.
  DescentCoverage coverage = DescentCoverage::region;
  DecisionFunction decision_function;
  LinearDecision::Params linear{};
  std::size_t samples = 0;                ///< region samples the GPs were fitted to
  double train_front_margin = 0.0;        ///< of the chosen thresholds, on the training field

  /// The planner options of a mission flown with this model: its camera, timing, top and
  /// candidate GSDs and descent coverage, with `mission`'s labels of interest and fixed times.
  [[nodiscard]] AdaptiveOptions adaptive_options(MissionOptions mission,
                                                 std::optional<double> budget_s = std::nullopt) const {
    mission.camera = camera;
    mission.timing = timing;
    return {std::move(mission), top_gsd_cm, candidate_gsd_cm, budget_s, coverage};
  }

  /// Throws unless `field` has the model's class set and `interest` (class indices of
  /// `field`) equals the model's labels of interest.
  /// @throws std::invalid_argument naming the mismatch.
  void check_compatible(const Field& field, const std::vector<int>& interest_indices) const {
    std::vector<std::string> names;
    for (const auto& c : field.classes()) names.push_back(c.name);
    if (names != classes)
      throw std::invalid_argument("decision model was calibrated for classes [" + join(classes) +
                                  "] but field '" + field.name() + "' has [" + join(names) + "]");
    std::vector<std::string> in;
    for (int i : interest_indices) in.push_back(names.at(static_cast<std::size_t>(i)));
    if (in != interest)
      throw std::invalid_argument("decision model was calibrated for labels of interest [" + join(interest) +
                                  "] but the mission uses [" + join(in) + "]");
  }

  /// Writes the model as YAML.
  /// @throws std::runtime_error if the file cannot be written.
  void save(const std::filesystem::path& path) const {
    std::ostringstream df;
    decision_function.save(df);
    YAML::Emitter e;
    e << YAML::BeginMap;
    e << YAML::Key << "format" << YAML::Value << "adaptseg.decision_model/1";
    e << YAML::Key << "calibration_field" << YAML::Value << calibration_field;
    e << YAML::Key << "segmenter" << YAML::Value << segmenter;
    e << YAML::Key << "classes" << YAML::Value << YAML::Flow << classes;
    e << YAML::Key << "interest" << YAML::Value << YAML::Flow << interest;
    e << YAML::Key << "camera" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "image_width_px" << YAML::Value << camera.image_width_px
      << YAML::Key << "image_height_px" << YAML::Value << camera.image_height_px
      << YAML::Key << "sensor_width_mm" << YAML::Value << camera.sensor_width_mm
      << YAML::Key << "focal_length_mm" << YAML::Value << camera.focal_length_mm << YAML::EndMap;
    e << YAML::Key << "timing" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "max_speed_mps" << YAML::Value << timing.max_speed_mps
      << YAML::Key << "max_accel_mps2" << YAML::Value << timing.max_accel_mps2 << YAML::EndMap;
    e << YAML::Key << "top_gsd_cm" << YAML::Value << top_gsd_cm;
    e << YAML::Key << "candidate_gsd_cm" << YAML::Value << YAML::Flow << candidate_gsd_cm;
    e << YAML::Key << "descent_coverage" << YAML::Value << to_string(coverage);
    e << YAML::Key << "linear" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "sigma_low" << YAML::Value << linear.sigma_low
      << YAML::Key << "sigma_high" << YAML::Value << linear.sigma_high << YAML::EndMap;
    e << YAML::Key << "samples" << YAML::Value << samples;
    e << YAML::Key << "train_front_margin" << YAML::Value << train_front_margin;
    e << YAML::Key << "decision_function" << YAML::Value << YAML::Literal << df.str();
    e << YAML::EndMap;
    std::ofstream os(path);
    if (!os) throw std::runtime_error("cannot write " + path.string());
    os << e.c_str() << '\n';
    if (!os) throw std::runtime_error("error writing " + path.string());
  }

  /// Reads a model written by save().
  /// @throws std::invalid_argument naming the file and the problem (missing, not YAML,
  ///         another format, a missing or mistyped key, a broken decision function).
  [[nodiscard]] static DecisionModel load(const std::filesystem::path& path) {
    const auto fail = [&](const std::string& what) -> void {
      throw std::invalid_argument(path.string() + ": " + what);
    };
    if (!std::filesystem::is_regular_file(path)) fail("decision model file not found");
    YAML::Node root;
    try {
      root = YAML::LoadFile(path.string());
    } catch (const YAML::Exception& ex) {
      fail(std::string("YAML error: ") + ex.what());
    }
    if (!root.IsMap()) fail("not a decision model (the document must be a mapping)");
    try {
      if (!root["format"] || root["format"].as<std::string>() != "adaptseg.decision_model/1")
        fail("not an adaptseg decision model (format must be adaptseg.decision_model/1)");
      const auto req = [&](const char* key) {
        if (!root[key]) fail(std::string("missing key '") + key + "'");
        return root[key];
      };
      std::istringstream df(req("decision_function").as<std::string>());
      DecisionModel m{.calibration_field = req("calibration_field").as<std::string>(),
                      .segmenter = req("segmenter").as<std::string>(),
                      .classes = req("classes").as<std::vector<std::string>>(),
                      .interest = req("interest").as<std::vector<std::string>>(),
                      .camera = {},
                      .timing = {},
                      .top_gsd_cm = req("top_gsd_cm").as<double>(),
                      .candidate_gsd_cm = req("candidate_gsd_cm").as<std::vector<double>>(),
                      .coverage = root["descent_coverage"]
                                      ? parse_descent_coverage(root["descent_coverage"].as<std::string>())
                                      : DescentCoverage::region,
                      .decision_function = DecisionFunction::load(df),
                      .linear = {},
                      .samples = req("samples").as<std::size_t>(),
                      .train_front_margin = req("train_front_margin").as<double>()};
      const YAML::Node cam = req("camera");
      m.camera = {cam["image_width_px"].as<int>(), cam["image_height_px"].as<int>(),
                  cam["sensor_width_mm"].as<double>(), cam["focal_length_mm"].as<double>()};
      (void)CameraModel(m.camera);
      const YAML::Node tim = req("timing");
      m.timing = {tim["max_speed_mps"].as<double>(), tim["max_accel_mps2"].as<double>()};
      (void)TimingModel(m.timing);
      const YAML::Node lin = req("linear");
      m.linear = {lin["sigma_low"].as<double>(), lin["sigma_high"].as<double>()};
      (void)LinearDecision(m.linear);
      if (m.classes.empty()) fail("'classes' is empty");
      if (m.interest.empty()) fail("'interest' is empty");
      for (const auto& n : m.interest)
        if (std::find(m.classes.begin(), m.classes.end(), n) == m.classes.end())
          fail("label of interest '" + n + "' is not among the classes");
      if (!(m.top_gsd_cm > 0.0)) fail("'top_gsd_cm' must be > 0");
      if (m.candidate_gsd_cm.empty()) fail("'candidate_gsd_cm' is empty");
      for (double g : m.candidate_gsd_cm)
        if (!(g > 0.0 && g < m.top_gsd_cm)) fail("candidate GSDs must be positive and finer than top_gsd_cm");
      return m;
    } catch (const YAML::Exception& ex) {
      fail(std::string("bad value: ") + ex.what());
    } catch (const std::invalid_argument& ex) {
      const std::string what = ex.what();
      if (what.rfind(path.string(), 0) == 0) throw;
      fail(what);
    }
    throw std::logic_error("unreachable");
  }

 private:
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  }
};

}  // namespace adaptseg
