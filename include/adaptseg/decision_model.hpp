#pragma once
/// @file
/// The initialised decision model as a file (`adaptseg_calibrate --out model.yaml`): the
/// decision function (gain model and rule), the linear baseline's parameters, and what they
/// were calibrated for (fields, class set, labels of interest, camera, GSDs, backend). Plain
/// YAML: every fitted quantity, the Gaussian processes' data and hyperparameters included, is
/// a key that any YAML tool reads and edits; numbers are written and read by one
/// locale-independent codec (detail/number_text.hpp). Files of format 1 (adaptseg 0.1, with
/// the decision function as an embedded text block) still load, with identical predictions.

#include <adaptseg/adaptive_planner.hpp>
#include <adaptseg/camera.hpp>
#include <adaptseg/decision_function.hpp>
#include <adaptseg/detail/number_text.hpp>
#include <adaptseg/field.hpp>
#include <adaptseg/lawnmower_planner.hpp>
#include <adaptseg/linear_decision.hpp>
#include <adaptseg/timing.hpp>

#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <optional>
#include <sstream>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace adaptseg {

namespace detail {

using ModelGp = GainModel::Gp;

/// Throws std::invalid_argument("<where>: <what>").
[[noreturn]] inline void model_error(const std::string& where, const std::string& what) {
  throw std::invalid_argument(where + ": " + what);
}

/// The decision-model YAML reader: every value read through the number codec, every error
/// naming the key.
class ModelReader {
 public:
  ModelReader(YAML::Node node, std::string where) : node_(std::move(node)), where_(std::move(where)) {}

  [[nodiscard]] bool has(const char* key) const { return static_cast<bool>(node_[key]); }
  [[nodiscard]] YAML::Node node(const char* key) const {
    const YAML::Node n = node_[key];
    if (!n) model_error(where_, std::string("missing key '") + path(key) + "'");
    return n;
  }
  [[nodiscard]] ModelReader map(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsMap()) model_error(where_, "'" + path(key) + "' must be a mapping");
    return ModelReader(n, where_, path(key));
  }
  [[nodiscard]] std::string text(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsScalar()) model_error(where_, "'" + path(key) + "' must be a scalar");
    return n.Scalar();
  }
  [[nodiscard]] double number(const char* key) const { return number_of(node(key), path(key)); }
  [[nodiscard]] long long integer(const char* key, long long lo, long long hi) const {
    const YAML::Node n = node(key);
    const auto v = n.IsScalar() ? parse_integer(n.Scalar(), lo, hi) : std::nullopt;
    if (!v)
      model_error(where_, "'" + path(key) + "' must be an integer in [" + std::to_string(lo) + ", " +
                              std::to_string(hi) + "]");
    return *v;
  }
  [[nodiscard]] bool flag(const char* key) const {
    const std::string t = text(key);
    if (t != "true" && t != "false") model_error(where_, "'" + path(key) + "' must be true or false (got '" + t + "')");
    return t == "true";
  }
  [[nodiscard]] std::vector<double> numbers(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsSequence()) model_error(where_, "'" + path(key) + "' must be a list of numbers");
    std::vector<double> out;
    for (std::size_t k = 0; k < n.size(); ++k) out.push_back(number_of(n[k], path(key) + "[" + std::to_string(k) + "]"));
    return out;
  }
  [[nodiscard]] std::vector<std::string> texts(const char* key) const {
    const YAML::Node n = node(key);
    if (!n.IsSequence()) model_error(where_, "'" + path(key) + "' must be a list");
    std::vector<std::string> out;
    for (const auto& v : n) {
      if (!v.IsScalar()) model_error(where_, "'" + path(key) + "' must be a list of names");
      out.push_back(v.Scalar());
    }
    return out;
  }
  [[nodiscard]] const std::string& where() const noexcept { return where_; }
  [[nodiscard]] std::string path(const char* key) const { return prefix_.empty() ? key : prefix_ + "." + key; }
  [[nodiscard]] double number_of(const YAML::Node& n, const std::string& what) const {
    const auto v = n.IsScalar() ? parse_number(n.Scalar()) : std::nullopt;
    if (!v) model_error(where_, "'" + what + "' must be a finite number" + (n.IsScalar() ? " (got '" + n.Scalar() + "')" : ""));
    return *v;
  }

 private:
  ModelReader(YAML::Node node, std::string where, std::string prefix)
      : node_(std::move(node)), where_(std::move(where)), prefix_(std::move(prefix)) {}
  YAML::Node node_;
  std::string where_;
  std::string prefix_;
};

inline YAML::Emitter& emit_number(YAML::Emitter& e, double v) { return e << format_number(v); }

inline YAML::Emitter& emit_numbers(YAML::Emitter& e, const Eigen::Ref<const Eigen::VectorXd>& v) {
  e << YAML::Flow << YAML::BeginSeq;
  for (Eigen::Index k = 0; k < v.size(); ++k) emit_number(e, v(k));
  return e << YAML::EndSeq;
}

inline YAML::Emitter& emit_numbers(YAML::Emitter& e, const std::vector<double>& v) {
  return emit_numbers(e, Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
}

inline const char* flag_text(bool b) { return b ? "true" : "false"; }

/// A fitted GP as a mapping: kernel, hyperparameters with bounds, options, normalisation, data.
inline void emit_gp(YAML::Emitter& e, const ModelGp& gp) {
  const auto s = gp.state();
  e << YAML::BeginMap;
  e << YAML::Key << "kernel" << YAML::Value << std::string(ArdSquaredExponentialKernel::kName);
  e << YAML::Key << "log_parameters" << YAML::Value;
  emit_numbers(e, s.kernel.log_parameters());
  e << YAML::Key << "log_lower_bounds" << YAML::Value;
  emit_numbers(e, s.kernel.log_lower_bounds());
  e << YAML::Key << "log_upper_bounds" << YAML::Value;
  emit_numbers(e, s.kernel.log_upper_bounds());
  e << YAML::Key << "normalize_y" << YAML::Value << flag_text(s.options.normalize_y);
  e << YAML::Key << "y_mean" << YAML::Value;
  emit_number(e, s.y_mean);
  e << YAML::Key << "y_std" << YAML::Value;
  emit_number(e, s.y_std);
  e << YAML::Key << "initial_jitter" << YAML::Value;
  emit_number(e, s.options.initial_jitter);
  e << YAML::Key << "max_jitter_attempts" << YAML::Value << std::to_string(s.options.max_jitter_attempts);
  e << YAML::Key << "inputs" << YAML::Value << YAML::BeginSeq;
  for (Eigen::Index r = 0; r < s.inputs.rows(); ++r) emit_numbers(e, s.inputs.row(r).transpose());
  e << YAML::EndSeq;
  e << YAML::Key << "targets" << YAML::Value;
  emit_numbers(e, s.targets);
  e << YAML::EndMap;
}

/// Reads what emit_gp wrote; `dimension` is the number of inputs the model's role needs
/// (0: 1 or 2).
inline ModelGp read_gp(const ModelReader& r, int dimension) {
  const std::string kernel = r.text("kernel");
  if (kernel != ArdSquaredExponentialKernel::kName)
    model_error(r.where(), "'" + r.path("kernel") + "' must be " + std::string(ArdSquaredExponentialKernel::kName) +
                               " (got '" + kernel + "')");
  const auto vec = [&](const char* key) {
    const auto v = r.numbers(key);
    return Eigen::VectorXd(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size())));
  };
  ModelGp::State s{ArdSquaredExponentialKernel::from_log_parameters(vec("log_parameters"), vec("log_lower_bounds"),
                                                                    vec("log_upper_bounds")),
                   {}, 0.0, 1.0, {}, {}};
  s.options.normalize_y = r.flag("normalize_y");
  s.options.initial_jitter = r.number("initial_jitter");
  s.options.max_jitter_attempts = static_cast<int>(r.integer("max_jitter_attempts", 0, 30));
  s.y_mean = r.number("y_mean");
  s.y_std = r.number("y_std");
  s.targets = vec("targets");
  const YAML::Node rows = r.node("inputs");
  if (!rows.IsSequence() || rows.size() != static_cast<std::size_t>(s.targets.size()) || rows.size() == 0)
    model_error(r.where(), "'" + r.path("inputs") + "' must be a list of as many input rows as 'targets' has values (>= 1)");
  const auto dims = rows[0].IsSequence() ? static_cast<Eigen::Index>(rows[0].size()) : 0;
  if ((dimension > 0 && dims != dimension) || (dimension == 0 && dims != 1 && dims != 2))
    model_error(r.where(), "'" + r.path("inputs") + "' rows must have " +
                               (dimension > 0 ? std::to_string(dimension) : std::string("1 or 2")) + " values");
  s.inputs.resize(static_cast<Eigen::Index>(rows.size()), dims);
  for (std::size_t i = 0; i < rows.size(); ++i) {
    if (!rows[i].IsSequence() || static_cast<Eigen::Index>(rows[i].size()) != dims)
      model_error(r.where(), "'" + r.path("inputs") + "' rows must all have " + std::to_string(dims) + " values");
    for (Eigen::Index d = 0; d < dims; ++d)
      s.inputs(static_cast<Eigen::Index>(i), d) =
          r.number_of(rows[i][static_cast<std::size_t>(d)], r.path("inputs") + "[" + std::to_string(i) + "]");
  }
  return ModelGp::from_state(std::move(s));
}

/// Reads the decision-function text of adaptseg 0.1 (`adaptseg.decision_function` versions
/// 1-3, embedded in decision-model files of format 1). `field` names the calibration field
/// (the front-aware rule's reference curve). The rule's parameters map one to one, except
/// that the front-aware rule of that version ignores `min_utility` and `exploration` (every
/// calibrated file had -max and 0).
/// @throws std::invalid_argument naming what is wrong for truncated or garbled input.
[[nodiscard]] inline DecisionFunction read_legacy_decision_function(std::istream& is, const std::string& field) {
  const auto token = [&](const std::string& what) {
    std::string t;
    require(static_cast<bool>(is >> t), "DecisionFunction::load: input ends before " + what, "<end of input>");
    return t;
  };
  const auto expect = [&](const std::string& key) {
    const std::string t = token("'" + key + "'");
    require(t == key, "DecisionFunction::load: expected '" + key + "', found", t);
  };
  const auto parse = [&](const std::string& t, const std::string& what) {
    const auto v = parse_number(t);
    require(v.has_value(), "DecisionFunction::load: bad number for " + what, t);
    return *v;
  };
  const auto number = [&](const std::string& key) {
    expect(key);
    return parse(token("the value of '" + key + "'"), "'" + key + "'");
  };
  expect("adaptseg.decision_function");
  const std::string version = token("the format version");
  require(version == "1" || version == "2" || version == "3", "DecisionFunction::load: unsupported format version",
          version);
  const double min_sigma = number("min_sigma");
  const double min_utility = number("min_utility");
  const double exploration = number("exploration");
  const bool weight_by_sigma = number("weight_by_sigma") != 0.0;
  const bool online = number("online") != 0.0;
  const double refit_every = number("refit_every");  // range-checked before the cast (UB otherwise)
  require(refit_every >= 0.0 && refit_every <= 1e9 && refit_every == std::floor(refit_every),
          "DecisionFunction::load: refit_every must be an integer in [0, 1e9]", refit_every);
  const bool relative_utility = number("relative_utility") != 0.0;
  bool front_aware = false;
  std::vector<GsdPoint> reference;
  if (version != "1") {  // version 1 had neither
    front_aware = number("front_aware") != 0.0;
    const double n = number("reference_lawnmower");
    require(n >= 0.0 && n <= 1000.0 && n == std::floor(n), "DecisionFunction::load: bad point count for 'reference_lawnmower'",
            n);
    const auto value = [&](const char* what) {
      const std::string name = std::string("a reference_lawnmower ") + what;
      return parse(token(name), name);
    };
    for (int k = 0; k < static_cast<int>(n); ++k) {
      const double g = value("GSD");
      reference.push_back({g, value("mIoU")});
    }
  }
  is >> std::ws;
  ModelGp o = ModelGp::load(is);
  is >> std::ws;
  ModelGp i = [&] {
    if (version == "3") return ModelGp::load(is);
    // Versions 1-2 stored I with the isotropic kernel, which for its one input is the ARD
    // kernel with one length scale (same parameters, same layout).
    std::string block, line;
    bool ended = false;
    while (std::getline(is, line)) {
      if (line == "kernel " + std::string(SquaredExponentialKernel::kName))
        line = "kernel " + std::string(ArdSquaredExponentialKernel::kName);
      block += line + '\n';
      if (line.rfind("end ", 0) == 0) {
        ended = true;
        break;
      }
    }
    require(ended, "DecisionFunction::load: input ends inside I's Gaussian process", "<end of input>");
    std::istringstream in(block);
    ModelGp gp = ModelGp::load(in);
    require(gp.dimension() == 1, "DecisionFunction::load: I of a version 1-2 file must have 1 input; dimension",
            gp.dimension());
    return gp;
  }();
  expect("end");
  expect("adaptseg.decision_function");
  require(std::isfinite(min_sigma) && min_sigma >= 0.0 && min_sigma <= 1.0,
          "DecisionFunction::load: min_sigma must be in [0, 1]", min_sigma);
  GainModel model(std::move(o), std::move(i), std::nullopt, {}, static_cast<int>(refit_every));
  if (front_aware) {
    require(!reference.empty(), "DecisionFunction::load: the front-aware rule needs reference_lawnmower points; count",
            reference.size());
    return DecisionFunction(FrontAwarePolicy(std::move(model), {ReferenceCurve{field, std::move(reference)}},
                                             {.min_sigma = min_sigma, .weight_by_sigma = weight_by_sigma,
                                              .online = online}));
  }
  return DecisionFunction(UtilityPolicy(std::move(model), {.min_sigma = min_sigma,
                                                           .min_utility = min_utility,
                                                           .exploration = exploration,
                                                           .weight_by_sigma = weight_by_sigma,
                                                           .online = online,
                                                           .relative_utility = relative_utility}));
}

}  // namespace detail

/// A calibrated decision model and its provenance.
struct DecisionModel {
  std::vector<std::string> calibration_fields;  ///< names of the training fields (with regions)
  std::string segmenter;                  ///< backend used for calibration
  /// Segmentation time charged per image during calibration [s]: declared, not measured, so
  /// that the model is a function of its inputs (format 1 files: 0, unknown).
  double calibration_segmentation_time_s = 0.0;
  std::vector<std::string> classes;       ///< class names, index order
  std::vector<std::string> interest;      ///< labels of interest L
  CameraParams camera{};
  TimingParams timing{};
  double top_gsd_cm = 0.0;
  std::vector<double> candidate_gsd_cm;
  /// What the model's descents re-map (its samples were taken so); files of format 1
  /// without the key are `region`, the paper's.
  DescentCoverage coverage = DescentCoverage::region;
  DecisionFunction decision_function;
  LinearDecision::Params linear{};
  std::size_t samples = 0;                ///< region samples the GPs were fitted to
  double train_front_margin = 0.0;        ///< of the chosen rule, on the training fields (mean)

  /// The planner options of a mission flown with this model: its camera, timing, top and
  /// candidate GSDs and descent coverage, with `mission`'s labels of interest and fixed times.
  [[nodiscard]] AdaptiveOptions adaptive_options(MissionOptions mission,
                                                 std::optional<double> budget_s = std::nullopt) const {
    mission.camera = camera;
    mission.timing = timing;
    return {std::move(mission), top_gsd_cm, candidate_gsd_cm, budget_s, coverage};
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
      throw std::invalid_argument("decision model was calibrated for classes [" + join(classes) +
                                  "] but field '" + field.name() + "' has [" + join(names) +
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
    using detail::emit_number;
    using detail::emit_numbers;
    const auto num = [](double v) { return detail::format_number(v); };
    YAML::Emitter e;
    e << YAML::BeginMap;
    e << YAML::Key << "format" << YAML::Value << "adaptseg.decision_model/2";
    e << YAML::Key << "calibration" << YAML::Value << YAML::BeginMap;
    e << YAML::Key << "fields" << YAML::Value << YAML::Flow << calibration_fields;
    e << YAML::Key << "segmenter" << YAML::Value << segmenter;
    e << YAML::Key << "segmentation_time_s" << YAML::Value << num(calibration_segmentation_time_s);
    e << YAML::Key << "samples" << YAML::Value << std::to_string(samples);
    e << YAML::Key << "train_front_margin" << YAML::Value << num(train_front_margin);
    e << YAML::EndMap;
    e << YAML::Key << "classes" << YAML::Value << YAML::Flow << classes;
    e << YAML::Key << "interest" << YAML::Value << YAML::Flow << interest;
    e << YAML::Key << "camera" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "image_width_px" << YAML::Value << std::to_string(camera.image_width_px)
      << YAML::Key << "image_height_px" << YAML::Value << std::to_string(camera.image_height_px)
      << YAML::Key << "sensor_width_mm" << YAML::Value << num(camera.sensor_width_mm)
      << YAML::Key << "focal_length_mm" << YAML::Value << num(camera.focal_length_mm) << YAML::EndMap;
    e << YAML::Key << "timing" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "max_speed_mps" << YAML::Value << num(timing.max_speed_mps)
      << YAML::Key << "max_accel_mps2" << YAML::Value << num(timing.max_accel_mps2) << YAML::EndMap;
    e << YAML::Key << "top_gsd_cm" << YAML::Value << num(top_gsd_cm);
    e << YAML::Key << "candidate_gsd_cm" << YAML::Value;
    emit_numbers(e, candidate_gsd_cm);
    e << YAML::Key << "descent_coverage" << YAML::Value << to_string(coverage);
    e << YAML::Key << "linear" << YAML::Value << YAML::Flow << YAML::BeginMap
      << YAML::Key << "sigma_low" << YAML::Value << num(linear.sigma_low)
      << YAML::Key << "sigma_high" << YAML::Value << num(linear.sigma_high) << YAML::EndMap;
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
    e << YAML::EndMap;
    e << YAML::Key << "rule" << YAML::Value << YAML::BeginMap;
    std::visit(
        [&](const auto& rule) {
          using R = std::decay_t<decltype(rule)>;
          const auto& p = rule.params();
          e << YAML::Key << "kind" << YAML::Value
            << (std::is_same_v<R, FrontAwarePolicy> ? "front-aware" : "utility");
          e << YAML::Key << "online" << YAML::Value << detail::flag_text(p.online);
          e << YAML::Key << "min_sigma" << YAML::Value << num(p.min_sigma);
          e << YAML::Key << "weight_by_sigma" << YAML::Value << detail::flag_text(p.weight_by_sigma);
          if constexpr (std::is_same_v<R, FrontAwarePolicy>) {
            e << YAML::Key << "confidence" << YAML::Value << num(p.confidence);
            e << YAML::Key << "scale_prior_sd" << YAML::Value << num(p.scale_prior_sd);
            e << YAML::Key << "sigma_prior_weight" << YAML::Value << num(p.sigma_prior_weight);
            e << YAML::Key << "reference" << YAML::Value << YAML::BeginSeq;
            for (const auto& r : rule.reference()) {
              std::vector<double> g, m;
              for (const auto& pt : r.points) g.push_back(pt.gsd_cm), m.push_back(pt.miou);
              e << YAML::BeginMap << YAML::Key << "field" << YAML::Value << r.field << YAML::Key << "field_sigma"
                << YAML::Value << num(r.field_sigma) << YAML::Key << "gsd_cm" << YAML::Value;
              emit_numbers(e, g);
              e << YAML::Key << "miou" << YAML::Value;
              emit_numbers(e, m);
              e << YAML::EndMap;
            }
            e << YAML::EndSeq;
          } else {
            e << YAML::Key << "min_utility" << YAML::Value << num(p.min_utility);
            e << YAML::Key << "exploration" << YAML::Value << num(p.exploration);
            e << YAML::Key << "relative_utility" << YAML::Value << detail::flag_text(p.relative_utility);
          }
        },
        decision_function.rule());
    e << YAML::EndMap;
    e << YAML::EndMap;
    std::ofstream os(path);
    if (!os) throw std::runtime_error("cannot write " + path.string());
    os << e.c_str() << '\n';
    if (!os) throw std::runtime_error("error writing " + path.string());
  }

  /// Reads a model written by save() (format 2) or by adaptseg 0.1 (format 1).
  /// @throws std::invalid_argument naming the file and the problem (missing, not YAML,
  ///         another format, a missing or mistyped key, a broken decision function).
  [[nodiscard]] static DecisionModel load(const std::filesystem::path& path) {
    const std::string where = path.string();
    if (!std::filesystem::is_regular_file(path)) detail::model_error(where, "decision model file not found");
    YAML::Node root;
    try {
      root = YAML::LoadFile(path.string());
    } catch (const YAML::Exception& ex) {
      detail::model_error(where, std::string("YAML error: ") + ex.what());
    }
    if (!root.IsMap()) detail::model_error(where, "not a decision model (the document must be a mapping)");
    try {
      const std::string format = root["format"] && root["format"].IsScalar() ? root["format"].Scalar() : "";
      const detail::ModelReader r(root, where);
      DecisionModel m = format == "adaptseg.decision_model/2"   ? read_v2(r)
                        : format == "adaptseg.decision_model/1" ? read_v1(r)
                                                                : throw std::invalid_argument(
                                                                      where +
                                                                      ": not an adaptseg decision model (format must "
                                                                      "be adaptseg.decision_model/2 or /1)");
      m.check(where);
      return m;
    } catch (const YAML::Exception& ex) {
      detail::model_error(where, std::string("bad value: ") + ex.what());
    } catch (const std::invalid_argument& ex) {
      const std::string what = ex.what();
      if (what.rfind(where, 0) == 0) throw;
      detail::model_error(where, what);
    }
  }

 private:
  static std::string join(const std::vector<std::string>& v) {
    std::string s;
    for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
    return s;
  }

  /// The keys both formats share, read into `m`.
  static void read_common(const detail::ModelReader& r, DecisionModel& m) {
    m.classes = r.texts("classes");
    m.interest = r.texts("interest");
    const auto cam = r.map("camera");
    m.camera = {static_cast<int>(cam.integer("image_width_px", 1, 1'000'000)),
                static_cast<int>(cam.integer("image_height_px", 1, 1'000'000)), cam.number("sensor_width_mm"),
                cam.number("focal_length_mm")};
    (void)CameraModel(m.camera);
    const auto tim = r.map("timing");
    m.timing = {tim.number("max_speed_mps"), tim.number("max_accel_mps2")};
    (void)TimingModel(m.timing);
    m.top_gsd_cm = r.number("top_gsd_cm");
    m.candidate_gsd_cm = r.numbers("candidate_gsd_cm");
    if (r.has("descent_coverage")) m.coverage = parse_descent_coverage(r.text("descent_coverage"));
    const auto lin = r.map("linear");
    m.linear = {lin.number("sigma_low"), lin.number("sigma_high")};
    (void)LinearDecision(m.linear);
  }

  /// A model of what a reader parsed first (the calibration record and the decision function),
  /// the rest default until read_common fills it in.
  static DecisionModel parsed(std::vector<std::string> fields, std::string segmenter, double segmentation_time_s,
                              DecisionFunction function, std::size_t samples, double train_front_margin) {
    return {.calibration_fields = std::move(fields),
            .segmenter = std::move(segmenter),
            .calibration_segmentation_time_s = segmentation_time_s,
            .classes = {},
            .interest = {},
            .camera = {},
            .timing = {},
            .top_gsd_cm = 0.0,
            .candidate_gsd_cm = {},
            .coverage = DescentCoverage::region,
            .decision_function = std::move(function),
            .linear = {},
            .samples = samples,
            .train_front_margin = train_front_margin};
  }

  // Both readers read keys in the order of the model's members: a file with several faults
  // reports the first in that order.
  static DecisionModel read_v1(const detail::ModelReader& r) {
    const std::string field = r.text("calibration_field");
    std::istringstream df(r.text("decision_function"));
    std::string segmenter = r.text("segmenter");
    DecisionFunction function = detail::read_legacy_decision_function(df, field);
    const auto samples = static_cast<std::size_t>(r.integer("samples", 0, 1'000'000'000));
    DecisionModel m = parsed({field}, std::move(segmenter), 0.0, std::move(function), samples,
                             r.number("train_front_margin"));
    read_common(r, m);
    return m;
  }

  static DecisionModel read_v2(const detail::ModelReader& r) {
    const auto cal = r.map("calibration");
    const auto gm = r.map("gain_model");
    const std::string inputs = gm.text("gain_inputs");
    if (inputs != "delta-sigma" && inputs != "delta-sigma-height")
      detail::model_error(r.where(), "'gain_model.gain_inputs' must be delta-sigma or delta-sigma-height (got '" +
                                         inputs + "')");
    const bool with_c = gm.has("C");
    std::vector<GainModel::EfficiencyPoint> efficiency;
    if (with_c) {
      const auto eff = gm.map("efficiency");
      const auto h = eff.numbers("delta_h_m");
      const auto v = eff.numbers("eta");
      if (h.size() != v.size() || h.empty())
        detail::model_error(r.where(), "'gain_model.efficiency' needs as many 'eta' as 'delta_h_m' values (>= 1)");
      for (std::size_t k = 0; k < h.size(); ++k) efficiency.push_back({h[k], v[k]});
    }
    GainModel model(detail::read_gp(gm.map("O"), 2), detail::read_gp(gm.map("I"), inputs == "delta-sigma" ? 1 : 2),
                    with_c ? std::optional(detail::read_gp(gm.map("C"), 2)) : std::nullopt, std::move(efficiency),
                    static_cast<int>(gm.integer("refit_every", 0, 1'000'000'000)));
    const auto rule = r.map("rule");
    const std::string kind = rule.text("kind");
    const bool online = rule.flag("online");
    const double min_sigma = rule.number("min_sigma");
    const bool weight_by_sigma = rule.flag("weight_by_sigma");
    const auto make_function = [&]() -> DecisionFunction {
      if (kind == "front-aware") {
        const YAML::Node refs = rule.node("reference");
        if (!refs.IsSequence()) detail::model_error(r.where(), "'rule.reference' must be a list of curves");
        std::vector<ReferenceCurve> reference;
        for (std::size_t k = 0; k < refs.size(); ++k) {
          if (!refs[k].IsMap()) detail::model_error(r.where(), "'rule.reference' entries must be mappings");
          const detail::ModelReader c(refs[k], r.where());
          const auto g = c.numbers("gsd_cm");
          const auto v = c.numbers("miou");
          if (g.size() != v.size())
            detail::model_error(r.where(), "a 'rule.reference' curve needs as many 'miou' as 'gsd_cm' values");
          ReferenceCurve curve{c.text("field"), {}, c.has("field_sigma") ? c.number("field_sigma") : 0.0};
          for (std::size_t i = 0; i < g.size(); ++i) curve.points.push_back({g[i], v[i]});
          reference.push_back(std::move(curve));
        }
        return DecisionFunction(FrontAwarePolicy(std::move(model), std::move(reference),
                                                 {.min_sigma = min_sigma,
                                                  .weight_by_sigma = weight_by_sigma,
                                                  .online = online,
                                                  .confidence = rule.number("confidence"),
                                                  .scale_prior_sd = rule.number("scale_prior_sd"),
                                                  .sigma_prior_weight = rule.number("sigma_prior_weight")}));
      }
      if (kind == "utility")
        return DecisionFunction(UtilityPolicy(std::move(model), {.min_sigma = min_sigma,
                                                                 .min_utility = rule.number("min_utility"),
                                                                 .exploration = rule.number("exploration"),
                                                                 .weight_by_sigma = weight_by_sigma,
                                                                 .online = online,
                                                                 .relative_utility = rule.flag("relative_utility")}));
      detail::model_error(r.where(), "'rule.kind' must be front-aware or utility (got '" + kind + "')");
    };
    std::vector<std::string> fields = cal.texts("fields");
    std::string segmenter = cal.text("segmenter");
    const double segmentation_time_s = cal.number("segmentation_time_s");
    DecisionFunction function = make_function();
    const auto samples = static_cast<std::size_t>(cal.integer("samples", 0, 1'000'000'000));
    DecisionModel m = parsed(std::move(fields), std::move(segmenter), segmentation_time_s, std::move(function),
                             samples, cal.number("train_front_margin"));
    read_common(r, m);
    return m;
  }

  /// What the model must satisfy whatever its format.
  void check(const std::string& where) const {
    if (calibration_fields.empty()) detail::model_error(where, "no calibration field is named");
    if (classes.empty()) detail::model_error(where, "'classes' is empty");
    if (interest.empty()) detail::model_error(where, "'interest' is empty");
    for (const auto& n : interest)
      if (std::find(classes.begin(), classes.end(), n) == classes.end())
        detail::model_error(where, "label of interest '" + n + "' is not among the classes");
    if (!(top_gsd_cm > 0.0)) detail::model_error(where, "'top_gsd_cm' must be > 0");
    if (candidate_gsd_cm.empty()) detail::model_error(where, "'candidate_gsd_cm' is empty");
    for (double g : candidate_gsd_cm)
      if (!(g > 0.0 && g < top_gsd_cm))
        detail::model_error(where, "candidate GSDs must be positive and finer than top_gsd_cm");
    if (!(calibration_segmentation_time_s >= 0.0))
      detail::model_error(where, "'calibration.segmentation_time_s' must be >= 0");
  }
};

}  // namespace adaptseg
