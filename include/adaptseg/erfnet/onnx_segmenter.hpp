#pragma once
/// @file
/// The network backend: any segmentation network exported to ONNX, run through OpenCV DNN (the
/// paper's is ERFNet, §3.1, §5: Romera et al. 2017, trained on RGB images taken at several
/// altitudes; OnnxSegmenter, called ErfnetSegmenter before adaptseg 0.3). Link
/// `adaptseg::erfnet`; this header is kept out of the umbrella `planner.hpp` so that users
/// without OpenCV DNN pay nothing for it.
///
/// A model is an ONNX file (fp32, input `1x3xHxW`, output `1xCx(H/s)x(W/s)` logits at output
/// stride s) plus a metadata YAML (onnx_model_info.hpp: class names, input size, channel order,
/// normalisation `(v / 255 - mean) / std`, output stride). Any network of that form runs here:
/// the bundled models are an ERFNet (`examples/models/erfnet-dubai`, stride 1) and a MobileNetV2
/// with a light decoder (`examples/models/mobilenetv2-dubai`, stride 4).

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/erfnet/onnx_model_info.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// Options of OnnxSegmenter, validated once by its constructor.
struct OnnxParams {
  /// Class names the caller needs, in label-index order (e.g. a Field's classes). Empty: not
  /// checked. Otherwise the model's classes must equal them, count and names.
  std::vector<std::string> expected_classes{};
  /// Size [px] of the camera images the backend will get; 0 x 0 means "the network's input
  /// size". Checked against the network at construction (see `resize_to_network`).
  int camera_width_px = 0;
  int camera_height_px = 0;
  /// What to do with images whose size differs from the network input. false: refuse (the
  /// constructor throws for a differing camera size, `segment` for a differing image). true:
  /// resample the RGB to the input size (INTER_AREA shrinking, INTER_LINEAR enlarging). The
  /// logits are resampled bilinearly to the image size whenever their size differs from it
  /// (a network with an output stride > 1 always). The aspect ratios must
  /// agree within 1 % either way: a stretched image has another GSD than the network learnt.
  bool resize_to_network = false;
  /// Camera pixels that are exactly black (0, 0, 0), which is how SimulatedSensor fills
  /// footprint parts outside the orthomosaic, carry no RGB content: true labels them with the
  /// image's ignore label and gives them all-zero probabilities; false lets the network
  /// label them like any other pixel.
  bool black_is_no_data = true;
  /// Test-time mirror: true runs the network on the image and on its left-right mirror and takes
  /// the mean of the two probability maps (the mirror's flipped back), labels being the mean's
  /// argmax; two forward passes per image. A network trained with mirrored images (as
  /// train_segnet.py's augmentations do) answers both, and their mean is usually the better map
  /// (measured: examples/models/ensemble-dubai/README.md, "Test-time mirror"). logits() stays one
  /// pass.
  bool test_time_mirror = false;
  /// 1..256: `cv::setNumThreads(num_threads)` at construction. NOTE: this is OpenCV's
  /// process-wide thread count and affects all OpenCV calls. 0: leave it unchanged.
  int num_threads = 0;
  /// OpenCV DNN backend and target (`cv::dnn::Backend`, `cv::dnn::Target`).
  int dnn_backend = cv::dnn::DNN_BACKEND_OPENCV;
  int dnn_target = cv::dnn::DNN_TARGET_CPU;
  /// Written into mission results by `name()`.
  std::string name = "erfnet";
};

/// Semantic segmentation with an ONNX network (ERFNet, MobileNetV2 + decoder, or any model of
/// the metadata format above) through OpenCV DNN; a `SegmentationBackend`.
///
/// Per image: BGR -> the network's channel order, `(v / 255 - mean) / std` per channel
/// (exactly the training normalisation, from the metadata), forward, then argmax over the
/// logits (ties to the lower class index) for `segment`, softmax of the logits over the model's
/// temperature for `probabilities` (both from one pass: `segment_with_probabilities`). With
/// OnnxParams::test_time_mirror a second pass over the mirrored image: probabilities are the
/// mean of the two, labels its argmax.
/// Every pixel with RGB content gets a class: the network cannot know the field boundary,
/// so pixels inside the footprint but outside the labelled field are labelled too (metrics
/// skip them through the ground truth's ignore label). Pixels without RGB content (exactly
/// black) get the ignore label when `black_is_no_data` (default), see OnnxParams.
///
/// Contract (SegmentationBackend): output CV_8UC1 of the image's size, values in
/// `0..classes()-1` or `image.ignore_label`; the image is not modified; same image -> same
/// labels. Not thread-safe: `segment` runs the network (a mutable cv::dnn::Net); use one
/// instance per thread. Move-only (a copied cv::dnn::Net would share its state).
///
/// @code
/// const auto field = adaptseg::Field::load("examples/data/dubai-tile-6");
/// const adaptseg::CameraModel camera;  // 480 x 360
/// adaptseg::OnnxSegmenter erfnet("examples/models/erfnet-dubai", field, camera);
/// cv::Mat labels = erfnet.segment(adaptseg::SimulatedSensor(field, camera).capture(waypoint));
/// @endcode
class OnnxSegmenter {
 public:
  using Params = OnnxParams;

  /// Loads `onnx_file` with its metadata `metadata_file`.
  /// @throws std::invalid_argument naming the file and the problem: a missing file, a
  ///         metadata YAML that is malformed or lacks a key, an ONNX file OpenCV cannot
  ///         parse, a network whose output is not `1 x classes x H x W` for the metadata's
  ///         input size, classes that differ from `params.expected_classes`, a camera size
  ///         the network cannot take (see OnnxParams::resize_to_network), or invalid
  ///         params (negative sizes or threads, an empty name, a DNN backend/target pair
  ///         this OpenCV build does not offer).
  OnnxSegmenter(const std::filesystem::path& onnx_file, const std::filesystem::path& metadata_file, Params params = {})
      : params_(std::move(params)) {
    validate_params();
    info_ = read_onnx_model_info(metadata_file);
    check_classes(metadata_file);
    check_camera();
    load_network(onnx_file);
    if (params_.num_threads > 0) cv::setNumThreads(params_.num_threads);
  }

  /// Loads `model_dir/model.onnx` and `model_dir/model.yaml`.
  /// @throws std::invalid_argument as the two-file constructor, and for a missing directory.
  explicit OnnxSegmenter(const std::filesystem::path& model_dir, Params params = {})
      : OnnxSegmenter(checked_dir(model_dir) / "model.onnx", model_dir / "model.yaml", std::move(params)) {}

  /// Loads `model_dir` for images of `camera` over `field`: the model's classes must be the
  /// field's classes and the camera's image size the network's input size (unless
  /// `params.resize_to_network`). Overrides `params.expected_classes` and the camera size.
  /// @throws std::invalid_argument as the two-file constructor.
  OnnxSegmenter(const std::filesystem::path& model_dir, const Field& field, const CameraModel& camera,
                Params params = {})
      : OnnxSegmenter(model_dir, for_field(field, camera, std::move(params))) {}

  OnnxSegmenter(const OnnxSegmenter&) = delete;
  OnnxSegmenter& operator=(const OnnxSegmenter&) = delete;
  OnnxSegmenter(OnnxSegmenter&&) = default;
  OnnxSegmenter& operator=(OnnxSegmenter&&) = default;
  ~OnnxSegmenter() = default;

  /// `params` with the expected classes of `field` and the image size of `camera`, for the
  /// two-file constructor (the directory-and-field constructor does this itself).
  [[nodiscard]] static Params for_field(const Field& field, const CameraModel& camera, Params params = {}) {
    params.expected_classes.clear();
    for (const auto& c : field.classes()) params.expected_classes.push_back(c.name);
    params.camera_width_px = camera.width_px();
    params.camera_height_px = camera.height_px();
    return params;
  }

  [[nodiscard]] std::string name() const { return params_.name; }
  [[nodiscard]] const Params& params() const noexcept { return params_; }
  [[nodiscard]] const OnnxModelInfo& model_info() const noexcept { return info_; }

  /// The metadata YAML `file` as the constructor reads it, without loading the network.
  /// @throws std::invalid_argument as the constructor does for bad metadata.
  [[nodiscard]] static OnnxModelInfo read_model_info(const std::filesystem::path& file) {
    return read_onnx_model_info(file);
  }
  [[nodiscard]] int num_classes() const noexcept { return static_cast<int>(info_.classes.size()); }
  [[nodiscard]] const std::vector<std::string>& classes() const noexcept { return info_.classes; }
  /// The network's input size [px].
  [[nodiscard]] cv::Size input_size() const noexcept { return {info_.input_width_px, info_.input_height_px}; }
  /// The size of the network's logits [px]: the input size / the output stride.
  [[nodiscard]] cv::Size output_size() const noexcept {
    return {info_.input_width_px / info_.output_stride, info_.input_height_px / info_.output_stride};
  }

  /// Labels: CV_8UC1, `image.height_px x image.width_px`, argmax of the logits (ties to the
  /// lower index); `image.ignore_label` on pixels without RGB content (see OnnxParams).
  /// @throws std::invalid_argument for an image without RGB (`image.bgr` empty, e.g. a field
  ///         with labels only), an RGB that is not CV_8UC3 of `width_px x height_px`, or a
  ///         size the network cannot take.
  [[nodiscard]] cv::Mat segment(const Image& image) {
    if (params_.test_time_mirror) return segment_with_probabilities(image).labels;
    cv::Mat labels = argmax(logits(image));
    if (params_.black_is_no_data) labels.setTo(cv::Scalar(image.ignore_label), no_data_mask(image.bgr));
    return labels;
  }

  /// segment() and probabilities() from one forward pass (two with
  /// OnnxParams::test_time_mirror) (SegmentsWithProbabilities).
  /// @throws std::invalid_argument as segment().
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) {
    Segmentation s;
    s.probabilities = logits(image);
    if (params_.test_time_mirror) {
      softmax_in_place(s.probabilities);
      Image mirrored = image;
      mirrored.bgr = cv::Mat();  // a new buffer: `image` shares its pixels with the copy
      cv::flip(image.bgr, mirrored.bgr, 1);
      std::vector<cv::Mat> back = logits(mirrored);
      softmax_in_place(back);
      cv::Mat flipped;
      for (std::size_t c = 0; c < back.size(); ++c) {
        cv::flip(back[c], flipped, 1);
        cv::addWeighted(s.probabilities[c], 0.5, flipped, 0.5, 0.0, s.probabilities[c]);
      }
      s.labels = argmax(s.probabilities);
    } else {
      s.labels = argmax(s.probabilities);
      softmax_in_place(s.probabilities);
    }
    if (params_.black_is_no_data) {
      const cv::Mat mask = no_data_mask(image.bgr);
      s.labels.setTo(cv::Scalar(image.ignore_label), mask);
      for (auto& p : s.probabilities) p.setTo(cv::Scalar(0.0), mask);
    }
    return s;
  }

  /// Class probabilities: one CV_32FC1 plane per class, each `image.height_px x
  /// image.width_px`, the softmax of the logits over the model's temperature
  /// (OnnxModelInfo::temperature); they sum to 1 per pixel, except on pixels without RGB
  /// content (see OnnxParams::black_is_no_data), where all are 0.
  /// @throws std::invalid_argument as segment().
  [[nodiscard]] std::vector<cv::Mat> probabilities(const Image& image) {
    return segment_with_probabilities(image).probabilities;
  }

  /// The raw network output: one CV_32FC1 plane of logits per class at the image's size
  /// (resampled bilinearly where the network's output size differs from it). No masking; one
  /// pass (OnnxParams::test_time_mirror does not apply).
  /// @throws std::invalid_argument as segment().
  [[nodiscard]] std::vector<cv::Mat> logits(const Image& image) {
    check_image(image);
    const cv::Size in = input_size();
    const cv::Size out_size(image.width_px, image.height_px);
    cv::Mat rgb = image.bgr;
    if (rgb.size() != in) {
      const bool shrink = rgb.cols > in.width;
      cv::resize(image.bgr, rgb, in, 0, 0, shrink ? cv::INTER_AREA : cv::INTER_LINEAR);
    }
    net_.setInput(to_blob(rgb));
    cv::Mat out = net_.forward();
    const cv::Size net_out = output_size();
    ADAPTSEG_ASSERT(out.dims == 4 && out.size[1] == num_classes() && out.size[2] == net_out.height &&
                    out.size[3] == net_out.width);
    std::vector<cv::Mat> planes(static_cast<std::size_t>(num_classes()));
    for (int c = 0; c < num_classes(); ++c) {
      // Wraps the network's buffer; copied (or resampled) before the next forward.
      const cv::Mat view(net_out, CV_32F, out.ptr<float>(0, c));
      if (out_size == net_out)
        planes[static_cast<std::size_t>(c)] = view.clone();
      else
        cv::resize(view, planes[static_cast<std::size_t>(c)], out_size, 0, 0, cv::INTER_LINEAR);
    }
    return planes;
  }

 private:
  /// Per pixel, the index of the largest plane (ties to the lower index).
  [[nodiscard]] static cv::Mat argmax(const std::vector<cv::Mat>& planes) {
    const cv::Size size = planes.front().size();
    cv::Mat labels(size, CV_8UC1);
    const auto n = planes.size();
    std::vector<const float*> rows(n);
    for (int r = 0; r < size.height; ++r) {
      for (std::size_t c = 0; c < n; ++c) rows[c] = planes[c].ptr<float>(r);
      auto* out = labels.ptr<std::uint8_t>(r);
      for (int x = 0; x < size.width; ++x) {
        std::size_t best = 0;
        float best_v = rows[0][x];
        for (std::size_t c = 1; c < n; ++c)
          if (rows[c][x] > best_v) {  // strict: ties keep the lower index
            best_v = rows[c][x];
            best = c;
          }
        out[x] = static_cast<std::uint8_t>(best);
      }
    }
    return labels;
  }

  /// Logits -> softmax(logits / T) per pixel, in place.
  void softmax_in_place(std::vector<cv::Mat>& planes) const {
    const cv::Size size = planes.front().size();
    const auto n = planes.size();
    const auto inv_t = static_cast<float>(1.0 / info_.temperature);
    std::vector<float*> rows(n);
    for (int r = 0; r < size.height; ++r) {
      for (std::size_t c = 0; c < n; ++c) rows[c] = planes[c].ptr<float>(r);
      for (int x = 0; x < size.width; ++x) {
        float m = rows[0][x];
        for (std::size_t c = 1; c < n; ++c) m = std::max(m, rows[c][x]);
        float sum = 0.0f;
        for (std::size_t c = 0; c < n; ++c) {
          rows[c][x] = std::exp((rows[c][x] - m) * inv_t);
          sum += rows[c][x];
        }
        for (std::size_t c = 0; c < n; ++c) rows[c][x] /= sum;
      }
    }
  }

  static std::filesystem::path checked_dir(const std::filesystem::path& dir) {
    if (!std::filesystem::is_directory(dir))
      throw std::invalid_argument("OnnxSegmenter: model directory not found: " + dir.string());
    return dir;
  }

  void validate_params() const {
    detail::require(params_.camera_width_px >= 0 && params_.camera_height_px >= 0 &&
                        (params_.camera_width_px == 0) == (params_.camera_height_px == 0),
                    "OnnxParams: camera_width_px and camera_height_px must both be 0 or both > 0",
                    std::to_string(params_.camera_width_px) + "x" + std::to_string(params_.camera_height_px));
    // Beyond a few hundred threads OpenCV's pool is no faster and its teardown has crashed
    // (100000 threads: a segmentation fault at exit).
    detail::require(params_.num_threads >= 0 && params_.num_threads <= 256, "OnnxParams: num_threads must be in 0..256",
                    params_.num_threads);
    detail::require(!params_.name.empty(), "OnnxParams: name must not be empty", "''");
    const auto targets = cv::dnn::getAvailableTargets(static_cast<cv::dnn::Backend>(params_.dnn_backend));
    bool target_ok = false;
    for (const auto t : targets) target_ok = target_ok || static_cast<int>(t) == params_.dnn_target;
    detail::require(target_ok,
                    "OnnxParams: dnn_target is not available for dnn_backend " + std::to_string(params_.dnn_backend) +
                        " in this OpenCV build",
                    params_.dnn_target);
  }

  void check_classes(const std::filesystem::path& file) const {
    if (params_.expected_classes.empty()) return;
    if (params_.expected_classes != info_.classes)
      throw std::invalid_argument(
          "OnnxSegmenter: " + file.string() + ": the model's " + std::to_string(info_.classes.size()) + " classes " +
          detail::class_list(info_.classes) + " differ from the " + std::to_string(params_.expected_classes.size()) +
          " expected classes " + detail::class_list(params_.expected_classes));
  }

  /// Throws unless images of `size` can be fed to the network.
  void check_size(const cv::Size& size, const char* who) const {
    const cv::Size in = input_size();
    if (size == in) return;
    const std::string desc = std::to_string(size.width) + "x" + std::to_string(size.height) + " vs network input " +
                             std::to_string(in.width) + "x" + std::to_string(in.height);
    detail::require(params_.resize_to_network,
                    std::string(who) +
                        ": image size differs from the network input size "
                        "(set OnnxParams::resize_to_network to resample)",
                    desc);
    const double a = static_cast<double>(size.width) / size.height;
    const double b = static_cast<double>(in.width) / in.height;
    detail::require(std::abs(a / b - 1.0) <= 0.01,
                    std::string(who) +
                        ": image aspect ratio differs from the network input's by "
                        "more than 1 %",
                    desc);
  }

  void check_camera() const {
    if (params_.camera_width_px == 0) return;
    check_size({params_.camera_width_px, params_.camera_height_px}, "OnnxSegmenter (camera)");
  }

  void load_network(const std::filesystem::path& onnx_file) {
    if (!std::filesystem::is_regular_file(onnx_file))
      throw std::invalid_argument("OnnxSegmenter: ONNX file not found: " + onnx_file.string());
    try {
      net_ = cv::dnn::readNetFromONNX(onnx_file.string());
    } catch (const cv::Exception& e) {
      throw std::invalid_argument("OnnxSegmenter: cannot load ONNX model " + onnx_file.string() + ": " + e.what());
    }
    if (net_.empty()) throw std::invalid_argument("OnnxSegmenter: ONNX model " + onnx_file.string() + " is empty");
    net_.setPreferableBackend(params_.dnn_backend);
    net_.setPreferableTarget(params_.dnn_target);
    // Shape inference (no forward pass): the output must be 1 x classes x H x W.
    const cv::dnn::MatShape in_shape{1, 3, info_.input_height_px, info_.input_width_px};
    cv::dnn::MatShape out_shape;
    try {
      const std::vector<int> outs = net_.getUnconnectedOutLayers();
      if (outs.size() != 1)
        throw std::invalid_argument("OnnxSegmenter: ONNX model " + onnx_file.string() + " has " +
                                    std::to_string(outs.size()) + " outputs, expected 1 (logits)");
      std::vector<cv::dnn::MatShape> in_shapes, out_shapes;
      net_.getLayerShapes(in_shape, outs.front(), in_shapes, out_shapes);
      if (!out_shapes.empty()) out_shape = out_shapes.front();
    } catch (const cv::Exception& e) {
      throw std::invalid_argument("OnnxSegmenter: ONNX model " + onnx_file.string() + " does not take a 1x3x" +
                                  std::to_string(info_.input_height_px) + "x" + std::to_string(info_.input_width_px) +
                                  " input: " + e.what());
    }
    const cv::Size net_out = output_size();
    const cv::dnn::MatShape expected{1, num_classes(), net_out.height, net_out.width};
    if (out_shape != expected) {
      std::string got;
      for (int d : out_shape) {
        if (!got.empty()) got += 'x';
        got += std::to_string(d);
      }
      throw std::invalid_argument("OnnxSegmenter: ONNX model " + onnx_file.string() + " outputs " + got +
                                  ", expected 1x" + std::to_string(num_classes()) + "x" +
                                  std::to_string(net_out.height) + "x" + std::to_string(net_out.width) +
                                  " (classes x input size / output stride from the metadata)");
    }
  }

  void check_image(const Image& image) const {
    detail::require(!image.bgr.empty(),
                    "OnnxSegmenter: the image has no RGB (Image::bgr is empty, e.g. a "
                    "field without an image); ERFNet segments RGB images only",
                    "empty rgb");
    detail::require(image.bgr.type() == CV_8UC3, "OnnxSegmenter: Image::bgr must be 8-bit 3-channel BGR (CV_8UC3)",
                    "type " + std::to_string(image.bgr.type()));
    detail::require(image.bgr.cols == image.width_px && image.bgr.rows == image.height_px,
                    "OnnxSegmenter: Image::bgr size differs from width_px x height_px",
                    std::to_string(image.bgr.cols) + "x" + std::to_string(image.bgr.rows) + " vs " +
                        std::to_string(image.width_px) + "x" + std::to_string(image.height_px));
    check_size(image.bgr.size(), "OnnxSegmenter (image)");
  }

  /// NCHW float blob, `(v / 255 - mean) / std` in the network's channel order.
  cv::Mat to_blob(const cv::Mat& bgr) const {
    const int h = bgr.rows, w = bgr.cols;
    const int shape[] = {1, 3, h, w};
    cv::Mat blob(4, shape, CV_32F);
    std::array<float*, 3> dst{};
    for (int k = 0; k < 3; ++k) dst[static_cast<std::size_t>(k)] = blob.ptr<float>(0, k);
    // Network channel k reads BGR channel src[k].
    const std::array<int, 3> src = info_.rgb_order ? std::array<int, 3>{2, 1, 0} : std::array<int, 3>{0, 1, 2};
    for (int r = 0; r < h; ++r) {
      const auto* p = bgr.ptr<std::uint8_t>(r);
      for (int x = 0; x < w; ++x)
        for (std::size_t k = 0; k < 3; ++k) {
          const float v = static_cast<float>(p[3 * x + src[k]]) / 255.0f;
          dst[k][static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(x)] =
              (v - info_.mean[k]) / info_.std[k];
        }
    }
    return blob;
  }

  /// 255 where all three channels are 0.
  static cv::Mat no_data_mask(const cv::Mat& bgr) {
    cv::Mat mask;
    cv::inRange(bgr, cv::Scalar(0, 0, 0), cv::Scalar(0, 0, 0), mask);
    return mask;
  }

  Params params_;
  OnnxModelInfo info_;
  cv::dnn::Net net_;
};

static_assert(SegmentationBackend<OnnxSegmenter>);
static_assert(SegmentsWithProbabilities<OnnxSegmenter>);

/// The names before adaptseg 0.3, kept for one version (they go in 0.4).
using ErfnetSegmenter [[deprecated("renamed adaptseg::OnnxSegmenter in adaptseg 0.3")]] = OnnxSegmenter;
using ErfnetParams [[deprecated("renamed adaptseg::OnnxParams in adaptseg 0.3")]] = OnnxParams;
using ErfnetModelInfo [[deprecated("renamed adaptseg::OnnxModelInfo in adaptseg 0.3")]] = OnnxModelInfo;

}  // namespace adaptseg
