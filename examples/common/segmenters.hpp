#pragma once
// Choosing the segmentation backend by name (--segmenter oracle|erfnet --model-file PATH) for
// the example programs. Not part of the library.

#include <adaptseg/calibration.hpp>
#include <adaptseg/camera.hpp>
#include <adaptseg/erfnet_segmenter.hpp>
#include <adaptseg/field.hpp>
#include <adaptseg/lawnmower_planner.hpp>
#include <adaptseg/oracle_segmenter.hpp>
#include <adaptseg/segmentation_backend.hpp>
#include <adaptseg/simulated_sensor.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <map>
#include <tuple>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::examples {

/// Memoises a deterministic backend: a simulated image is identified by its footprint, its
/// yaw, its size and its RGB sums. For calibration, which flies the same waypoints many times,
/// and only with a fixed segmentation time per image (a cache hit takes no time, so a measured
/// time would be wrong). Gives probabilities where the backend does (computed, and kept, the
/// first time an image is asked for with them).
template <SegmentationBackend Backend>
class CachedBackend {
 public:
  explicit CachedBackend(Backend& inner) : inner_(inner) {}
  [[nodiscard]] std::string name() const { return inner_.name(); }
  [[nodiscard]] cv::Mat segment(const Image& image) {
    const Key key = key_of(image);
    if (const auto it = cache_.find(key); it != cache_.end()) return it->second.labels.clone();
    Segmentation s{inner_.segment(image), {}};
    cv::Mat labels = s.labels.clone();
    cache_.emplace(key, std::move(s));
    return labels;
  }
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image)
    requires SegmentsWithProbabilities<Backend>
  {
    const Key key = key_of(image);
    auto it = cache_.find(key);
    if (it == cache_.end() || it->second.probabilities.empty()) {
      Segmentation s = inner_.segment_with_probabilities(image);
      if (it == cache_.end())
        it = cache_.emplace(key, std::move(s)).first;
      else
        it->second = std::move(s);
    }
    Segmentation out{it->second.labels.clone(), {}};
    for (const cv::Mat& p : it->second.probabilities) out.probabilities.push_back(p.clone());
    return out;
  }

 private:
  using Key = std::tuple<int, int, int, int, double, int, int, double, double, double>;
  static Key key_of(const Image& image) {
    const cv::Scalar sum = image.rgb.empty() ? cv::Scalar() : cv::sum(image.rgb);
    return {image.footprint_px.x, image.footprint_px.y, image.footprint_px.width, image.footprint_px.height,
            image.yaw_deg, image.width_px, image.height_px, sum[0], sum[1], sum[2]};
  }
  Backend& inner_;
  std::map<Key, Segmentation> cache_;
};

/// adaptseg::calibrate with `backend` cached: calibration flies the same waypoints many times
/// (at its declared per-image time, so a cache hit changes no number), and a network backend
/// is the slow part.
template <SegmentationBackend Backend>
CalibrationResult calibrate_cached(std::span<const Field> fields, Backend& backend, const CalibrationOptions& options) {
  CachedBackend<Backend> cached(backend);
  return calibrate(fields, cached, options);
}

/// The backend options shared by adaptseg_mission, adaptseg_calibrate and adaptseg_evaluate.
struct SegmenterOptions {
  std::string name = "oracle";
  std::filesystem::path model_file;  ///< ERFNet: model directory, or the .onnx (metadata: same stem .yaml)
  int threads = 0;                   ///< ERFNet: OpenCV threads (0: OpenCV's default)

  void add_to(CLI::App& app) {
    app.add_option("--segmenter", name,
                   "segmentation backend: oracle (ground truth, simulation only) or erfnet (needs --model-file)")
        ->check(CLI::IsMember({"oracle", "erfnet"}))
        ->capture_default_str();
    app.add_option("--model-file", model_file,
                   "network of --segmenter erfnet (the ONNX backend): a directory with model.onnx + model.yaml, "
                   "or an .onnx file with its .yaml next to it (examples/models/erfnet-dubai, "
                   "examples/models/mobilenetv2-dubai)");
    app.add_option("--threads", threads, "ERFNet: OpenCV threads (0: OpenCV's default)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
  }

  /// @throws std::invalid_argument for a model file given to the oracle or missing for ERFNet.
  void validate() const {
    if (name == "erfnet" && model_file.empty())
      throw std::invalid_argument("--segmenter erfnet needs --model-file (e.g. examples/models/erfnet-dubai)");
    if (name == "oracle" && !model_file.empty())
      throw std::invalid_argument("--model-file applies to --segmenter erfnet only");
  }

  /// Calls `f(backend)` with the chosen backend built for `field` seen by `camera` (the
  /// network's classes must be the field's; a camera image of another size than the network's
  /// input, with the same aspect ratio, is resampled to it, as the MobileNetV2 model's 512x384
  /// input needs for the 480x360 camera).
  template <class F>
  decltype(auto) with_backend(const Field& field, const CameraModel::Params& camera, F&& f) const {
    validate();
    if (name == "oracle") {
      OracleSegmenter oracle(field.num_classes());
      return std::forward<F>(f)(oracle);
    }
    ErfnetParams p = ErfnetSegmenter::for_field(field, CameraModel(camera));
    p.num_threads = threads;
    p.resize_to_network = true;
    const bool dir = std::filesystem::is_directory(model_file);
    const std::filesystem::path onnx = dir ? model_file / "model.onnx" : model_file;
    std::filesystem::path metadata = onnx;
    metadata.replace_extension(".yaml");
    ErfnetSegmenter erfnet(onnx, metadata, std::move(p));
    return std::forward<F>(f)(erfnet);
  }
};

}  // namespace adaptseg::examples
