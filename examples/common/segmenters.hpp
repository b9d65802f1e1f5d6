#pragma once
// Choosing the segmentation backend by name (--segmenter oracle|network --network PATH) for
// the example programs. Not part of the library.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/erfnet/network_identity.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/sim/cached_backend.hpp>
#include <adaptseg/vision/any_backend.hpp>
#include <adaptseg/vision/calibration.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include "old_spelling.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <initializer_list>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::examples {

/// The backend options shared by adaptseg_mission, adaptseg_calibrate and adaptseg_evaluate.
struct SegmenterOptions {
  std::string name = "oracle";
  std::filesystem::path network;     ///< network: model directory, or the .onnx (metadata: same stem .yaml)
  int threads = 0;                   ///< network: OpenCV threads (0: OpenCV's default)
  std::filesystem::path cache_root;  ///< network: where calibration keeps segmentations on disk (empty: nowhere)
  /// network, calibration: networks for the training fields --network was trained on, each such
  /// field segmented by the first of them that never saw it (cross-fitting, calibrate()).
  std::vector<std::filesystem::path> calibration_networks;
  /// network, calibration: each training field --network was trained on segmented by every
  /// calibration network that never saw it, one calibration field per network (their folds in
  /// the search leave the field's every copy out), instead of by the first only.
  bool calibration_network_each = false;

  void add_to(CLI::App& app) {
    accept_old_value(app.add_option("--segmenter", name,
                                    "segmentation backend: oracle (ground truth, simulation only) or network (an ONNX "
                                    "network or an ensemble of them, --network)"),
                     "erfnet", "network")
        ->check(CLI::IsMember({"oracle", "network"}))
        ->capture_default_str();
    CLI::Option* net =
        app.add_option("--network", network,
                       "network of --segmenter network (the ONNX backend): a directory with model.onnx + model.yaml, "
                       "an .onnx file with its .yaml next to it (examples/models/erfnet-dubai, "
                       "examples/models/mobilenetv2-dubai), or an ensemble directory with ensemble.yaml "
                       "(examples/models/ensemble-dubai: the mean of its members' probabilities)");
    accept_old_spelling(app, net, "--model-file", network);
    app.add_option("--threads", threads, "network: OpenCV threads (0: OpenCV's default; at most 256)")
        ->check(CLI::Range(0, 256))
        ->capture_default_str();
    app.add_option("--segmentation-cache", cache_root,
                   "network: keep calibration's segmentations on disk below this directory (one folder per network "
                   "and weights), so that calibrations over the same fields segment each image once; missions "
                   "always segment (their time is measured)");
  }

  /// The calibrating programs' --calibration-network (cross-fitting), refused together with any
  /// of `excludes`.
  void add_calibration_networks_to(CLI::App& app, std::initializer_list<CLI::Option*> excludes = {}) {
    CLI::Option* current =
        app.add_option("--calibration-network", calibration_networks,
                       "ERFNet, calibration (repeatable): networks of --network's recipe for the training fields it "
                       "was trained on (training.fields of its model.yaml), each such field segmented by the first of "
                       "them that was not trained on it: a network knows its training fields so well that, calibrated "
                       "there, the decision learns that flying lower gains little (cross-fitting; the missions fly "
                       "--network)");
    accept_old_spelling(app, current, "--calibration-model-file", calibration_networks);
    CLI::Option* each = app.add_flag(
        "--calibration-network-each", calibration_network_each,
        "calibration: each such field segmented by every --calibration-network that never saw it, one calibration "
        "field per network (the search's fold of a field leaves its every copy out), not by the first only: more "
        "looks of networks on ground they never trained on");
    each->needs(current);
    for (CLI::Option* e : excludes) {
      current->excludes(e);
      each->excludes(e);
    }
  }

  /// Where calibration keeps the network's segmentations (--segmentation-cache), if anywhere:
  /// a folder named by the network and the hash of its files (network_digest()).
  [[nodiscard]] std::optional<std::filesystem::path> calibration_cache() const {
    if (name != "network" || cache_root.empty()) return std::nullopt;
    return cache_root / network_digest(network);
  }

  /// @throws std::invalid_argument for a model file given to the oracle or missing for ERFNet.
  void validate() const {
    if (name == "network" && network.empty())
      throw std::invalid_argument("--segmenter network needs --network (e.g. examples/models/mobilenetv2-dubai)");
    if (name == "oracle" && !network.empty())
      throw std::invalid_argument("--network applies to --segmenter network only");
    if (name == "oracle" && !calibration_networks.empty())
      throw std::invalid_argument("--calibration-network applies to --segmenter network only");
  }

  /// Per training field, the network that segments it in calibration: --network where it was
  /// not trained on the field, else the first --calibration-network that was not (empty path:
  /// --network). Without --calibration-network, --network for every field.
  /// @throws std::invalid_argument for a network whose metadata names no training fields (it
  ///         cannot be told whether it saw a field), or a field no given network is new to.
  /// With --calibration-network-each, `fields` gains a copy of such a field per further network
  /// that never saw it, each copy after the field, and the result names one network per entry;
  /// `grounds`, where given, receives each entry's ground (CalibrationOptions::field_grounds:
  /// the index of the field's first entry).
  [[nodiscard]] std::vector<std::filesystem::path> network_per_field(
      std::vector<Field>& fields, std::vector<std::size_t>* grounds = nullptr) const {
    if (grounds) grounds->clear();
    if (calibration_networks.empty()) return std::vector<std::filesystem::path>(fields.size());
    const auto trained_on = [](const std::filesystem::path& file, const char* flag) {
      std::vector<std::string> t = network_training_fields(file);
      if (t.empty())
        throw std::invalid_argument(std::string("--calibration-network: ") + flag + " " + file.string() +
                                    " names no training fields (training.fields in its model.yaml), so whether it "
                                    "saw a calibration field cannot be told");
      return t;
    };
    const auto knows = [](const std::vector<std::string>& trained, const std::string& field) {
      return std::find(trained.begin(), trained.end(), field) != trained.end();
    };
    const std::vector<std::string> mission = trained_on(network, "--network");
    std::vector<std::vector<std::string>> pool;
    for (const auto& file : calibration_networks) pool.push_back(trained_on(file, "network"));
    std::vector<Field> expanded;
    std::vector<std::filesystem::path> networks;
    for (Field& f : fields) {
      // A part of a field ("dubai-tile-1[0,0,0.5,1]", Field::sub_field) is that field's ground.
      const std::string full = f.name();
      const std::string ground = full.back() == ']' ? full.substr(0, full.rfind('[')) : full;
      std::vector<std::filesystem::path> new_to;  // the calibration networks that never saw it
      if (knows(mission, ground))
        for (std::size_t j = 0; j < pool.size(); ++j)
          if (!knows(pool[j], ground)) new_to.push_back(calibration_networks[j]);
      if (knows(mission, ground) && new_to.empty())
        throw std::invalid_argument("--calibration-network: every network given was trained on calibration field '" +
                                    full + "' (as --network " + network.string() + " was): give one that never saw it");
      if (new_to.empty()) new_to.emplace_back();  // --network never saw it
      if (!calibration_network_each) new_to.resize(1);
      const std::size_t at = expanded.size();
      expanded.push_back(std::move(f));
      for (std::size_t j = 1; j < new_to.size(); ++j) {
        Field copy = expanded[at];
        expanded.push_back(std::move(copy));
      }
      networks.insert(networks.end(), new_to.begin(), new_to.end());
      if (grounds && calibration_network_each) grounds->insert(grounds->end(), new_to.size(), at);
    }
    fields = std::move(expanded);  // without --calibration-network-each, `grounds` stays empty: each its own
    return networks;
  }

  /// Calls `f(backend)` with the chosen backend built for `field` seen by `camera`, behind
  /// AnyBackend (one type for every backend: the planner and calibration are compiled once; a
  /// virtual call per image costs nothing next to a segmentation). The network's classes must be
  /// the field's; a camera image of another size than the network's input, with the same aspect
  /// ratio, is resampled to it, as the MobileNetV2 model's 512x384 input needs for the 480x360
  /// camera.
  template <class F>
  decltype(auto) with_backend(const Field& field, const CameraModel::Params& camera, F&& f) const {
    validate();
    if (name == "oracle") {
      OracleSegmenter oracle(field.num_classes());
      AnyBackend any(oracle);
      return std::forward<F>(f)(any);
    }
    return with_network(network, network_params(field, camera), std::forward<F>(f));
  }

  /// The ONNX backend's parameters for `field` seen by `camera`: --threads, and the camera image
  /// resampled to the network's input (see with_backend()).
  [[nodiscard]] OnnxParams network_params(const Field& field, const CameraModel::Params& camera) const {
    OnnxParams p = OnnxSegmenter::for_field(field, CameraModel(camera));
    p.num_threads = threads;
    p.resize_to_network = true;
    return p;
  }
};

/// To stderr, for a cross-fitted model: which network segmented each calibration field.
inline void print_field_segmenters(const DecisionModel& model) {
  for (std::size_t k = 0; k < model.field_segmenters.size(); ++k)
    std::fprintf(stderr, "  calibration field %s segmented by %s\n", model.calibration_fields[k].c_str(),
                 model.field_segmenters[k].c_str());
}

/// adaptseg::calibrate for the programs: every field segmented by `backend` (--network, cached in
/// memory and in --segmentation-cache if given: calibration flies the same waypoints many times,
/// at its declared per-image time, so a cache hit changes no number, and a network backend is
/// the slow part) or, where `networks` (SegmenterOptions::network_per_field(fields), resolved
/// once by the program before any work) names one, by that network (built for `fields.front()`
/// seen by the missions' camera, cached in its own folder of --segmentation-cache).
/// Compiled once, in segmenters.cpp (the adaptseg_examples_common library).
/// @throws std::invalid_argument if `networks` does not hold one entry per field.
CalibrationResult calibrate_fields(const SegmenterOptions& segmenter, std::span<const Field> fields,
                                   std::span<const std::filesystem::path> networks, AnyBackend& backend,
                                   const CalibrationOptions& options);

}  // namespace adaptseg::examples
