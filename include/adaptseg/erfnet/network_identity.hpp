#pragma once
/// @file
/// A network on disk as the programs name it (`--network`): an ONNX network's folder (model.onnx
/// and its model.yaml), an .onnx file with its .yaml beside it, or an ensemble's folder
/// (ensemble.yaml). Its identity is its folder's name and the hash of its weights and metadata,
/// so that a decision model calibrated with one network is refused with another, or with the
/// same one at another temperature, whatever their folders are called; a segmentation cache is
/// kept per identity. with_network() builds the backend behind AnyBackend.

#include <adaptseg/core/detail/fnv1a.hpp>
#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/vision/any_backend.hpp>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

namespace detail {
/// The FNV-1a hash over the bytes of `files`, in order, as 16 hex digits (a missing file hashes
/// as empty).
[[nodiscard]] inline std::string files_hash(const std::vector<std::filesystem::path>& files) {
  std::uint64_t h = kFnv1aBasis;
  for (const auto& f : files) {
    std::ifstream in(f, std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    h = fnv1a(bytes.data(), bytes.size(), h);
  }
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(h));
  return hex;
}
}  // namespace detail

/// A network's ONNX file and metadata: `network` is a folder with model.onnx and model.yaml, or
/// an .onnx file with its .yaml next to it.
[[nodiscard]] inline std::pair<std::filesystem::path, std::filesystem::path> network_files(
    const std::filesystem::path& network) {
  const bool dir = std::filesystem::is_directory(network);
  const std::filesystem::path onnx = dir ? network / "model.onnx" : network;
  std::filesystem::path metadata = onnx;
  metadata.replace_extension(".yaml");
  return {onnx, metadata};
}

/// One ONNX network's identity: its folder's name and the hash of its ONNX file and metadata
/// (the temperature included), e.g. "mobilenetv2-dubai-3fa2...".
[[nodiscard]] inline std::string onnx_digest(const std::filesystem::path& onnx, const std::filesystem::path& metadata) {
  const std::filesystem::path dir = onnx.parent_path();
  return (dir.filename().empty() ? std::string("model") : dir.filename().string()) + "-" +
         detail::files_hash({onnx, metadata});
}

/// An ensemble folder's identity: its name and the hash of its ensemble.yaml and of every
/// member's ONNX file and metadata, in the file's order (a member retrained or re-tempered, or
/// weights changed, is another ensemble).
[[nodiscard]] inline std::string ensemble_digest(const std::filesystem::path& dir) {
  std::vector<std::filesystem::path> files{dir / "ensemble.yaml"};
  for (const EnsembleMember& m : read_ensemble_file(dir)) {
    files.push_back(m.model_dir / "model.onnx");
    files.push_back(m.model_dir / "model.yaml");
  }
  const std::filesystem::path name = dir.filename().empty() ? dir.parent_path().filename() : dir.filename();
  return name.string() + "-" + detail::files_hash(files);
}

/// A network's identity, one network's (onnx_digest()) or an ensemble folder's (ensemble_digest()).
[[nodiscard]] inline std::string network_digest(const std::filesystem::path& network) {
  if (EnsembleSegmenter::is_ensemble_dir(network)) return ensemble_digest(network);
  const auto [onnx, metadata] = network_files(network);
  return onnx_digest(onnx, metadata);
}

/// The name a network backend goes by in results and decision models: "erfnet:" (one network;
/// the prefix of adaptseg 0.1, kept so that model files keep working) or "ensemble:" and its
/// identity (network_digest()).
[[nodiscard]] inline std::string network_name(const std::filesystem::path& network) {
  return (EnsembleSegmenter::is_ensemble_dir(network) ? "ensemble:" : "erfnet:") + network_digest(network);
}

/// The fields `network` was trained on (its metadata's training.fields; an ensemble's: every
/// member's, each once), empty where the metadata names none.
[[nodiscard]] inline std::vector<std::string> network_training_fields(const std::filesystem::path& network) {
  std::vector<std::filesystem::path> metadata;
  if (EnsembleSegmenter::is_ensemble_dir(network)) {
    for (const EnsembleMember& m : read_ensemble_file(network)) metadata.push_back(network_files(m.model_dir).second);
  } else {
    metadata.push_back(network_files(network).second);
  }
  std::vector<std::string> out;
  for (const auto& file : metadata)
    for (std::string& f : OnnxSegmenter::read_model_info(file).training_fields)
      if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(std::move(f));
  return out;
}

/// Calls `f(backend)` with the backend of `network` behind AnyBackend: an EnsembleSegmenter for
/// an ensemble folder, else an OnnxSegmenter (network_files()); named by network_name() and
/// built with `params` otherwise. One backend type for every network, so that a program
/// instantiates the planner and calibration once; `f`'s result is returned.
template <class F>
decltype(auto) with_network(const std::filesystem::path& network, OnnxParams params, F&& f) {
  params.name = network_name(network);
  if (EnsembleSegmenter::is_ensemble_dir(network)) {
    EnsembleSegmenter ensemble(network, std::move(params));
    AnyBackend any(ensemble);
    return std::forward<F>(f)(any);
  }
  const auto [onnx, metadata] = network_files(network);
  OnnxSegmenter one(onnx, metadata, std::move(params));
  AnyBackend any(one);
  return std::forward<F>(f)(any);
}

}  // namespace adaptseg
