#pragma once
// Choosing the segmentation backend by name (--segmenter oracle|erfnet --network PATH) for
// the example programs. Not part of the library.

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/vision/any_backend.hpp>
#include <adaptseg/vision/calibration.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include "old_spelling.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <initializer_list>
#include <iterator>
#include <map>
#include <memory>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

namespace adaptseg::examples {

/// FNV-1a, 64 bits, over `bytes`, continuing from `h`: names cached segmentations and models.
inline std::uint64_t fnv1a(const void* bytes, std::size_t n, std::uint64_t h = 14695981039346656037ull) {
  const auto* p = static_cast<const unsigned char*>(bytes);
  for (std::size_t k = 0; k < n; ++k) h = (h ^ p[k]) * 1099511628211ull;
  return h;
}

/// The hash (FNV-1a over their bytes, in order) of `files`, as 16 hex digits.
inline std::string files_hash(const std::vector<std::filesystem::path>& files) {
  std::uint64_t h = 14695981039346656037ull;
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    h = fnv1a(bytes.data(), bytes.size(), h);
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}

/// A model directory's (or ONNX file's) identity for a segmentation cache: its name and the hash
/// of its ONNX file and metadata (the temperature included), e.g. "mobilenetv2-dubai-3fa2...".
inline std::string model_digest(const std::filesystem::path& onnx, const std::filesystem::path& metadata) {
  const std::filesystem::path dir = onnx.parent_path();
  return (dir.filename().empty() ? std::string("model") : dir.filename().string()) + "-" + files_hash({onnx, metadata});
}

/// An ensemble directory's identity: its name and the hash of its ensemble.yaml and of every
/// member's ONNX file and metadata, in the file's order (a member retrained or re-tempered, or
/// weights changed, is another ensemble).
inline std::string ensemble_digest(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files{dir / "ensemble.yaml"};
  for (const EnsembleMember& m : read_ensemble_file(dir)) {
    files.push_back(m.model_dir / "model.onnx");
    files.push_back(m.model_dir / "model.yaml");
  }
  const std::filesystem::path name = dir.filename().empty() ? dir.parent_path().filename() : dir.filename();
  return name.string() + "-" + files_hash(files);
}

/// --network's ONNX file and metadata: a directory with model.onnx + model.yaml, or an .onnx
/// file with its .yaml next to it.
inline std::pair<std::filesystem::path, std::filesystem::path> model_paths(const std::filesystem::path& model_file) {
  const bool dir = std::filesystem::is_directory(model_file);
  const std::filesystem::path onnx = dir ? model_file / "model.onnx" : model_file;
  std::filesystem::path metadata = onnx;
  metadata.replace_extension(".yaml");
  return {onnx, metadata};
}

/// --network's identity (a network's model_digest(), an ensemble directory's ensemble_digest()).
inline std::string model_file_digest(const std::filesystem::path& model_file) {
  if (EnsembleSegmenter::is_ensemble_dir(model_file)) return ensemble_digest(model_file);
  const auto [onnx, metadata] = model_paths(model_file);
  return model_digest(onnx, metadata);
}

/// The name a network backend goes by in results and decision models: "erfnet:" (one network)
/// or "ensemble:" (an ensemble directory) and its identity (model_file_digest(): its folder's
/// name and the hash of its weights and metadata), so that a model calibrated with one network
/// is refused with another (or with the same network at another temperature), whatever their
/// folders are called.
inline std::string network_name(const std::filesystem::path& model_file) {
  return (EnsembleSegmenter::is_ensemble_dir(model_file) ? "ensemble:" : "erfnet:") + model_file_digest(model_file);
}

/// Calls `f(backend)` with the network backend of `model_file` behind AnyBackend: an
/// EnsembleSegmenter for an ensemble directory (ensemble.yaml), else an OnnxSegmenter
/// (model_paths()); named by network_name() and built with `params` otherwise. One backend type
/// for every network, so that a program instantiates the planner and calibration once.
template <class F>
decltype(auto) with_network(const std::filesystem::path& model_file, OnnxParams params, F&& f) {
  params.name = network_name(model_file);
  if (EnsembleSegmenter::is_ensemble_dir(model_file)) {
    EnsembleSegmenter ensemble(model_file, std::move(params));
    AnyBackend any(ensemble);
    return std::forward<F>(f)(any);
  }
  const auto [onnx, metadata] = model_paths(model_file);
  OnnxSegmenter network(onnx, metadata, std::move(params));
  AnyBackend any(network);
  return std::forward<F>(f)(any);
}

/// Memoises a deterministic backend: a simulated image is identified by its footprint, its
/// yaw, its size and its RGB sums. For calibration, which flies the same waypoints many times,
/// and only with a fixed segmentation time per image (a cache hit takes no time, so a measured
/// time would be wrong). Gives probabilities where the backend does; they are kept (3.5 MB an
/// image for 5 classes at 480 x 360) only for images asked for with them a second time, as the
/// top-level images are by every mission of a calibration, not for the many finer images its
/// samples look at once. With a directory, the segmentations are also kept on disk there (one
/// file per image: labels, and the probabilities where they are kept), so that calibrations
/// with the same backend over the same fields (a sweep's runs) segment each image once; the
/// directory must be the backend's own (model_digest()).
template <SegmentationBackend Backend>
class CachedBackend {
 public:
  explicit CachedBackend(Backend& inner, std::optional<std::filesystem::path> dir = std::nullopt)
      : inner_(inner), dir_(std::move(dir)) {
    if (dir_) std::filesystem::create_directories(*dir_);
  }
  [[nodiscard]] std::string name() const { return inner_.name(); }
  [[nodiscard]] cv::Mat segment(const Image& image) { return lookup(image, false).labels; }
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) requires
      SegmentsWithProbabilities<Backend> {
    return lookup(image, true);
  }

 private:
  using Key = std::tuple<int, int, int, int, double, int, int, double, double, double>;
  struct Entry {
    Segmentation segmentation;
    int probability_asks = 0;
  };
  static Key key_of(const Image& image) {
    const cv::Scalar sum = image.bgr.empty() ? cv::Scalar() : cv::sum(image.bgr);
    return {image.footprint_px.x,
            image.footprint_px.y,
            image.footprint_px.width,
            image.footprint_px.height,
            image.yaw_deg,
            image.width_px,
            image.height_px,
            sum[0],
            sum[1],
            sum[2]};
  }

  static Segmentation copy(const Segmentation& s) {
    Segmentation out{s.labels.clone(), {}};
    for (const cv::Mat& p : s.probabilities) out.probabilities.push_back(p.clone());
    for (const cv::Mat& v : s.member_votes) out.member_votes.push_back(v.clone());
    return out;
  }

  /// The image's segmentation (a copy), with probabilities if `probabilities` (and the backend
  /// gives them): from memory, from disk, or computed.
  Segmentation lookup(const Image& image, bool probabilities) {
    const Key key = key_of(image);
    Entry& e = cache_[key];
    const bool known = !e.segmentation.labels.empty();
    if (known && (!probabilities || !e.segmentation.probabilities.empty())) return copy(e.segmentation);
    const bool keep = probabilities && ++e.probability_asks >= 2;
    std::optional<Segmentation> s = load(key);
    if (!s || (probabilities && s->probabilities.empty())) {
      if constexpr (SegmentsWithProbabilities<Backend>)
        s = probabilities ? inner_.segment_with_probabilities(image) : Segmentation{inner_.segment(image), {}};
      else
        s = Segmentation{inner_.segment(image), {}};
      // On disk: the labels the first time, the probabilities once they are kept.
      if (!known || keep) store(key, keep ? *s : Segmentation{s->labels, {}});
    }
    if (keep || !known) e.segmentation = keep ? copy(*s) : Segmentation{s->labels.clone(), {}};
    return std::move(*s);
  }

  [[nodiscard]] std::filesystem::path file_of(const Key& key) const {
    const auto& [x, y, w, h, yaw, iw, ih, b, g, r] = key;
    std::uint64_t hash = 14695981039346656037ull;
    for (int v : {x, y, w, h, iw, ih}) hash = fnv1a(&v, sizeof v, hash);
    for (double v : {yaw, b, g, r}) hash = fnv1a(&v, sizeof v, hash);
    char name[32];
    std::snprintf(name, sizeof name, "%016llx.seg", static_cast<unsigned long long>(hash));
    return *dir_ / name;
  }

  /// File: kMagic, rows, cols, probability planes, member-vote planes (int32), the labels (rows x
  /// cols bytes), the probability planes, then the vote planes (float32). Files written before
  /// the member votes (no magic: rows, cols, planes) are read as having none.
  static constexpr std::int32_t kMagic = 0x32475341;  // "ASG2"

  [[nodiscard]] std::optional<Segmentation> load(const Key& key) const {
    if (!dir_) return std::nullopt;
    std::ifstream in(file_of(key), std::ios::binary);
    std::int32_t first[3] = {0, 0, 0};
    if (!in.read(reinterpret_cast<char*>(first), sizeof first)) return std::nullopt;
    // head: rows, cols, probability planes, vote planes (none in the format before the votes).
    std::int32_t head[4] = {first[0], first[1], first[2], 0};
    if (first[0] == kMagic) {
      head[0] = first[1];
      head[1] = first[2];
      if (!in.read(reinterpret_cast<char*>(head + 2), 2 * sizeof(std::int32_t))) return std::nullopt;
    }
    const auto& [x, y, w, h, yaw, iw, ih, b, g, r] = key;
    if (head[0] != ih || head[1] != iw || head[2] < 0 || head[2] > 255 || head[3] < 0 || head[3] > 255)
      return std::nullopt;
    Segmentation s{cv::Mat(ih, iw, CV_8UC1), {}};
    if (!in.read(reinterpret_cast<char*>(s.labels.data), static_cast<std::streamsize>(s.labels.total())))
      return std::nullopt;
    for (int k = 0; k < head[2] + head[3]; ++k) {
      cv::Mat p(ih, iw, CV_32FC1);
      if (!in.read(reinterpret_cast<char*>(p.data), static_cast<std::streamsize>(p.total() * sizeof(float))))
        return std::nullopt;
      (k < head[2] ? s.probabilities : s.member_votes).push_back(std::move(p));
    }
    return s;
  }

  /// Written to a temporary file and renamed, so that concurrent runs never read half a file.
  void store(const Key& key, const Segmentation& s) const {
    if (!dir_) return;
    const std::filesystem::path target = file_of(key);
    std::filesystem::path tmp = target;
    tmp += ".tmp" + std::to_string(reinterpret_cast<std::uintptr_t>(this));
    {
      std::ofstream out(tmp, std::ios::binary);
      const std::int32_t head[5] = {kMagic, s.labels.rows, s.labels.cols,
                                    static_cast<std::int32_t>(s.probabilities.size()),
                                    static_cast<std::int32_t>(s.member_votes.size())};
      out.write(reinterpret_cast<const char*>(head), sizeof head);
      const cv::Mat labels = s.labels.isContinuous() ? s.labels : s.labels.clone();
      out.write(reinterpret_cast<const char*>(labels.data), static_cast<std::streamsize>(labels.total()));
      for (const auto* planes : {&s.probabilities, &s.member_votes})
        for (const cv::Mat& p0 : *planes) {
          const cv::Mat p = p0.isContinuous() ? p0 : p0.clone();
          out.write(reinterpret_cast<const char*>(p.data), static_cast<std::streamsize>(p.total() * sizeof(float)));
        }
      if (!out) return;  // a full disk costs time, not correctness
    }
    std::error_code ec;
    std::filesystem::rename(tmp, target, ec);
    if (ec) std::filesystem::remove(tmp, ec);
  }

  Backend& inner_;
  std::optional<std::filesystem::path> dir_;
  std::map<Key, Entry> cache_;
};

/// The fields the network of `model_file` was trained on (its metadata's training.fields; an
/// ensemble's: every member's), empty where the metadata names none.
inline std::vector<std::string> network_training_fields(const std::filesystem::path& model_file) {
  std::vector<std::filesystem::path> metadata;
  if (EnsembleSegmenter::is_ensemble_dir(model_file)) {
    for (const EnsembleMember& m : read_ensemble_file(model_file)) metadata.push_back(model_paths(m.model_dir).second);
  } else {
    metadata.push_back(model_paths(model_file).second);
  }
  std::vector<std::string> out;
  for (const auto& file : metadata)
    for (std::string& f : OnnxSegmenter::read_model_info(file).training_fields)
      if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(std::move(f));
  return out;
}

/// The backend options shared by adaptseg_mission, adaptseg_calibrate and adaptseg_evaluate.
struct SegmenterOptions {
  std::string name = "oracle";
  std::filesystem::path network;     ///< network: model directory, or the .onnx (metadata: same stem .yaml)
  int threads = 0;                   ///< network: OpenCV threads (0: OpenCV's default)
  std::filesystem::path cache_root;  ///< network: where calibration keeps segmentations on disk (empty: nowhere)
  /// network, calibration: networks for the training fields --network was trained on, each such
  /// field segmented by the first of them that never saw it (cross-fitting, calibrate()).
  std::vector<std::filesystem::path> calibration_networks;

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
    for (CLI::Option* e : excludes) current->excludes(e);
  }

  /// Where calibration keeps the network's segmentations (--segmentation-cache), if anywhere:
  /// a folder named by the network and the hash of its files (model_file_digest()).
  [[nodiscard]] std::optional<std::filesystem::path> calibration_cache() const {
    if (name != "network" || cache_root.empty()) return std::nullopt;
    return cache_root / model_file_digest(network);
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
  [[nodiscard]] std::vector<std::filesystem::path> network_per_field(std::span<const Field> fields) const {
    std::vector<std::filesystem::path> out(fields.size());
    if (calibration_networks.empty()) return out;
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
    for (std::size_t k = 0; k < fields.size(); ++k) {
      // A part of a field ("dubai-tile-1[0,0,0.5,1]", Field::sub_field) is that field's ground.
      const std::string& full = fields[k].name();
      const std::string field = full.back() == ']' ? full.substr(0, full.rfind('[')) : full;
      if (!knows(mission, field)) continue;
      std::size_t j = 0;
      while (j < pool.size() && knows(pool[j], field)) ++j;
      if (j == pool.size())
        throw std::invalid_argument("--calibration-network: every network given was trained on calibration field '" +
                                    full + "' (as --network " + network.string() + " was): give one that never saw it");
      out[k] = calibration_networks[j];
    }
    return out;
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
