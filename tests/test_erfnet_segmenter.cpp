// Tests of the ONNX backend (include/adaptseg/erfnet/onnx_segmenter.hpp) with every bundled model:
// examples/models/erfnet-dubai (ERFNet, input = camera size, stride 1) and
// examples/models/mobilenetv2-dubai (MobileNetV2 + decoder, input 512x384 for the 480x360
// camera, logits at stride 4), each with its fixture in tests/data/<fixture> (written by
// tests/tools/make_erfnet_fixture.py from the PyTorch weights the ONNX file was exported from).
// Models are loaded inside test cases only: doctest_discover_tests runs this binary at build
// time. About 30 forward passes per model (18 of them in the conformance suite).

#include "backend_conformance.hpp"
#include "test_support.hpp"

#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/erfnet/erfnet_segmenter.hpp>  // the old name: it must still bring OnnxSegmenter in
#include <adaptseg/erfnet/network_identity.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/vision/decision_model.hpp>
#include <adaptseg/vision/metrics.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/semantic_map.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <doctest/doctest.h>
#include <yaml-cpp/yaml.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <type_traits>
#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;
namespace fs = std::filesystem;

static_assert(SegmentationBackend<OnnxSegmenter>);
static_assert(!std::is_copy_constructible_v<OnnxSegmenter>);
static_assert(std::is_move_constructible_v<OnnxSegmenter>);

namespace {

/// A bundled model and what its tests expect of it.
struct BundledModel {
  const char* dir;      ///< examples/models/<dir>
  const char* fixture;  ///< tests/data/<fixture>
  /// mIoU floor on the tile-6 test region at 5 cm/px (see the floor test): the value measured
  /// with PyTorch (the fixture's test_field_miou.test_region) minus a margin.
  double floor;
  fs::path model_dir() const { return fs::path(ADAPTSEG_EXAMPLES_DIR) / "models" / dir; }
  fs::path fixture_dir() const { return fs::path(ADAPTSEG_TEST_DATA_DIR) / fixture; }
};

// Measured (fixture.yaml): erfnet-dubai 0.522, mobilenetv2-dubai 0.522; floors 0.05 below.
const BundledModel kModels[] = {{"erfnet-dubai", "erfnet", 0.47}, {"mobilenetv2-dubai", "mobilenetv2", 0.47}};

// The ERFNet model, for the tests of errors and options that need one model only.
fs::path model_dir() { return kModels[0].model_dir(); }
fs::path fixture_dir() { return kModels[0].fixture_dir(); }
const char* kTestField = "dubai-tile-6";  // held out of training and validation

/// The fixture's camera image as the sensor would hand it over.
Image fixture_image(const BundledModel& m = kModels[0]) {
  Image img;
  img.bgr = cv::imread((m.fixture_dir() / "camera.png").string(), cv::IMREAD_COLOR);
  REQUIRE_FALSE(img.bgr.empty());
  img.width_px = img.bgr.cols;
  img.height_px = img.bgr.rows;
  return img;
}

}  // namespace

// The names before adaptseg 0.3 name the same types until 0.4 (with a deprecation warning).
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
static_assert(std::is_same_v<adaptseg::ErfnetSegmenter, adaptseg::OnnxSegmenter>);
static_assert(std::is_same_v<adaptseg::ErfnetParams, adaptseg::OnnxParams>);
static_assert(std::is_same_v<adaptseg::ErfnetModelInfo, adaptseg::OnnxModelInfo>);
#pragma GCC diagnostic pop

TEST_CASE("erfnet: each bundled model reproduces PyTorch's logits and labels on its fixture") {
  for (const BundledModel& m : kModels) {
    CAPTURE(m.dir);
    const YAML::Node fx = YAML::LoadFile((m.fixture_dir() / "fixture.yaml").string());
    const std::vector<int> shape = fx["logits"]["shape"].as<std::vector<int>>();
    const int stride = fx["logits"]["stride"].as<int>();
    REQUIRE(shape.size() == 3);
    const Image img = fixture_image(m);
    // The fixture image has RGB content everywhere, so no pixel is masked as no-data.
    cv::Mat black;
    cv::inRange(img.bgr, cv::Scalar(0, 0, 0), cv::Scalar(0, 0, 0), black);
    REQUIRE(cv::countNonZero(black) == 0);

    OnnxSegmenter erfnet(m.model_dir(), OnnxParams{.camera_width_px = img.width_px,
                                                   .camera_height_px = img.height_px,
                                                   .resize_to_network = true,
                                                   .num_threads = 2});
    REQUIRE(erfnet.num_classes() == shape[0]);

    std::vector<float> ref(static_cast<std::size_t>(shape[0]) * static_cast<std::size_t>(shape[1]) *
                           static_cast<std::size_t>(shape[2]));
    std::ifstream in(m.fixture_dir() / "logits_stride4.f32", std::ios::binary);
    in.read(reinterpret_cast<char*>(ref.data()), static_cast<std::streamsize>(ref.size() * sizeof(float)));
    REQUIRE(in.gcount() == static_cast<std::streamsize>(ref.size() * sizeof(float)));

    // Logits: OpenCV DNN vs PyTorch (float32 both; measured max |diff| ~1e-5 on logits of
    // magnitude ~10). Tolerance 1e-3 absolute.
    const std::vector<cv::Mat> logits = erfnet.logits(img);
    REQUIRE(logits.size() == static_cast<std::size_t>(shape[0]));
    double max_diff = 0.0;
    std::size_t k = 0;
    for (int c = 0; c < shape[0]; ++c)
      for (int i = 0; i < shape[1]; ++i)
        for (int j = 0; j < shape[2]; ++j, ++k)
          max_diff = std::max(
              max_diff,
              std::abs(static_cast<double>(logits[static_cast<std::size_t>(c)].at<float>(i * stride, j * stride)) -
                       static_cast<double>(ref[k])));
    CAPTURE(max_diff);
    CHECK(max_diff < 1e-3);

    // Labels: argmax agrees with PyTorch's on >= 99.9 % of the pixels (near-ties may flip).
    const cv::Mat torch_labels = cv::imread((m.fixture_dir() / "labels_torch.png").string(), cv::IMREAD_UNCHANGED);
    REQUIRE(torch_labels.type() == CV_8UC1);
    const cv::Mat labels = erfnet.segment(img);
    REQUIRE(labels.size() == torch_labels.size());
    const double agree = 1.0 - cv::countNonZero(labels != torch_labels) / static_cast<double>(labels.total());
    CAPTURE(agree);
    CHECK(agree >= 0.999);
  }
}

TEST_CASE("erfnet: each bundled model passes the backend conformance suite on the held-out Dubai tile 6") {
  const Field f = Field::load(t::example_field(kTestField));
  const CameraModel camera;
  for (const BundledModel& m : kModels) {
    CAPTURE(m.dir);
    OnnxSegmenter erfnet(m.model_dir(), f, camera, OnnxParams{.resize_to_network = true, .num_threads = 2});
    CHECK(erfnet.name() == "erfnet");
    t::check_backend_conformance(erfnet, SimulatedSensor(f, camera), f.num_classes());
  }
}

TEST_CASE("erfnet: mIoU of each bundled model on held-out tile 6 at the finest GSD is above its floor") {
  // A sub-field of tile 6 (8 images at 1x the orthomosaic GSD, 5 cm/px, to keep the test
  // fast). Measured with PyTorch by tests/tools/make_erfnet_fixture.py (fixture.yaml,
  // test_field_miou.test_region); the floor is set below that with margin (kModels); it catches
  // a broken pre-processing (channel order, normalisation, resampling) or a wrong model, which
  // fall far below it.
  const Field whole = Field::load(t::example_field(kTestField));
  const Field f = whole.sub_field({0.0, 0.0, 0.37, 0.57});
  const CameraModel camera;
  const SimulatedSensor sensor(f, camera);
  const auto plan = LawnmowerPlanner(camera).plan(f.area(), f.gsd_cm());
  CHECK(plan.size() == 8);
  for (const BundledModel& m : kModels) {
    CAPTURE(m.dir);
    OnnxSegmenter erfnet(m.model_dir(), f, camera, OnnxParams{.resize_to_network = true, .num_threads = 2});
    ConfusionMatrix erf(f.num_classes()), oracle_cm(f.num_classes());
    OracleSegmenter oracle(f.num_classes());
    for (const auto& w : plan) {
      const Image img = sensor.capture(w);
      erf += image_confusion(img, erfnet.segment(img), f.num_classes());
      oracle_cm += image_confusion(img, oracle.segment(img), f.num_classes());
    }
    const double miou = erf.miou_all().value();
    const double measured =
        YAML::LoadFile((m.fixture_dir() / "fixture.yaml").string())["test_field_miou"]["test_region"]["miou_ortho"]
            .as<double>();
    CAPTURE(miou);
    CAPTURE(measured);
    CHECK(miou > m.floor);
    // The C++ path computes the same number as the Python measurement (up to argmax near-ties).
    CHECK(miou == doctest::Approx(measured).epsilon(0.01));
    CHECK(oracle_cm.miou_all().value() == doctest::Approx(1.0));  // oracle at g0: exact
  }
}

TEST_CASE("erfnet: probabilities are the softmax of the logits and black pixels are no-data") {
  Image img = fixture_image();
  img.ignore_label = 255;
  img.bgr(cv::Rect(0, 0, 40, 30)).setTo(cv::Scalar(0, 0, 0));  // as outside the orthomosaic
  OnnxSegmenter erfnet(model_dir(), OnnxParams{.num_threads = 2});
  const cv::Mat labels = erfnet.segment(img);
  const std::vector<cv::Mat> probs = erfnet.probabilities(img);
  REQUIRE(probs.size() == static_cast<std::size_t>(erfnet.num_classes()));
  cv::Mat sum = cv::Mat::zeros(labels.size(), CV_32F);
  for (const auto& p : probs) {
    REQUIRE(p.type() == CV_32FC1);
    REQUIRE(p.size() == labels.size());
    sum += p;
  }
  int disagree = 0, bad_no_data = 0, bad_sum = 0;
  for (int r = 0; r < labels.rows; ++r)
    for (int c = 0; c < labels.cols; ++c) {
      const bool no_data = r < 30 && c < 40;
      if (no_data) {
        bad_no_data += (labels.at<std::uint8_t>(r, c) != 255 || sum.at<float>(r, c) != 0.0f) ? 1 : 0;
        continue;
      }
      bad_sum += std::abs(sum.at<float>(r, c) - 1.0f) > 1e-4f ? 1 : 0;
      int best = 0;
      for (int k = 1; k < erfnet.num_classes(); ++k)
        if (probs[static_cast<std::size_t>(k)].at<float>(r, c) > probs[static_cast<std::size_t>(best)].at<float>(r, c))
          best = k;
      disagree += best != labels.at<std::uint8_t>(r, c) ? 1 : 0;
    }
  CHECK(bad_no_data == 0);  // no-data pixels: ignore label, all probabilities 0
  CHECK(bad_sum == 0);      // elsewhere the probabilities sum to 1
  CHECK(disagree <= 10);    // argmax of the softmax = argmax of the logits, but for exp rounding

  // With the no-data mask off, the network labels the black pixels too.
  OnnxSegmenter unmasked(model_dir(), OnnxParams{.black_is_no_data = false});
  const cv::Mat all = unmasked.segment(img);
  CHECK(cv::countNonZero(all == 255) == 0);
  CHECK(cv::countNonZero(all != labels) == 30 * 40);
}

TEST_CASE("erfnet: labels and tempered probabilities from one pass") {
  const Image img = fixture_image();
  OnnxSegmenter erfnet(model_dir(), OnnxParams{.num_threads = 2});
  const Segmentation s = erfnet.segment_with_probabilities(img);
  CHECK(cv::countNonZero(s.labels != erfnet.segment(img)) == 0);
  const auto probs = erfnet.probabilities(img);
  REQUIRE(s.probabilities.size() == probs.size());
  for (std::size_t c = 0; c < probs.size(); ++c) CHECK(cv::norm(s.probabilities[c], probs[c], cv::NORM_INF) == 0.0);
  CHECK(erfnet.model_info().temperature > 0.0);
  // The same network at temperature 2: the same labels, probabilities softmax(logits / 2).
  t::TempDir tmp;
  fs::copy_file(model_dir() / "model.onnx", tmp.path() / "model.onnx");
  std::string yaml = t::read_file(model_dir() / "model.yaml");
  if (const auto at = yaml.find("\ntemperature:"); at != std::string::npos)
    yaml.erase(at + 1, yaml.find('\n', at + 1) - at);
  t::write_file(tmp.path() / "model.yaml", yaml + "temperature: 2\n");
  OnnxSegmenter warm(tmp.path(), OnnxParams{.num_threads = 2});
  CHECK(warm.model_info().temperature == 2.0);
  const Segmentation w = warm.segment_with_probabilities(img);
  CHECK(cv::countNonZero(w.labels != s.labels) == 0);
  const auto logits = warm.logits(img);
  int bad = 0;
  for (int r = 0; r < img.height_px; r += 7)
    for (int x = 0; x < img.width_px; x += 7) {
      double z = 0.0;
      for (const auto& l : logits) z += std::exp(l.at<float>(r, x) / 2.0);
      for (std::size_t c = 0; c < logits.size(); ++c)
        bad +=
            std::abs(w.probabilities[c].at<float>(r, x) - std::exp(logits[c].at<float>(r, x) / 2.0) / z) > 1e-5 ? 1 : 0;
    }
  CHECK(bad == 0);
  // A temperature outside [0.01, 100] is refused, naming the file.
  t::write_file(tmp.path() / "model.yaml", yaml + "temperature: 0\n");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("temperature must be a number in [0.01, 100]"),
                       std::invalid_argument);
}

TEST_CASE("erfnet: resize_to_network takes other camera sizes of the same aspect ratio") {
  const Image native = fixture_image();
  Image big = native;
  cv::resize(native.bgr, big.bgr, cv::Size(960, 720), 0, 0, cv::INTER_LINEAR);
  big.width_px = 960;
  big.height_px = 720;
  OnnxSegmenter strict(model_dir());
  CHECK_THROWS_WITH_AS((void)strict.segment(big), doctest::Contains("resize_to_network"), std::invalid_argument);
  OnnxSegmenter erfnet(model_dir(),
                       OnnxParams{.camera_width_px = 960, .camera_height_px = 720, .resize_to_network = true});
  const cv::Mat labels = erfnet.segment(big);
  REQUIRE(labels.type() == CV_8UC1);
  REQUIRE(labels.size() == cv::Size(960, 720));
  // The contract: the network sees the image shrunk with INTER_AREA to its input size, and its
  // logits come back bilinearly enlarged to the camera size.
  Image small = native;
  cv::resize(big.bgr, small.bgr, cv::Size(480, 360), 0, 0, cv::INTER_AREA);
  OnnxSegmenter native_net(model_dir());
  const std::vector<cv::Mat> want = native_net.logits(small);
  const std::vector<cv::Mat> got = erfnet.logits(big);
  REQUIRE(got.size() == want.size());
  for (std::size_t c = 0; c < got.size(); ++c) {
    REQUIRE(got[c].size() == cv::Size(960, 720));
    cv::Mat up;
    cv::resize(want[c], up, got[c].size(), 0, 0, cv::INTER_LINEAR);
    CHECK(cv::norm(got[c], up, cv::NORM_INF) < 1e-4);
  }
  // And the labels stay close to the original image's (INTER_AREA 2x down of a bilinear 2x up
  // is close to, not equal to, the original; 0.89 for the committed model).
  const cv::Mat torch_labels = cv::imread((fixture_dir() / "labels_torch.png").string(), cv::IMREAD_UNCHANGED);
  cv::Mat up;
  cv::resize(torch_labels, up, labels.size(), 0, 0, cv::INTER_NEAREST);
  const double agree = 1.0 - cv::countNonZero(labels != up) / static_cast<double>(labels.total());
  CAPTURE(agree);
  CHECK(agree > 0.8);
}

TEST_CASE("erfnet: clear errors for bad models, bad parameters and images without RGB") {
  t::TempDir tmp;
  // Missing files.
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path() / "nope"), doctest::Contains("model directory not found"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("metadata file not found"), std::invalid_argument);
  fs::copy_file(model_dir() / "model.yaml", tmp.path() / "model.yaml");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("ONNX file not found"), std::invalid_argument);
  // A corrupt ONNX file.
  t::write_file(tmp.path() / "model.onnx", "this is not a protobuf \x01\x02\x03 garbage garbage");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("cannot load ONNX model"), std::invalid_argument);
  // A truncated ONNX file.
  {
    std::ifstream src(model_dir() / "model.onnx", std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(src)), std::istreambuf_iterator<char>());
    bytes.resize(bytes.size() / 2);
    std::ofstream(tmp.path() / "model.onnx", std::ios::binary) << bytes;
  }
  CHECK_THROWS_AS(OnnxSegmenter(tmp.path()), std::invalid_argument);
  // Metadata whose class list does not match the network's output channels.
  fs::copy_file(model_dir() / "model.onnx", tmp.path() / "model.onnx", fs::copy_options::overwrite_existing);
  {
    YAML::Node meta = YAML::LoadFile((model_dir() / "model.yaml").string());
    meta["classes"].push_back("extra");
    std::ofstream(tmp.path() / "model.yaml") << meta;
  }
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("outputs 1x5x"), std::invalid_argument);
  // Malformed metadata.
  t::write_file(tmp.path() / "model.yaml",
                "classes: [a, b]\ninput: {width: 481, height: 360, channel_order: RGB, mean: [0,0,0], std: [1,1,1]}\n");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("multiples of 8"), std::invalid_argument);
  t::write_file(tmp.path() / "model.yaml",
                "classes: [a, b]\ninput: {width: 480, height: 360, channel_order: RGB, mean: [0,0,0], std: [1,0,1]}\n");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("input.std"), std::invalid_argument);
  t::write_file(tmp.path() / "model.yaml", "classes: [a, b\n");
  CHECK_THROWS_WITH_AS(OnnxSegmenter(tmp.path()), doctest::Contains("YAML error"), std::invalid_argument);

  // Wrong class count vs a field (WeedMap: soil, crop, weed).
  const Field weedmap = Field::load(t::example_field("weedmap-000"));
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), weedmap, CameraModel{}),
                       doctest::Contains("the model's 5 classes [building, land, road, vegetation, water] "
                                         "differ from the 3 expected classes [soil, crop, weed]"),
                       std::invalid_argument);
  // Same count, other names or order.
  CHECK_THROWS_AS(
      OnnxSegmenter(model_dir(), OnnxParams{.expected_classes = {"land", "building", "road", "vegetation", "water"}}),
      std::invalid_argument);
  // A camera the network cannot take.
  const Field dubai = Field::load(t::example_field(kTestField));
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), dubai, CameraModel({.image_width_px = 640, .image_height_px = 480})),
                       doctest::Contains("640x480 vs network input 480x360"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), dubai, CameraModel({.image_width_px = 640, .image_height_px = 360}),
                                     OnnxParams{.resize_to_network = true}),
                       doctest::Contains("aspect ratio"), std::invalid_argument);
  // Bad parameters.
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), OnnxParams{.camera_width_px = 480}),
                       doctest::Contains("camera_width_px"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), OnnxParams{.num_threads = -1}), doctest::Contains("num_threads"),
                       std::invalid_argument);
  // 100000 threads crashed OpenCV's pool at exit: refused before any is started.
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), OnnxParams{.num_threads = 100000}),
                       doctest::Contains("num_threads must be in 0..256"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), OnnxParams{.name = ""}), doctest::Contains("name"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(OnnxSegmenter(model_dir(), OnnxParams{.dnn_target = 12345}), doctest::Contains("dnn_target"),
                       std::invalid_argument);

  // Images without RGB (a labels-only field such as WeedMap) and mistyped images.
  OnnxSegmenter erfnet(model_dir(), dubai, CameraModel{});
  const SimulatedSensor no_rgb(weedmap, CameraModel{});
  const Image labels_only = no_rgb.capture(LawnmowerPlanner(CameraModel{}).plan(weedmap.area(), 2.0).front());
  REQUIRE(labels_only.bgr.empty());
  CHECK_THROWS_WITH_AS((void)erfnet.segment(labels_only), doctest::Contains("no RGB"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)erfnet.probabilities(labels_only), doctest::Contains("no RGB"), std::invalid_argument);
  Image gray = fixture_image();
  cv::cvtColor(gray.bgr, gray.bgr, cv::COLOR_BGR2GRAY);
  CHECK_THROWS_WITH_AS((void)erfnet.segment(gray), doctest::Contains("CV_8UC3"), std::invalid_argument);
  Image mismatch = fixture_image();
  mismatch.width_px = 481;
  CHECK_THROWS_WITH_AS((void)erfnet.segment(mismatch), doctest::Contains("width_px x height_px"),
                       std::invalid_argument);
}

TEST_CASE(
    "erfnet: the deployment model's bundled decision models name it and the networks that never saw their tiles") {
  // examples/models/mobilenetv2-dubai-all/decision-<class>.yaml (scripts/loto.sh decision): a
  // new site flies them with this network, so each must name this network as it is now (its
  // weights and temperature) and each calibration tile's network of the same recipe that never
  // saw it; a retrained or re-tempered network makes them stale, and this says so. They pool
  // their maps (docs/method.md, "Fusion").
  const fs::path models = fs::path(ADAPTSEG_EXAMPLES_DIR) / "models";
  const fs::path all = models / "mobilenetv2-dubai-all";
  for (const char* cls : {"building", "road", "vegetation", "water"}) {
    CAPTURE(cls);
    const DecisionModel m = DecisionModel::load(all / ("decision-" + std::string(cls) + ".yaml"));
    CHECK(m.segmenter == network_name(all));
    CHECK(m.interest == std::vector<std::string>{cls});
    CHECK(m.map_fusion == MapFusion::pooled);
    REQUIRE(m.calibration_fields.size() == 6);
    REQUIRE(m.field_segmenters.size() == 6);
    for (std::size_t k = 0; k < 6; ++k) {
      const std::string tile = "tile-" + std::to_string(k + 1);
      CHECK(m.calibration_fields[k] == "dubai-" + tile);
      CHECK(m.field_segmenters[k] == network_name(models / "mobilenetv2-dubai-loto" / tile));
    }
  }
}

TEST_CASE("erfnet: the deployment model (all six tiles) keeps the backend contract and its metadata says what it saw") {
  // examples/models/mobilenetv2-dubai-all: trained on every bundled tile, for new ground; no
  // held-out tile to measure its accuracy on here (its README), so the checks are the contract,
  // the metadata, and that it is a trained network: on tile 6 (one of its training tiles) at
  // 15 cm/px it labels the ground better than the evaluation network, which never saw it.
  const fs::path dir = fs::path(ADAPTSEG_EXAMPLES_DIR) / "models" / "mobilenetv2-dubai-all";
  const YAML::Node meta = YAML::LoadFile((dir / "model.yaml").string());
  CHECK(meta["training"]["fields"].size() == 6);
  CHECK(meta["training"]["held_out_test_field"].as<std::string>() == "none");
  const Field f = Field::load(t::example_field(kTestField));
  const CameraModel camera;
  const OnnxParams p{.resize_to_network = true, .num_threads = 2};
  OnnxSegmenter all(dir, f, camera, p);
  CHECK(all.model_info().output_stride == 4);
  t::check_backend_conformance(all, SimulatedSensor(f, camera), f.num_classes());
  OnnxSegmenter eval(kModels[1].model_dir(), f, camera, p);
  const SimulatedSensor sensor(f, camera);
  ConfusionMatrix ca(f.num_classes()), ce(f.num_classes());
  for (const auto& w : LawnmowerPlanner(camera).plan(f.area(), 3.0 * f.gsd_cm())) {
    const Image img = sensor.capture(w);
    ca += image_confusion(img, all.segment(img), f.num_classes());
    ce += image_confusion(img, eval.segment(img), f.num_classes());
  }
  CAPTURE(ca.miou_all().value());
  CAPTURE(ce.miou_all().value());
  CHECK(ca.miou_all().value() > ce.miou_all().value() + 0.02);
}

TEST_CASE(
    "network identity: the folder's name and its files' hash, and another network for other weights or temperature") {
  const std::filesystem::path models = std::filesystem::path(ADAPTSEG_EXAMPLES_DIR) / "models";
  const auto [onnx, metadata] = network_files(models / "mobilenetv2-dubai");
  CHECK(onnx == models / "mobilenetv2-dubai" / "model.onnx");
  CHECK(metadata == models / "mobilenetv2-dubai" / "model.yaml");
  CHECK(network_files(onnx) == std::pair{onnx, metadata});  // the .onnx itself: its .yaml beside it
  const std::string id = network_digest(models / "mobilenetv2-dubai");
  CHECK(id.rfind("mobilenetv2-dubai-", 0) == 0);
  CHECK(id.size() == std::string("mobilenetv2-dubai-").size() + 16);
  CHECK(network_name(models / "mobilenetv2-dubai") == "erfnet:" + id);
  CHECK(network_name(models / "ensemble-dubai").rfind("ensemble:ensemble-dubai-", 0) == 0);
  const std::vector<std::string> seen = network_training_fields(models / "mobilenetv2-dubai");
  CHECK(std::find(seen.begin(), seen.end(), "dubai-tile-1") != seen.end());
  CHECK(std::find(seen.begin(), seen.end(), "dubai-tile-4") == seen.end());

  // A copy under the same folder name: the same network; another temperature or other weights
  // in that folder: another one.
  t::TempDir dir;
  const std::filesystem::path copy = dir.path() / "mobilenetv2-dubai";
  std::filesystem::create_directories(copy);
  std::filesystem::copy_file(onnx, copy / "model.onnx");
  std::filesystem::copy_file(metadata, copy / "model.yaml");
  CHECK(network_digest(copy) == id);
  { std::ofstream(copy / "model.yaml", std::ios::app) << "# re-tempered\n"; }
  const std::string tempered = network_digest(copy);
  CHECK(tempered != id);
  { std::ofstream(copy / "model.onnx", std::ios::app | std::ios::binary) << '\0'; }
  CHECK(network_digest(copy) != tempered);
  // An ensemble is another ensemble when a member changes.
  const std::string ensemble = ensemble_digest(models / "ensemble-dubai");
  CHECK(ensemble == network_digest(models / "ensemble-dubai"));
}

TEST_CASE(
    "pooled map: on tile 6, which it never saw, the network's 15 and 5 cm/px images pooled map better than 5 alone") {
  // The leave-one-tile-out MobileNetV2 that never trained on tile 6 (examples/models/
  // mobilenetv2-dubai-loto/tile-6, its bundled temperature) flies two whole-field lawnmowers,
  // 15 then 5 cm/px, over the tile. With the paper's fusion the map is the 5 cm/px one; pooled,
  // the 15 cm/px images keep the pixels where they were sure and the closer look was not.
  // Measured (2026-11-29), finest -> pooled: building 0.576 -> 0.583, road 0.309 -> 0.356,
  // vegetation 0.715 -> 0.725, water 0.748 -> 0.762, as adaptseg_tools.fusion_study --tiles 6
  // measures them in Python.
  const Field f = Field::load(t::example_field(kTestField));
  const CameraModel camera;
  const SimulatedSensor sensor(f, camera);
  OnnxSegmenter net(fs::path(ADAPTSEG_EXAMPLES_DIR) / "models" / "mobilenetv2-dubai-loto" / "tile-6", f, camera,
                    OnnxParams{.resize_to_network = true, .num_threads = 2});
  SemanticMap finest(f.labels().size(), f.ignore_label());
  SemanticMap pooled(f.labels().size(), f.ignore_label(), MapFusion::pooled);
  const LawnmowerPlanner planner(camera);
  for (double factor : {3.0, 1.0})
    for (const auto& w : planner.plan(f.area(), factor * f.gsd_cm())) {
      const Image img = sensor.capture(w);
      const Segmentation s = net.segment_with_probabilities(img);
      finest.fuse(img, s.labels);
      pooled.fuse(img, s);
    }
  ConfusionMatrix fine_cm(f.num_classes()), pooled_cm(f.num_classes());
  fine_cm.add(f.labels(), finest.labels(), f.ignore_label());
  pooled_cm.add(f.labels(), pooled.labels(), f.ignore_label());
  int better = 0;
  for (const std::string name : {"building", "road", "vegetation", "water"}) {
    const int c = f.class_indices({name}).front();
    const double fine_iou = fine_cm.iou(c).value(), pooled_iou = pooled_cm.iou(c).value();
    CAPTURE(name);
    CAPTURE(fine_iou);
    CAPTURE(pooled_iou);
    CHECK(pooled_iou > fine_iou - 0.002);  // never worse
    better += pooled_iou > fine_iou + 0.005 ? 1 : 0;
  }
  CHECK(better >= 3);
  CHECK(pooled_cm.miou_all().value() > fine_cm.miou_all().value() + 0.01);
  CHECK(cv::countNonZero(pooled.gsd_cm() != finest.gsd_cm()) == 0);  // the same looks
}
