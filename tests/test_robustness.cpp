// Hardened input: every row of docs/robustness.md is proved by the test case
// of the same name here. Each bad input is built in a temporary directory from the bundled
// data (a crop of examples/data/weedmap-000, examples/models/erfnet-dubai) with one thing
// broken, and must give the documented exception type and message fragment: no crash, no
// sanitizer report, no silent acceptance. Also the library half of item 5 (determinism).

#include "test_support.hpp"

#include <adaptseg/core/decision_function.hpp>
#include <adaptseg/core/gaussian_process.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/gp_io.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/region_samples.hpp>

#include <doctest/doctest.h>

#include <opencv2/imgcodecs.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;
namespace fs = std::filesystem;
using doctest::Contains;

namespace {

const double kNaN = std::numeric_limits<double>::quiet_NaN();
const double kInf = std::numeric_limits<double>::infinity();

std::string read_text(const fs::path& p) {
  std::ifstream is(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(is), std::istreambuf_iterator<char>()};
}

/// `text` with the first occurrence of `from` replaced by `to` (which must occur).
std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  REQUIRE_MESSAGE(at != std::string::npos, "'" << from << "' not found");
  return text.replace(at, from.size(), to);
}

fs::path weedmap_dir() { return t::example_field("weedmap-000"); }

/// A 240 x 180 px crop of the bundled WeedMap labels (all three classes and ignore pixels).
const cv::Mat& weedmap_crop() {
  static const cv::Mat crop = [] {
    const cv::Mat all = cv::imread((weedmap_dir() / "labels.png").string(), cv::IMREAD_UNCHANGED);
    REQUIRE(all.type() == CV_8UC1);
    return all(cv::Rect(1200, 3000, 240, 180)).clone();
  }();
  return crop;
}

/// The bundled WeedMap field.yaml.
std::string weedmap_yaml() { return read_text(weedmap_dir() / "field.yaml"); }

/// Writes a field directory `dir` with `yaml` and `labels` (default: the WeedMap crop).
fs::path make_field(const fs::path& dir, const std::string& yaml, const cv::Mat& labels = weedmap_crop()) {
  t::write_field(dir, labels, yaml);
  return dir;
}

/// The WeedMap crop as a Field.
Field weedmap_field() {
  static const t::TempDir dir;
  static const Field f = Field::load(make_field(dir.path() / "f", weedmap_yaml()));
  return f;
}

MissionOptions fixed_times() {
  MissionOptions o;
  o.fixed_segmentation_time_s = 0.1;
  o.fixed_planning_time_s = 0.01;
  return o;
}

/// A decision model for the WeedMap classes, fitted to region samples of the crop.
DecisionModel small_model() {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  const auto samples = collect_region_samples(f, oracle, CameraModel({.image_width_px = 48, .image_height_px = 36}),
                                              3.0, {1.0, 2.0}, f.interest());
  REQUIRE(samples.size() >= 4);
  DecisionModel m{.calibration_fields = {f.name()},
                  .segmenter = "oracle",
                  .calibration_segmentation_time_s = 0.1,
                  .classes = {"soil", "crop", "weed"},
                  .interest = {"crop", "weed"},
                  .camera = {.image_width_px = 48, .image_height_px = 36},
                  .timing = {},
                  .top_gsd_cm = 3.0,
                  .candidate_gsd_cm = {1.0, 2.0},
                  .decision_function = DecisionFunction(UtilityPolicy(GainModel::fit(samples, {.restarts = 0}), {})),
                  .linear = {0.1, 0.5},
                  .samples = samples.size(),
                  .train_front_margin = 0.0};
  return m;
}

/// The saved small model as text.
const std::string& model_text() {
  static const std::string text = [] {
    const t::TempDir dir;
    small_model().save(dir.path() / "model.yaml");
    return read_text(dir.path() / "model.yaml");
  }();
  return text;
}

/// Writes `text` as a model file and loads it.
DecisionModel load_model_text(const t::TempDir& dir, const std::string& text) {
  const fs::path p = dir.path() / "model.yaml";
  t::write_file(p, text);
  return DecisionModel::load(p);
}

/// A fitted 1-D GP as a GP file (YAML; what the reader must survive).
std::string gp_text() {
  Eigen::MatrixXd x(5, 1);
  x << 0.0, 0.5, 1.0, 1.5, 2.0;
  const Eigen::VectorXd y = x.col(0).array().sin();
  GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(1.0, 1.0, 0.01));
  gp.condition(x, y);
  std::ostringstream os;
  save_gaussian_process(gp, os);
  return os.str();
}

GaussianProcess<SquaredExponentialKernel> load_gp(const std::string& text) {
  std::istringstream is(text);
  return load_gaussian_process<SquaredExponentialKernel>(is);
}

fs::path erfnet_dir() { return fs::path(ADAPTSEG_EXAMPLES_DIR) / "models" / "erfnet-dubai"; }

/// A backend that breaks the SegmentationBackend contract: a 1 x 1 label map.
/// A backend that breaks the segmentation contract (segmentation_backend.hpp) one way.
struct ContractBreaker {
  enum class Fault { size, type, label };
  Fault fault = Fault::label;
  [[nodiscard]] std::string name() const { return "breaker"; }
  [[nodiscard]] cv::Mat segment(const Image& image) const {
    switch (fault) {
      case Fault::size: return cv::Mat(1, 1, CV_8UC1, cv::Scalar(0));
      case Fault::type: return cv::Mat(image.height_px, image.width_px, CV_16UC1, cv::Scalar(0));
      case Fault::label: break;
    }
    cv::Mat labels(image.height_px, image.width_px, CV_8UC1, cv::Scalar(0));
    labels.at<unsigned char>(5, 7) = 7;  // row 5, column 7: not a class of a 3-class field
    return labels;
  }
};
static_assert(SegmentationBackend<ContractBreaker>);

/// A live planner's options over `f`: top level 3 cm/px, one candidate, fixed times.
AdaptiveOptions live_options(const Field& f) {
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.mission.interest = f.interest();
  o.top_gsd_cm = 3.0;
  o.candidate_gsd_cm = {1.0};
  return o;
}

}  // namespace

// ---- camera and timing -----------------------------------------------------------------------

TEST_CASE("robustness: camera: zero image width") {
  CHECK_THROWS_WITH_AS(CameraModel({.image_width_px = 0}), Contains("image_width_px must be > 0"),
                       std::invalid_argument);
}

TEST_CASE("robustness: camera: negative image height") {
  CHECK_THROWS_WITH_AS(CameraModel({.image_height_px = -360}), Contains("image_height_px must be > 0"),
                       std::invalid_argument);
}

TEST_CASE("robustness: camera: NaN sensor width and infinite focal length") {
  CHECK_THROWS_WITH_AS(CameraModel({.sensor_width_mm = kNaN}), Contains("sensor_width_mm must be finite and > 0"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(CameraModel({.focal_length_mm = kInf}), Contains("focal_length_mm must be finite and > 0"),
                       std::invalid_argument);
}

TEST_CASE("robustness: camera: image too large to simulate") {
  CHECK_THROWS_WITH_AS(CameraModel({.image_width_px = 200000, .image_height_px = 150000}), Contains("too many pixels"),
                       std::invalid_argument);
}

TEST_CASE("robustness: timing: zero speed and negative acceleration") {
  CHECK_THROWS_WITH_AS(TimingModel({.max_speed_mps = 0.0}), Contains("max_speed_mps must be finite and > 0"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(TimingModel({.max_accel_mps2 = -2.0}), Contains("max_accel_mps2 must be finite and > 0"),
                       std::invalid_argument);
}

// ---- field files ---------------------------------------------------------------------------

TEST_CASE("robustness: field: directory missing") {
  const t::TempDir dir;
  CHECK_THROWS_WITH_AS(Field::load(dir.path() / "none"), Contains("field directory not found"), std::invalid_argument);
}

TEST_CASE("robustness: field: field.yaml missing") {
  const t::TempDir dir;
  CHECK_THROWS_WITH_AS(Field::load(dir.path()), Contains("missing"), std::invalid_argument);
}

TEST_CASE("robustness: field: YAML syntax error") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "interest: [crop, weed]", "interest: [crop, weed"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("YAML error"), std::invalid_argument);
}

TEST_CASE("robustness: field: document is a list not a mapping") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), "- name\n- gsd_cm\n");
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("the document must be a mapping"), std::invalid_argument);
}

TEST_CASE("robustness: field: empty field.yaml") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), "");
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("the document must be a mapping"), std::invalid_argument);
}

TEST_CASE("robustness: field: required key missing") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "gsd_cm: 1.0\n", ""));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("missing key 'gsd_cm'"), std::invalid_argument);
}

TEST_CASE("robustness: field: misspelt key") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "ignore_label:", "ignore_lable:"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("unknown key 'ignore_lable'"), std::invalid_argument);
}

TEST_CASE("robustness: field: gsd_cm of the wrong type") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "gsd_cm: 1.0", "gsd_cm: one"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'gsd_cm' must be a finite number (got 'one')"), std::invalid_argument);
}

TEST_CASE("robustness: field: gsd_cm zero negative or NaN") {
  for (const char* bad : {"0", "-1.0"}) {
    CAPTURE(bad);
    const t::TempDir dir;
    const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "gsd_cm: 1.0", std::string("gsd_cm: ") + bad));
    const std::string message = "'gsd_cm' must be > 0 (got " + std::string(bad) + ")";
    CHECK_THROWS_WITH_AS(Field::load(f), Contains(message.c_str()), std::invalid_argument);
  }
  for (const char* bad : {".nan", ".inf"}) {
    CAPTURE(bad);
    const t::TempDir dir;
    const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "gsd_cm: 1.0", std::string("gsd_cm: ") + bad));
    CHECK_THROWS_WITH_AS(Field::load(f), Contains("'gsd_cm' must be a finite number"), std::invalid_argument);
  }
}

TEST_CASE("robustness: field: a mapping where a scalar belongs") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "labels: labels.png", "labels: {file: labels.png}"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'labels' must be a scalar"), std::invalid_argument);
}

TEST_CASE("robustness: field: empty class list") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), "name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: []\n");
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'classes' must be a non-empty list"), std::invalid_argument);
}

TEST_CASE("robustness: field: class colour out of range") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "[0, 255, 0]", "[0, 256, 0]"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'classes[1].color[1]' must be an integer in [0, 255] (got '256')"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: class colour with two components") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "[0, 255, 0]", "[0, 255]"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'classes[1].color' must be a list of 3 integers"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: duplicate class name") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "{name: weed,", "{name: crop,"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'classes[2].name': class name 'crop' listed twice"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: ignore_label is a class index") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "ignore_label: 255", "ignore_label: 1"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("ignore_label must not be a class index"), std::invalid_argument);
}

TEST_CASE("robustness: field: ignore_label out of 0..255") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "ignore_label: 255", "ignore_label: 300"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'ignore_label' must be an integer in [0, 255] (got '300')"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: label PNG missing") {
  const t::TempDir dir;
  make_field(dir.path(), weedmap_yaml());
  fs::remove(dir.path() / "labels.png");
  CHECK_THROWS_WITH_AS(Field::load(dir.path()), Contains("file not found"), std::invalid_argument);
}

TEST_CASE("robustness: field: label file is not an image") {
  const t::TempDir dir;
  make_field(dir.path(), weedmap_yaml());
  t::write_file(dir.path() / "labels.png", "\x89PNG\r\n\x1a\n truncated");
  CHECK_THROWS_WITH_AS(Field::load(dir.path()), Contains("cannot decode image"), std::invalid_argument);
}

TEST_CASE("robustness: field: label PNG with three channels") {
  const t::TempDir dir;
  cv::Mat bgr;
  cv::merge(std::vector<cv::Mat>(3, weedmap_crop()), bgr);
  const auto f = make_field(dir.path(), weedmap_yaml(), bgr);
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("must be an 8-bit single-channel PNG (got 3 channels"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: label PNG with 16-bit depth") {
  const t::TempDir dir;
  cv::Mat wide;
  weedmap_crop().convertTo(wide, CV_16U);
  const auto f = make_field(dir.path(), weedmap_yaml(), wide);
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("must be an 8-bit single-channel PNG (got 1 channels, depth 2)"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: label value out of range") {
  const t::TempDir dir;
  cv::Mat labels = weedmap_crop().clone();
  labels.at<std::uint8_t>(7, 11) = 3;  // three classes: 0..2, ignore 255
  const auto f = make_field(dir.path(), weedmap_yaml(), labels);
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("label value 3 at row 7, col 11 is neither a class index"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: image and label map differ in size") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), weedmap_yaml() + "image: image.png\n");
  cv::imwrite((dir.path() / "image.png").string(), cv::Mat(90, 120, CV_8UC3, cv::Scalar(0, 80, 0)));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("image and label map differ in size (got 120x90 vs 240x180)"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: unknown label of interest in field.yaml") {
  const t::TempDir dir;
  const auto f = make_field(dir.path(), replaced(weedmap_yaml(), "[crop, weed]", "[crop, tree]"));
  CHECK_THROWS_WITH_AS(Field::load(f), Contains("'interest' names unknown class 'tree'"), std::invalid_argument);
}

TEST_CASE("robustness: field: unknown label of interest asked by name") {
  CHECK_THROWS_WITH_AS((void)weedmap_field().class_indices({"crop", "tree"}),
                       Contains("unknown class 'tree' in field 'weedmap-rededge-000' (classes: soil, crop, weed)"),
                       std::invalid_argument);
}

TEST_CASE("robustness: field: region outside 0..1 or empty") {
  const Field f = weedmap_field();
  CHECK_THROWS_WITH_AS((void)f.sub_field({0.5, 0.0, 0.4, 1.0}), Contains("region must satisfy"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)f.sub_field({0.0, 0.0, 1.0, kNaN}), Contains("region must satisfy"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)f.sub_field({0.0, 0.0, 1e-4, 1.0}), Contains("region holds no pixel"),
                       std::invalid_argument);
}

// ---- missions: labels of interest, altitudes, budgets, backends ------------------------------

TEST_CASE("robustness: mission: empty labels of interest") {
  const t::TempDir dir;
  const auto d = make_field(dir.path(), replaced(weedmap_yaml(), "interest: [crop, weed]", "interest: []"));
  const Field f = Field::load(d);
  CHECK(f.interest().empty());
  OracleSegmenter oracle(f.num_classes());
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, oracle, fixed_times()),
                       Contains("Mission: no labels of interest"), std::invalid_argument);
}

TEST_CASE("robustness: mission: label of interest out of range") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  MissionOptions o = fixed_times();
  o.interest = {1, 7};
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, oracle, o),
                       Contains("Mission: label of interest out of range (got 7)"), std::invalid_argument);
}

TEST_CASE("robustness: mission: GSD finer than the field or NaN") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  for (double g : {0.5, 0.0, -3.0, kNaN}) {
    CAPTURE(g);
    CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, g, oracle, fixed_times()),
                         Contains("gsd_cm must be finite and not finer than the field's"), std::invalid_argument);
  }
}

TEST_CASE("robustness: mission: altitude too high to simulate") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  for (double g : {1e5, 1e12, kInf}) {
    CAPTURE(g);
    CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, g, oracle, fixed_times()), Contains("gsd_cm"),
                         std::invalid_argument);
  }
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.top_gsd_cm = 1e7;
  o.candidate_gsd_cm = {1.0};
  LinearDecision policy({0.0, 1.0});
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, policy, o, "linear"),
                       Contains("footprint is too large to simulate"), std::invalid_argument);
}

TEST_CASE("robustness: mission: negative fixed segmentation time") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  MissionOptions o = fixed_times();
  o.fixed_segmentation_time_s = -1.0;
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, oracle, o),
                       Contains("fixed_segmentation_time_s must be finite and >= 0"), std::invalid_argument);
  o.fixed_segmentation_time_s = 0.1;
  o.fixed_planning_time_s = kNaN;
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, oracle, o),
                       Contains("fixed_planning_time_s must be finite and >= 0"), std::invalid_argument);
}

TEST_CASE("robustness: mission: backend returns labels of the wrong size") {
  const Field f = weedmap_field();
  ContractBreaker backend{ContractBreaker::Fault::size};
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, backend, fixed_times()),
                       Contains("segmentation backend 'breaker' broke the segmentation contract: labels must have "
                                "the image's size 480x360 (got 1x1)"),
                       std::invalid_argument);
}

TEST_CASE("robustness: mission: backend returns labels of the wrong type") {
  const Field f = weedmap_field();
  ContractBreaker backend{ContractBreaker::Fault::type};
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, backend, fixed_times()),
                       Contains("segmentation backend 'breaker' broke the segmentation contract: labels must be "
                                "CV_8UC1 (8-bit, one channel) (got type CV_16UC1)"),
                       std::invalid_argument);
}

TEST_CASE("robustness: mission: backend returns a label outside the class set") {
  const Field f = weedmap_field();
  REQUIRE(f.num_classes() == 3);
  ContractBreaker backend{ContractBreaker::Fault::label};
  CHECK_THROWS_WITH_AS((void)run_lawnmower_mission(f, 3.0, backend, fixed_times()),
                       Contains("segmentation backend 'breaker' broke the segmentation contract: label 7 at pixel "
                                "(x 7, y 5) is neither a class index 0..2 nor the ignore label 255"),
                       std::invalid_argument);
}

TEST_CASE("robustness: calibration: backend returns a label outside the class set") {
  const Field f = weedmap_field();
  ContractBreaker backend{ContractBreaker::Fault::label};
  CHECK_THROWS_WITH_AS((void)collect_region_samples(f, backend, CameraModel{}, 3.0, {1.0}, f.interest()),
                       Contains("segmentation backend 'breaker' broke the segmentation contract: label 7"),
                       std::invalid_argument);
}

namespace {
/// The oracle's segmentation with its probabilities broken as `fault` says.
struct ProbabilityBreaker {
  enum class Fault { planes, nan, sum, votes };
  Fault fault;
  OracleSegmenter oracle{3};
  std::string name() const { return "breaker"; }
  cv::Mat segment(const Image& image) { return oracle.segment(image); }
  Segmentation segment_with_probabilities(const Image& image) {
    Segmentation s = oracle.segment_with_probabilities(image);
    if (fault == Fault::planes) s.probabilities.pop_back();
    if (fault == Fault::nan) s.probabilities[0].at<float>(5, 7) = static_cast<float>(kNaN);
    // Member votes (as an ensemble gives them) of one plane too few.
    if (fault == Fault::votes) s.member_votes = {s.probabilities[0].clone(), s.probabilities[1].clone()};
    // The first labelled pixel's probabilities sum to 1.5.
    const cv::Mat labelled = s.labels != image.ignore_label;
    std::vector<cv::Point> at;
    cv::findNonZero(labelled, at);
    if (fault == Fault::sum && !at.empty()) {  // the least likely class, so that no value leaves [0, 1]
      std::size_t least = 0;
      for (std::size_t c = 1; c < s.probabilities.size(); ++c)
        if (s.probabilities[c].at<float>(at.front()) < s.probabilities[least].at<float>(at.front())) least = c;
      s.probabilities[least].at<float>(at.front()) += 0.5f;
    }
    return s;
  }
};
}  // namespace

TEST_CASE("robustness: ranked missions: class probabilities that break the contract, from the backend or the caller") {
  const Field f = weedmap_field();
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.top_gsd_cm = 3.0;
  o.candidate_gsd_cm = {1.0};
  o.coverage = DescentCoverage::ranked;
  o.mission.interest = f.interest();
  LinearDecision never({0.0, 1.0});
  ProbabilityBreaker fewer{ProbabilityBreaker::Fault::planes}, nan{ProbabilityBreaker::Fault::nan},
      sum{ProbabilityBreaker::Fault::sum};
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, fewer, never, o, "ranked"),
                       Contains("segmentation backend 'breaker' broke the segmentation contract: probabilities must "
                                "have one plane per class (3) (got 2)"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, nan, never, o, "ranked"),
                       Contains("probability nan of class 0 at pixel (x 7, y 5) is not in [0, 1]"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, sum, never, o, "ranked"),
                       Contains("sum to 1.5, not 1 (tolerance 0.001)"), std::invalid_argument);
  ProbabilityBreaker votes{ProbabilityBreaker::Fault::votes};
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, votes, never, o, "ranked"),
                       Contains("segmentation backend 'breaker' (member votes) broke the segmentation contract: "
                                "probabilities must have one plane per class (3) (got 2)"),
                       std::invalid_argument);
  // Calibration collects the same images: the same errors.
  CHECK_THROWS_WITH_AS((void)collect_samples(f, sum, CameraModel{}, 3.0, {1.0}, f.interest(), DescentCoverage::ranked),
                       Contains("sum to 1.5"), std::invalid_argument);
  // The caller's probabilities in report(image, segmentation, s): checked, nothing changes.
  AdaptivePlanner planner(SurveyArea::of(f), never, o);
  const auto w = planner.next();
  REQUIRE(w.has_value());
  const Image image = SimulatedSensor(f, planner.camera()).capture(w->waypoint);
  CHECK_THROWS_WITH_AS((void)planner.report(image, sum.segment_with_probabilities(image), 0.1),
                       Contains("AdaptivePlanner::report: the probabilities reported broke the segmentation contract"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)planner.report(image, votes.segment_with_probabilities(image), 0.1),
                       Contains("AdaptivePlanner::report: the member votes reported broke the segmentation contract"),
                       std::invalid_argument);
  CHECK(planner.pending().has_value());
}

TEST_CASE("robustness: decision model: a broken cell gain model") {
  const t::TempDir dir;
  DecisionModel m = small_model();
  m.coverage = DescentCoverage::ranked;
  GainModel g = m.decision_function.model();
  g.set_cells(CellGainModel(DecisionInput::expected_error, {{3.0, 1.0, 0.9, 0.01, 1.0, 0.01, 0.8, 0.02},
                                                            {3.0, 2.0, 0.3, 0.01, 0.9, 0.01, 0.2, 0.02}}));
  m.decision_function = DecisionFunction(UtilityPolicy(g, {}));
  m.save(dir.path() / "ranked.yaml");
  const std::string text = read_text(dir.path() / "ranked.yaml");
  REQUIRE(text.find("    input: expected_error") != std::string::npos);
  CHECK(DecisionModel::load(dir.path() / "ranked.yaml").decision_function.model().cells().has_value());
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(text, "input: expected_error", "input: confusion")),
                       Contains("decision input must be 'sigma', 'boundary'"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(text, "gain_slope: [0.9, 0.3]", "gain_slope: [0.9]")),
                       Contains("'gain_model.cells' needs one top_gsd_cm, sub_gsd_cm, gain_slope"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(text, "gain_noise: [0.01, 0.01]", "gain_noise: [0.01, -1]")),
                       Contains("noises finite and >= 0"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(text, "sub_gsd_cm: [1, 2]", "sub_gsd_cm: [1, 4]")),
                       Contains("the descent's finer than the top's"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(text, "sub_gsd_cm: [1, 2]", "sub_gsd_cm: [2, 1]")),
                       Contains("increasing (top, descent) GSD order"), std::invalid_argument);
}

TEST_CASE("robustness: live planner: labels outside the class set, from the backend or the caller") {
  const Field f = weedmap_field();
  ContractBreaker backend{ContractBreaker::Fault::label};
  LinearDecision never({0.0, 1.0});
  AdaptivePlanner planner(SurveyArea::of(f), never, live_options(f));
  const auto w = planner.next();
  REQUIRE(w.has_value());
  const Image image = SimulatedSensor(f, planner.camera()).capture(w->waypoint);
  CHECK_THROWS_WITH_AS((void)segment_and_report(planner, backend, image),
                       Contains("segmentation backend 'breaker' broke the segmentation contract: label 7 at pixel "
                                "(x 7, y 5)"),
                       std::invalid_argument);
  cv::Mat labels(image.height_px, image.width_px, CV_8UC1, cv::Scalar(1));
  labels.at<unsigned char>(359, 479) = 3;
  CHECK_THROWS_WITH_AS((void)planner.report(image, labels, 0.1),
                       Contains("AdaptivePlanner::report: the labels reported broke the segmentation contract: "
                                "label 3 at pixel (x 479, y 359)"),
                       std::invalid_argument);
  labels.at<unsigned char>(359, 479) = 255;  // the ignore label is allowed
  CHECK(planner.report(image, labels, 0.1).waypoint.index == 0);
}

TEST_CASE("robustness: live planner: survey area without its class count") {
  const Field f = weedmap_field();
  LinearDecision never({0.0, 1.0});
  const AdaptiveOptions o = live_options(f);
  SurveyArea area = SurveyArea::of(f);
  area.num_classes = 0;
  CHECK_THROWS_WITH_AS(AdaptivePlanner(area, never, o),
                       Contains("SurveyArea: num_classes must be the size of the backend's class set, 1..255"),
                       std::invalid_argument);
  area.num_classes = 1;  // interest is class 1 or 2 of the WeedMap crop: not a class any more
  CHECK_THROWS_WITH_AS(AdaptivePlanner(area, never, o), Contains("a label of interest is not a class index 0..0"),
                       std::invalid_argument);
}

TEST_CASE("robustness: adaptive: top GSD finer than the field") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.top_gsd_cm = 0.5;
  LinearDecision policy({0.0, 1.0});
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, policy, o, "linear"),
                       Contains("top_gsd_cm must not be finer than the map's"), std::invalid_argument);
}

TEST_CASE("robustness: adaptive: candidate GSD not finer than the top") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.candidate_gsd_cm = {1.0, 3.0};
  LinearDecision policy({0.0, 1.0});
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, policy, o, "linear"),
                       Contains("candidate GSDs must be positive and finer than top_gsd_cm (got 3)"),
                       std::invalid_argument);
}

TEST_CASE("robustness: adaptive: budget too small for coverage") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.candidate_gsd_cm = {1.0};
  o.budget_s = 0.05;
  LinearDecision policy({0.0, 1.0});
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, policy, o, "linear"),
                       Contains("too small for the top-level coverage"), std::invalid_argument);
}

TEST_CASE("robustness: adaptive: budget negative or NaN") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.candidate_gsd_cm = {1.0};
  LinearDecision policy({0.0, 1.0});
  for (double b : {-10.0, 0.0, kNaN}) {
    CAPTURE(b);
    o.budget_s = b;
    CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, policy, o, "linear"),
                         Contains("budget_s must be finite and > 0"), std::invalid_argument);
  }
}

TEST_CASE("robustness: adaptive: no candidate GSD to descend to") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o;
  o.mission = fixed_times();
  LinearDecision policy({0.0, 1.0});
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, policy, o, "linear"),
                       Contains("AdaptivePlanner: no candidate GSD to descend to"), std::invalid_argument);
}

TEST_CASE("robustness: linear decision: sigma range reversed") {
  CHECK_THROWS_WITH_AS(LinearDecision({0.6, 0.4}), Contains("sigma_high must be in (sigma_low, 1]"),
                       std::invalid_argument);
}

// ---- Gaussian processes and the decision function --------------------------------------------

TEST_CASE("robustness: GP: training data with NaN") {
  Eigen::MatrixXd x(3, 1);
  x << 0.0, kNaN, 1.0;
  GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(1.0, 1.0, 0.01));
  CHECK_THROWS_WITH_AS(gp.condition(x, Eigen::Vector3d(0.0, 1.0, 2.0)), Contains("x must be finite"),
                       std::invalid_argument);
  x(1, 0) = 0.5;
  CHECK_THROWS_WITH_AS(gp.condition(x, Eigen::Vector3d(0.0, kNaN, 2.0)), Contains("y must be finite"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(gp.add_observation(Eigen::VectorXd::Constant(1, kInf), 0.0),
                       Contains("add_observation: x must be finite"), std::invalid_argument);
}

TEST_CASE("robustness: GP: duplicate inputs are accepted") {
  // Repeated inputs with differing outputs are what noisy data look like: no error, a finite
  // posterior (the noise variance keeps K + s2 I positive definite; jitter otherwise).
  Eigen::MatrixXd x(6, 1);
  x << 1.0, 1.0, 1.0, 2.0, 2.0, 2.0;
  Eigen::VectorXd y(6);
  y << 0.1, 0.2, 0.3, 0.5, 0.5, 0.5;
  GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(1.0, 1.0, 1e-8));
  REQUIRE_NOTHROW((void)gp.fit(x, y, {.restarts = 1}));
  const auto p = gp.predict(Eigen::MatrixXd::Constant(1, 1, 1.0));
  CHECK(std::isfinite(p.mean(0)));
  CHECK(p.variance(0) >= 0.0);
}

TEST_CASE("robustness: GP file: NaN value") {
  const std::string text = replaced(gp_text(), "y_mean: 0", "y_mean: nan");
  CHECK_THROWS_WITH_AS(load_gp(text), Contains("'y_mean' must be a finite number"), std::invalid_argument);
}

TEST_CASE("robustness: GP file: truncated") {
  const std::string text = gp_text();
  // Cut after the inputs: the targets are missing.
  CHECK_THROWS_WITH_AS(load_gp(text.substr(0, text.find("targets:"))), Contains("missing key 'targets'"),
                       std::invalid_argument);
  // Cut inside the targets' list: YAML itself fails, named as such.
  CHECK_THROWS_WITH_AS(load_gp(text.substr(0, text.find("targets:") + 14)), Contains("YAML error"),
                       std::invalid_argument);
}

TEST_CASE("robustness: GP file: another kernel") {
  std::istringstream is(gp_text());
  CHECK_THROWS_WITH_AS((void)load_gaussian_process<ArdSquaredExponentialKernel>(is),
                       Contains("'kernel' must be squared_exponential_ard"), std::invalid_argument);
}

TEST_CASE("robustness: GP file: huge or false announced dimension") {
  // The rows are the data: a `dimension` key that disagrees with them is refused, whatever its
  // size (nothing is allocated from it), and beyond 1e6 it is out of range.
  CHECK_THROWS_WITH_AS(load_gp(replaced(gp_text(), "dimension: 1", "dimension: 1000000")),
                       Contains("'dimension' is 1000000 but the rows of 'inputs' have 1 values"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(load_gp(replaced(gp_text(), "dimension: 1", "dimension: 100000000")), Contains("dimension"),
                       std::invalid_argument);
  // An ARD kernel has as many length scales as inputs: an empty model of another dimension is
  // refused up front.
  std::ostringstream os;
  save_gaussian_process(
      GaussianProcess<ArdSquaredExponentialKernel>(ArdSquaredExponentialKernel(Eigen::VectorXd::Ones(2))), os);
  std::istringstream is(replaced(os.str(), "dimension: 0", "dimension: 1000000"));
  CHECK_THROWS_WITH_AS((void)load_gaussian_process<ArdSquaredExponentialKernel>(is),
                       Contains("does not accept inputs of dimension 1000000"), std::invalid_argument);
}

TEST_CASE("robustness: decision function: no samples or a NaN sample") {
  CHECK_THROWS_WITH_AS((void)GainModel::fit({}), Contains("number of samples must be > 0"), std::invalid_argument);
  std::vector<RegionSample> samples(4);
  for (std::size_t k = 0; k < samples.size(); ++k) {
    samples[k] = {3.0, 1.0, 10.0, 0.1 * static_cast<double>(k), 0.05, 0.5, 0.6};
  }
  samples[2].sigma_top = kNaN;
  CHECK_THROWS_WITH_AS((void)GainModel::fit(samples, {.restarts = 0}), Contains("must be finite"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision function: threshold out of range") {
  CHECK_THROWS_WITH_AS(UtilityPolicy::Params{.min_sigma = 1.5}.validate(), Contains("min_sigma must be in [0, 1]"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(UtilityPolicy::Params{.exploration = -1.0}.validate(),
                       Contains("exploration must be finite and >= 0"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(FrontAwarePolicy::Params{.confidence = kNaN}.validate(),
                       Contains("confidence must be finite and >= 0"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(FrontAwarePolicy::Params{.scale_prior_sd = 0.0}.validate(),
                       Contains("scale_prior_sd must be finite and > 0"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(FrontAwarePolicy::Params{.sigma_prior_sd = -0.1}.validate(),
                       Contains("sigma_prior_sd must be in [0, 1]"), std::invalid_argument);
}

TEST_CASE("robustness: decision function: a policy that descends to a GSD it was not offered") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  struct Rogue {  // descends to 1.7 cm/px, which is no candidate
    std::string name() const { return "rogue"; }
    void begin_mission() {}
    Decision decide(const DecisionContext&) { return {.descend = true, .gsd_cm = 1.7, .scores = {}}; }
    void observe(const DescentOutcome&) {}
  } rogue;
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.mission.camera = {.image_width_px = 48, .image_height_px = 36};
  o.top_gsd_cm = 3.0;
  o.candidate_gsd_cm = {1.0, 2.0};
  CHECK_THROWS_WITH_AS((void)run_adaptive_mission(f, oracle, rogue, o, "rogue"),
                       Contains("decision policy 'rogue' descends to 1.7"), std::logic_error);
}

// ---- decision model files --------------------------------------------------------------------

TEST_CASE("robustness: decision model: file missing") {
  const t::TempDir dir;
  CHECK_THROWS_WITH_AS((void)DecisionModel::load(dir.path() / "none.yaml"), Contains("decision model file not found"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision model: truncated file") {
  const t::TempDir dir;
  const std::string& text = model_text();
  // Cut inside the rule (the last key).
  const std::string cut = text.substr(0, text.find("  relative_utility:"));
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, cut), Contains("missing key 'rule.relative_utility'"),
                       std::invalid_argument);
  // Cut before the gain model: a key is missing.
  const std::string head = text.substr(0, text.find("gain_model:"));
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, head), Contains("missing key 'gain_model'"), std::invalid_argument);
}

TEST_CASE("robustness: decision model: a number that is none, or a GP whose data do not fit") {
  const t::TempDir dir;
  const std::string& text = model_text();
  const auto y_mean = text.find("    y_mean: ");
  REQUIRE(y_mean != std::string::npos);
  const auto eol = text.find('\n', y_mean);
  std::string bad = text;
  bad.replace(y_mean, eol - y_mean, "    y_mean: 0,25");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, bad),
                       Contains("'gain_model.O.y_mean' must be a finite number (got '0,25')"), std::invalid_argument);
  const auto targets = text.find("    targets: [");
  REQUIRE(targets != std::string::npos);
  bad = text;
  bad.insert(targets + std::string("    targets: [").size(), "0.5, ");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, bad), Contains("as many input rows as 'targets' has values"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision model: a field.yaml given as model") {
  const t::TempDir dir;
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, weedmap_yaml()), Contains("not an adaptseg decision model"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision model: from another class set") {
  const t::TempDir dir;
  const DecisionModel m = load_model_text(dir, model_text());
  const Field dubai = Field::load(t::example_field("dubai-tile-1"));
  CHECK_THROWS_WITH_AS(
      m.check_compatible(dubai, dubai.interest()),
      Contains("decision model was calibrated for classes [soil, crop, weed] but field 'dubai-tile-1'"),
      std::invalid_argument);
}

TEST_CASE("robustness: decision model: other labels of interest") {
  const t::TempDir dir;
  const DecisionModel m = load_model_text(dir, model_text());
  CHECK_THROWS_WITH_AS(m.check_compatible(weedmap_field(), {2}),
                       Contains("calibrated for labels of interest [crop, weed] but the mission uses [weed]"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision model: label of interest not among its classes") {
  const t::TempDir dir;
  const std::string text = replaced(model_text(), "interest: [crop, weed]", "interest: [crop, tree]");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, text), Contains("label of interest 'tree' is not among the classes"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision model: candidate GSD not finer than top") {
  const t::TempDir dir;
  const std::string text = replaced(model_text(), "candidate_gsd_cm: [1, 2]", "candidate_gsd_cm: [1, 4]");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, text),
                       Contains("candidate GSDs must be positive and finer than top_gsd_cm"), std::invalid_argument);
}

TEST_CASE("robustness: decision model: invalid camera") {
  const t::TempDir dir;
  const std::string text = replaced(model_text(), "image_width_px: 48", "image_width_px: 0");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, text),
                       Contains("'camera.image_width_px' must be an integer in [1, 1000000]"), std::invalid_argument);
}

TEST_CASE("robustness: decision model: mistyped value") {
  const t::TempDir dir;
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(model_text(), "top_gsd_cm: 3", "top_gsd_cm: high")),
                       Contains("'top_gsd_cm' must be a finite number (got 'high')"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, replaced(model_text(), "samples: ", "samples: -")),
                       Contains("'calibration.samples' must be an integer"), std::invalid_argument);
}

TEST_CASE("robustness: decision model: refit count out of range") {
  const t::TempDir dir;
  const std::string text = replaced(model_text(), "refit_every: 0", "refit_every: 1e300");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, text), Contains("'gain_model.refit_every' must be an integer"),
                       std::invalid_argument);
}

TEST_CASE("robustness: decision model: unknown descent coverage, grid or gain extent") {
  const t::TempDir dir;
  const std::string text = replaced(model_text(), "descent_coverage: region", "descent_coverage: everywhere");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, text), Contains("'region', 'interest' or 'ranked'"),
                       std::invalid_argument);
  // An optional setup key (`key`): an unknown name (`bad`) is refused with `refusal`; a known one
  // (`good`, `value`) is read, handed to the missions' options and written back; a file without
  // the key reads the paper's `region`.
  const auto check_key = [&](const std::string& key, const std::string& bad, const std::string& refusal,
                             const std::string& good, auto member, auto option, auto value) {
    CAPTURE(key);
    const auto with = [&](const std::string& v) {
      return replaced(model_text(), "descent_coverage: region", "descent_coverage: region\n" + key + ": " + v);
    };
    CHECK_THROWS_WITH_AS((void)load_model_text(dir, with(bad)), Contains(refusal.c_str()), std::invalid_argument);
    const DecisionModel m = load_model_text(dir, with(good));
    CHECK(m.*member == value);
    CHECK(m.adaptive_options({}).*option == value);
    m.save(dir.path() / "again.yaml");
    CHECK(DecisionModel::load(dir.path() / "again.yaml").*member == value);
    CHECK(load_model_text(dir, model_text()).*member == decltype(value)::region);
  };
  check_key("descent_grid", "shared", "descent grid must be 'region' or 'field', not 'shared'", "field",
            &DecisionModel::descent_grid, &AdaptiveOptions::descent_grid, DescentGrid::field);
  // The gain extent tells the missions over which pixels each ranked cell is forecast.
  check_key("gain_extent", "footprint", "gain extent must be 'region' or 'images', not 'footprint'", "images",
            &DecisionModel::gain_extent, &AdaptiveOptions::gain_extent, GainExtent::images);
}

TEST_CASE("robustness: decision model: I with three inputs") {
  const t::TempDir dir;
  // I's inputs get a third column: I takes (Δσ, Δh).
  std::string text = model_text();
  const auto i_block = text.find("\n  I:\n");
  REQUIRE(i_block != std::string::npos);
  const auto row = text.find("]", text.find("    inputs:", i_block));
  REQUIRE(row != std::string::npos);
  text.insert(row, ", 3");
  CHECK_THROWS_WITH_AS((void)load_model_text(dir, text), Contains("'gain_model.I.inputs' rows must have 2 values"),
                       std::invalid_argument);
}

// ---- ERFNet model files ----------------------------------------------------------------------

TEST_CASE("robustness: erfnet: ONNX file missing") {
  CHECK_THROWS_WITH_AS(OnnxSegmenter(erfnet_dir() / "none.onnx", erfnet_dir() / "model.yaml"),
                       Contains("ONNX file not found"), std::invalid_argument);
}

TEST_CASE("robustness: erfnet: ONNX file corrupt") {
  const t::TempDir dir;
  std::string bytes = read_text(erfnet_dir() / "model.onnx");
  for (std::size_t k = 0; k < bytes.size(); k += 97) bytes[k] = static_cast<char>(bytes[k] ^ 0x5a);
  t::write_file(dir.path() / "model.onnx", bytes);
  CHECK_THROWS_WITH_AS(OnnxSegmenter(dir.path() / "model.onnx", erfnet_dir() / "model.yaml"),
                       Contains("cannot load ONNX model"), std::invalid_argument);
}

TEST_CASE("robustness: erfnet: ONNX file truncated") {
  const t::TempDir dir;
  const std::string bytes = read_text(erfnet_dir() / "model.onnx");
  t::write_file(dir.path() / "model.onnx", bytes.substr(0, bytes.size() / 3));
  CHECK_THROWS_WITH_AS(OnnxSegmenter(dir.path() / "model.onnx", erfnet_dir() / "model.yaml"),
                       Contains("cannot load ONNX model"), std::invalid_argument);
}

TEST_CASE("robustness: erfnet: ONNX file empty") {
  const t::TempDir dir;
  t::write_file(dir.path() / "model.onnx", "");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(dir.path() / "model.onnx", erfnet_dir() / "model.yaml"), Contains("ONNX model"),
                       std::invalid_argument);
}

TEST_CASE("robustness: erfnet: model for another class set") {
  CHECK_THROWS_WITH_AS(OnnxSegmenter(erfnet_dir(), weedmap_field(), CameraModel{}),
                       Contains("differ from the 3 expected classes [soil, crop, weed]"), std::invalid_argument);
}

TEST_CASE("robustness: erfnet: metadata input size not a multiple of 8") {
  const t::TempDir dir;
  t::write_file(dir.path() / "model.yaml",
                replaced(read_text(erfnet_dir() / "model.yaml"), "width: 480", "width: 481"));
  CHECK_THROWS_WITH_AS(OnnxSegmenter(erfnet_dir() / "model.onnx", dir.path() / "model.yaml"),
                       Contains("positive multiples of 8 (got 481x360)"), std::invalid_argument);
}

TEST_CASE("robustness: erfnet: field without RGB") {
  const Field f = weedmap_field();
  OnnxSegmenter erfnet(erfnet_dir());
  const Image img = SimulatedSensor(f, CameraModel{}).capture(LawnmowerPlanner(CameraModel{}).plan(f.area(), 3.0)[0]);
  CHECK_THROWS_WITH_AS((void)erfnet.segment(img), Contains("the image has no RGB"), std::invalid_argument);
}

// ---- determinism --------------------------------------------------------------

TEST_CASE("determinism: the same samples and seed give the same decision function") {
  const t::TempDir dir;
  small_model().save(dir.path() / "a.yaml");
  small_model().save(dir.path() / "b.yaml");
  CHECK(read_text(dir.path() / "a.yaml") == read_text(dir.path() / "b.yaml"));
}

TEST_CASE("determinism: two adaptive missions give identical records") {
  const Field f = weedmap_field();
  OracleSegmenter oracle(f.num_classes());
  AdaptiveOptions o;
  o.mission = fixed_times();
  o.mission.camera = {.image_width_px = 48, .image_height_px = 36};
  o.top_gsd_cm = 3.0;
  o.candidate_gsd_cm = {1.0, 2.0};
  const DecisionModel model = small_model();
  const auto run = [&] {
    UtilityPolicy policy = std::get<UtilityPolicy>(model.decision_function.rule());
    auto p = policy.params();
    p.min_utility = -1.0;  // descend wherever the predicted gain is positive
    policy.set_params(p);
    return run_adaptive_mission(f, oracle, policy, o, policy.name());
  };
  const AdaptiveResult a = run();
  const AdaptiveResult b = run();
  REQUIRE(a.mission.waypoints.size() == b.mission.waypoints.size());
  CHECK(a.descents() > 0);
  for (std::size_t k = 0; k < a.mission.waypoints.size(); ++k) {
    const WaypointRecord& x = a.mission.waypoints[k];
    const WaypointRecord& y = b.mission.waypoints[k];
    CHECK(x.waypoint.position == y.waypoint.position);
    CHECK(x.waypoint.gsd_cm == y.waypoint.gsd_cm);
    CHECK(x.level == y.level);
    CHECK(x.semantic_ratio == y.semantic_ratio);
    CHECK(x.image_miou_interest == y.image_miou_interest);
    CHECK(x.segmentation_s == y.segmentation_s);
  }
  REQUIRE(a.decisions.size() == b.decisions.size());
  for (std::size_t k = 0; k < a.decisions.size(); ++k) {
    CHECK(a.decisions[k].decision.descend == b.decisions[k].decision.descend);
    CHECK(a.decisions[k].decision.gsd_cm == b.decisions[k].decision.gsd_cm);
    REQUIRE(a.decisions[k].decision.scores.size() == b.decisions[k].decision.scores.size());
    for (std::size_t c = 0; c < a.decisions[k].decision.scores.size(); ++c)
      CHECK(a.decisions[k].decision.scores[c].utility == b.decisions[k].decision.scores[c].utility);
  }
  CHECK(a.mission.total_s() == b.mission.total_s());
  CHECK(a.mission.miou_interest() == b.mission.miou_interest());
  CHECK(cv::countNonZero(a.mission.fused_labels != b.mission.fused_labels) == 0);
}
