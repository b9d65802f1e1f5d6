#pragma once
// Choosing the segmentation backend by name (--segmenter oracle|erfnet --model-file PATH) for
// the example programs. Not part of the library.

#include <adaptseg/camera.hpp>
#include <adaptseg/erfnet_segmenter.hpp>
#include <adaptseg/field.hpp>
#include <adaptseg/oracle_segmenter.hpp>

#include <CLI/CLI.hpp>

#include <filesystem>
#include <stdexcept>
#include <string>
#include <utility>

namespace adaptseg::examples {

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
                   "ERFNet model: a directory with model.onnx + model.yaml, or an .onnx file with its .yaml "
                   "next to it (e.g. examples/models/erfnet-dubai)");
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
  /// ERFNet's classes must be the field's and its input size the camera's).
  template <class F>
  decltype(auto) with_backend(const Field& field, const CameraModel::Params& camera, F&& f) const {
    validate();
    if (name == "oracle") {
      OracleSegmenter oracle(field.num_classes());
      return std::forward<F>(f)(oracle);
    }
    ErfnetParams p = ErfnetSegmenter::for_field(field, CameraModel(camera));
    p.num_threads = threads;
    const bool dir = std::filesystem::is_directory(model_file);
    const std::filesystem::path onnx = dir ? model_file / "model.onnx" : model_file;
    std::filesystem::path metadata = onnx;
    metadata.replace_extension(".yaml");
    ErfnetSegmenter erfnet(onnx, metadata, std::move(p));
    return std::forward<F>(f)(erfnet);
  }
};

}  // namespace adaptseg::examples
