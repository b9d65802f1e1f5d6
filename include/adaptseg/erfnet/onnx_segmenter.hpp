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
#include <adaptseg/erfnet/detail/onnx_planes.hpp>
#include <adaptseg/erfnet/onnx_model_info.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
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
  /// Test-time coarser look [cm/px]; 0: off. > 0: where an image is finer than this (its
  /// Image::gsd_cm), the network also segments it resampled to min(this, 2 x its GSD) (the input
  /// shrunk by that ratio, each side a multiple of 32 px, INTER_AREA), and the probabilities are
  /// the mean of the passes (with test_time_mirror, of the mirrored passes too), labels its
  /// argmax. An image at 5 cm/px then also counts what the network makes of the same ground at
  /// 10 (coarse 10): on the Dubai tiles the leave-one-tile-out networks never saw, the mean maps
  /// 5 cm/px images better on five tiles of six, though flown it made no better descents
  /// (docs/journal/2026-12-coarse.md). The network must take the smaller input (fully
  /// convolutional; checked at construction); images at or coarser than this get one pass.
  double test_time_coarse_gsd_cm = 0.0;
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
/// OnnxParams::test_time_mirror a second pass over the mirrored image, with
/// OnnxParams::test_time_coarse_gsd_cm one over the image shrunk to a coarser GSD: probabilities
/// are the mean of the passes, labels its argmax.
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
    if (params_.test_time_mirror || coarse_gsd_cm(image) > 0.0) return segment_with_probabilities(image).labels;
    cv::Mat labels = detail::onnx_argmax(logits(image));
    if (params_.black_is_no_data) labels.setTo(cv::Scalar(image.ignore_label), detail::onnx_no_data_mask(image.bgr));
    return labels;
  }

  /// segment() and probabilities() from one forward pass (more with OnnxParams::test_time_mirror
  /// and test_time_coarse_gsd_cm: the mean of the passes' probabilities) (SegmentsWithProbabilities).
  /// @throws std::invalid_argument as segment(), and for an image without a GSD
  ///         (Image::gsd_cm <= 0) when test_time_coarse_gsd_cm is set.
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) {
    Segmentation s;
    const double coarse = coarse_gsd_cm(image);
    if (!params_.test_time_mirror && coarse == 0.0) {
      s.probabilities = logits(image);
      s.labels = detail::onnx_argmax(s.probabilities);
      detail::onnx_softmax_in_place(s.probabilities, info_.temperature);
    } else {
      check_image(image);
      std::vector<cv::Size> inputs{input_size()};
      if (coarse > 0.0) inputs.push_back(coarse_input_size(image.gsd_cm / coarse));
      int passes = 0;
      for (const cv::Size& in : inputs)
        for (const bool flip : {false, true}) {
          if (flip && !params_.test_time_mirror) continue;
          std::vector<cv::Mat> p = pass_probabilities(image, in, flip);
          if (passes++ == 0)
            s.probabilities = std::move(p);
          else
            for (std::size_t c = 0; c < p.size(); ++c) s.probabilities[c] += p[c];
        }
      for (auto& p : s.probabilities) p *= 1.0 / passes;
      s.labels = detail::onnx_argmax(s.probabilities);
    }
    if (params_.black_is_no_data) {
      const cv::Mat mask = detail::onnx_no_data_mask(image.bgr);
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
    return forward(image.bgr, input_size(), image.bgr.size());
  }

  /// The GSD [cm/px] of the coarser pass OnnxParams::test_time_coarse_gsd_cm adds for `image`:
  /// min(that, 2 x the image's GSD) where it is at least 10 % coarser than the image, else 0 (one
  /// pass at the network's input size).
  /// @throws std::invalid_argument for an image without a GSD (Image::gsd_cm <= 0) when it is set.
  [[nodiscard]] double coarse_gsd_cm(const Image& image) const {
    if (params_.test_time_coarse_gsd_cm <= 0.0) return 0.0;
    detail::require(std::isfinite(image.gsd_cm) && image.gsd_cm > 0.0,
                    "OnnxSegmenter: OnnxParams::test_time_coarse_gsd_cm needs the image's GSD (Image::gsd_cm > 0)",
                    image.gsd_cm);
    const double g = std::min(params_.test_time_coarse_gsd_cm, 2.0 * image.gsd_cm);
    return g >= 1.1 * image.gsd_cm ? g : 0.0;
  }

 private:
  /// The network's input size scaled by `scale` (<= 1), each side rounded to a multiple of 32 px
  /// (at least 32): a size every encoder's strides divide.
  [[nodiscard]] cv::Size coarse_input_size(double scale) const {
    const auto side = [&](int px) { return std::max(32, static_cast<int>(std::lround(px * scale / 32.0)) * 32); };
    return {side(info_.input_width_px), side(info_.input_height_px)};
  }

  /// softmax(logits / T) of one pass over `image` fed at input size `in`, left-right mirrored
  /// (and its planes flipped back) where `flip`; planes at the image's size.
  [[nodiscard]] std::vector<cv::Mat> pass_probabilities(const Image& image, cv::Size in, bool flip) {
    cv::Mat bgr;  // a new buffer where flipped: `image` keeps its pixels
    if (flip)
      cv::flip(image.bgr, bgr, 1);
    else
      bgr = image.bgr;
    std::vector<cv::Mat> planes = forward(bgr, in, bgr.size());
    detail::onnx_softmax_in_place(planes, info_.temperature);
    for (auto& p : planes)
      if (flip) {
        cv::Mat back;
        cv::flip(p, back, 1);
        p = back;
      }
    return planes;
  }

  /// The network's logits for `bgr` resampled to input size `in` (INTER_AREA shrinking,
  /// INTER_LINEAR enlarging), one CV_32FC1 plane per class resampled bilinearly to `out_size`.
  [[nodiscard]] std::vector<cv::Mat> forward(const cv::Mat& bgr, cv::Size in, cv::Size out_size) {
    cv::Mat rgb = bgr;
    if (rgb.size() != in) cv::resize(bgr, rgb, in, 0, 0, bgr.cols > in.width ? cv::INTER_AREA : cv::INTER_LINEAR);
    net_.setInput(detail::onnx_blob(rgb, info_));
    cv::Mat out = net_.forward();
    const cv::Size net_out(in.width / info_.output_stride, in.height / info_.output_stride);
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
    detail::require(std::isfinite(params_.test_time_coarse_gsd_cm) && params_.test_time_coarse_gsd_cm >= 0.0,
                    "OnnxParams: test_time_coarse_gsd_cm must be 0 (off) or a GSD > 0 [cm/px]",
                    params_.test_time_coarse_gsd_cm);
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
    check_output_shape(onnx_file, input_size());
    // The coarser look's smallest input (half the input size) must work as well.
    if (params_.test_time_coarse_gsd_cm > 0.0) check_output_shape(onnx_file, coarse_input_size(0.5));
  }

  /// Shape inference (no forward pass): for a 1 x 3 x in input the output must be 1 x classes x
  /// (in / the output stride).
  void check_output_shape(const std::filesystem::path& onnx_file, cv::Size in) {
    const cv::dnn::MatShape in_shape{1, 3, in.height, in.width};
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
                                  std::to_string(in.height) + "x" + std::to_string(in.width) + " input" +
                                  (in == input_size() ? "" : " (OnnxParams::test_time_coarse_gsd_cm)") + ": " +
                                  e.what());
    }
    const cv::Size net_out(in.width / info_.output_stride, in.height / info_.output_stride);
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
