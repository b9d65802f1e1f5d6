#pragma once
/// @file
/// A network's metadata file (model.yaml beside its ONNX export, written by
/// `python/adaptseg_tools/train_segnet.py`): what OnnxSegmenter reads of it (`OnnxModelInfo`) and the
/// reader, which checks it without loading the network (docs/data_format.md). CMake target
/// adaptseg::erfnet (yaml-cpp only; no OpenCV DNN).

#include <adaptseg/vision/detail/yaml_io.hpp>

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <filesystem>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

namespace detail {
/// Class names as "[a, b, c]", for messages about class sets.
inline std::string class_list(const std::vector<std::string>& classes) {
  std::string s;
  for (const auto& x : classes) s += (s.empty() ? "" : ", ") + x;
  return "[" + s + "]";
}
}  // namespace detail

/// What a model's metadata YAML (model.yaml) says; read by OnnxSegmenter. The keys below are
/// read (`classes`, `input.{width, height, channel_order, mean, std}`, optional `output.stride`,
/// `width`, `temperature`, `training.fields`); the others the export writes (the rest of
/// training, validation, check ...) are provenance for people and are not read.
struct OnnxModelInfo {
  std::vector<std::string> classes;  ///< class names, label-index order
  int input_width_px = 0;            ///< network input W [px] (multiple of 8)
  int input_height_px = 0;           ///< network input H [px] (multiple of 8)
  bool rgb_order = true;             ///< true: the network takes RGB; false: BGR
  std::array<float, 3> mean{};       ///< per input channel, in the network's channel order, on v/255
  std::array<float, 3> std{};        ///< per input channel, > 0
  int output_stride = 1;             ///< logits are input / output_stride per side (`output.stride`, default 1)
  double width_multiplier = 0.0;     ///< informational (ERFNet; 1.0 = the paper's 16/64/128 channels)
  /// T > 0 of the probabilities softmax(logits / T) (`temperature`, default 1): fitted on the
  /// network's validation data so that its confidence matches its accuracy
  /// (adaptseg_fit_temperature, examples/tools/fit_temperature.cpp); labels do not depend on it.
  double temperature = 1.0;
  /// The fields the network was trained on, by name (`training.fields`, optional; empty: not
  /// stated): a network maps them nearly as well from high up as from low down, so a decision
  /// calibrated there learns that flying lower gains little (calibrate(), cross-fitting).
  std::vector<std::string> training_fields;
};

namespace detail {
[[noreturn]] inline void onnx_meta_error(const std::filesystem::path& file, const std::string& what) {
  throw std::invalid_argument("OnnxSegmenter: " + file.string() + ": " + what);
}
}  // namespace detail

/// Reads and checks a network's metadata `file` (OnnxSegmenter::read_model_info, and its
/// constructor).
/// @throws std::invalid_argument naming the file and the key for a missing file, YAML that is not
///         a mapping, a missing or mistyped key, or a value out of range (1 to 255 classes, an
///         input size a positive multiple of 8, channel order RGB or BGR, std > 0, a stride that
///         divides the input, a temperature in [0.01, 100]).
[[nodiscard]] inline OnnxModelInfo read_onnx_model_info(const std::filesystem::path& file) {
  if (!std::filesystem::is_regular_file(file))
    throw std::invalid_argument("OnnxSegmenter: metadata file not found: " + file.string());
  // The keys read below; the others (the rest of training, validation, check ...) are provenance.
  const std::string where = "OnnxSegmenter: " + file.string();
  const detail::YamlReader r(
      detail::yaml_mapping(where, "network metadata", [&] { return YAML::LoadFile(file.string()); }), where);
  OnnxModelInfo info;
  info.classes = r.texts("classes");
  if (info.classes.empty() || info.classes.size() > 255)
    detail::onnx_meta_error(
        file, "'classes' must be a list of 1 to 255 class names (got " + std::to_string(info.classes.size()) + ")");
  const detail::YamlReader input = r.map("input");
  info.input_width_px = static_cast<int>(input.integer("width", 8, 1 << 16));
  info.input_height_px = static_cast<int>(input.integer("height", 8, 1 << 16));
  if (info.input_width_px % 8 != 0 || info.input_height_px % 8 != 0)
    detail::onnx_meta_error(file, "input width and height must be positive multiples of 8 (got " +
                                      std::to_string(info.input_width_px) + "x" + std::to_string(info.input_height_px) +
                                      ")");
  const std::string order = input.text("channel_order");
  if (order != "RGB" && order != "BGR")
    detail::onnx_meta_error(file, "input.channel_order must be RGB or BGR (got '" + order + "')");
  info.rgb_order = order == "RGB";
  for (const char* key : {"mean", "std"}) {
    const bool std_dev = std::string(key) == "std";
    const std::vector<double> v = input.numbers(key);
    if (v.size() != 3) detail::onnx_meta_error(file, "'" + input.path(key) + "' must be a list of 3 numbers");
    for (std::size_t k = 0; k < 3; ++k) {
      if (std_dev && !(v[k] > 0.0))
        detail::onnx_meta_error(file, "input.std values must be > 0 (got " + std::to_string(v[k]) + ")");
      (std_dev ? info.std : info.mean)[k] = static_cast<float>(v[k]);
    }
  }
  if (r.has("output") && r.map("output").has("stride")) {
    info.output_stride = static_cast<int>(r.map("output").integer("stride", 1, 32));
    if (info.input_width_px % info.output_stride != 0 || info.input_height_px % info.output_stride != 0)
      detail::onnx_meta_error(file, "output.stride must divide the input width and height (got " +
                                        std::to_string(info.output_stride) + ")");
  }
  if (r.has("width")) info.width_multiplier = r.number("width");
  if (r.has("temperature")) {
    info.temperature = r.number("temperature");
    if (info.temperature < 0.01 || info.temperature > 100.0)
      detail::onnx_meta_error(
          file, "temperature must be a number in [0.01, 100] (got " + std::to_string(info.temperature) + ")");
  }
  if (r.has("training") && r.map("training").has("fields")) info.training_fields = r.map("training").texts("fields");
  return info;
}

}  // namespace adaptseg
