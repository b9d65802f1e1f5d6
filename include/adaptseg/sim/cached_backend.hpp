#pragma once
/// @file
/// A segmentation backend remembered: calibration flies the same waypoints over the same fields
/// many times (every setting tried, every fold), and a network is its slow part. CachedBackend
/// segments each image once, in memory and, with a folder, on disk across runs.

#include <adaptseg/core/detail/fnv1a.hpp>
#include <adaptseg/vision/image.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <opencv2/core.hpp>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <system_error>
#include <tuple>
#include <utility>

namespace adaptseg {

/// Memoises a deterministic backend: a simulated image is identified by its footprint, its
/// yaw, its size and the sums of its colour channels. For calibration, which flies the same waypoints many times,
/// and only with a fixed segmentation time per image (a cache hit takes no time, so a measured
/// time would be wrong). Gives probabilities where the backend does; they are kept (3.5 MB an
/// image for 5 classes at 480 x 360) only for images asked for with them a second time, as the
/// top-level images are by every mission of a calibration, not for the many finer images its
/// samples look at once. With a directory, the segmentations are also kept on disk there (one
/// file per image: labels, and the probabilities where they are kept), so that calibrations
/// with the same backend over the same fields (a sweep's runs) segment each image once; the
/// directory must be the backend's own (network_digest() names a network's).
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
    std::uint64_t hash = detail::kFnv1aBasis;
    for (int v : {x, y, w, h, iw, ih}) hash = detail::fnv1a(&v, sizeof v, hash);
    for (double v : {yaw, b, g, r}) hash = detail::fnv1a(&v, sizeof v, hash);
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

}  // namespace adaptseg
