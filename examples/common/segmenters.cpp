// calibrate_fields, compiled once for every example program (the adaptseg_examples_common
// library): calibration is instantiated here for AnyBackend alone.

#include "segmenters.hpp"

#include <map>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::examples {
namespace {

/// A network of a cross-fitted calibration with its segmentation cache, behind AnyBackend.
class CalibrationNetwork {
 public:
  virtual ~CalibrationNetwork() = default;
  [[nodiscard]] virtual AnyBackend& backend() = 0;
};

template <class Net>
class OwnedCalibrationNetwork final : public CalibrationNetwork {
 public:
  template <class... Args>
  explicit OwnedCalibrationNetwork(std::optional<std::filesystem::path> cache, Args&&... args)
      : net_(std::forward<Args>(args)...), inner_(net_), cached_(inner_, std::move(cache)), any_(cached_) {}
  [[nodiscard]] AnyBackend& backend() override { return any_; }

 private:
  Net net_;
  AnyBackend inner_;  // the cache is compiled for AnyBackend alone
  CachedBackend<AnyBackend> cached_;
  AnyBackend any_;
};

}  // namespace

CalibrationResult calibrate_fields(const SegmenterOptions& segmenter, std::span<const Field> fields,
                                   std::span<const std::filesystem::path> networks, AnyBackend& backend,
                                   const CalibrationOptions& options) {
  if (networks.size() != fields.size())
    throw std::invalid_argument("calibrate_fields: one calibration network entry per field is needed (" +
                                std::to_string(networks.size()) + " for " + std::to_string(fields.size()) + " fields)");
  CachedBackend<AnyBackend> cached(backend, segmenter.calibration_cache());
  AnyBackend mission(cached);
  std::map<std::filesystem::path, std::unique_ptr<CalibrationNetwork>> built;
  std::vector<AnyBackend*> backends;
  for (const auto& file : networks) {
    if (file.empty()) {
      backends.push_back(&mission);
      continue;
    }
    auto& net = built[file];
    if (!net) {
      OnnxParams p = segmenter.network_params(fields.front(), options.adaptive.mission.camera);
      p.name = network_name(file);
      std::optional<std::filesystem::path> cache;
      if (!segmenter.cache_root.empty()) cache = segmenter.cache_root / network_digest(file);
      if (EnsembleSegmenter::is_ensemble_dir(file)) {
        net = std::make_unique<OwnedCalibrationNetwork<EnsembleSegmenter>>(std::move(cache), file, std::move(p));
      } else {
        const auto [onnx, metadata] = network_files(file);
        net = std::make_unique<OwnedCalibrationNetwork<OnnxSegmenter>>(std::move(cache), onnx, metadata, std::move(p));
      }
    }
    backends.push_back(&net->backend());
  }
  return calibrate(fields, std::span<AnyBackend* const>(backends), options);
}

}  // namespace adaptseg::examples
