#pragma once
/// @file
/// An ensemble of ONNX networks of one class set (OnnxSegmenter members, of one architecture or
/// of several) run in one process through OpenCV DNN: the weighted mean of the members' class
/// probabilities, its labels, and where the members disagree. Link `adaptseg::erfnet`.
///
/// Why: averaging the probabilities of independently trained networks is the simplest ensemble
/// there is (Lakshminarayanan et al., "Simple and scalable predictive uncertainty estimation
/// using deep ensembles", NeurIPS 2017) and on the bundled Dubai fields the mean of two networks
/// maps every field better than either (docs/results.md, "The ensemble"); the members'
/// disagreement marks pixels where the networks' training left the answer open, which one
/// network's own softmax does not show.
///
/// An ensemble directory holds `ensemble.yaml`:
/// @code{.yaml}
/// # members: model directories (model.onnx + model.yaml), relative to this file
/// members:
///   - model: ../mobilenetv2-dubai
///     weight: 1        # optional, default 1; > 0; weights are normalised
///     mirror: true     # optional, default false: OnnxParams::test_time_mirror for this member
///     coarse_gsd_cm: 10  # optional, default 0 (off): OnnxParams::test_time_coarse_gsd_cm for it
///   - model: ../erfnet-dubai
/// description: free text  # optional
/// @endcode

#include <adaptseg/core/camera.hpp>
#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/erfnet/onnx_segmenter.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>
#include <adaptseg/vision/field.hpp>
#include <adaptseg/vision/segmentation_backend.hpp>

#include <opencv2/core.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg {

/// One member of an ensemble: a model directory (model.onnx + model.yaml, as OnnxSegmenter
/// loads it), its weight in the mean, and whether it also segments the mirrored image.
struct EnsembleMember {
  std::filesystem::path model_dir;
  double weight = 1.0;  ///< > 0, finite; the weights are normalised to sum to 1
  /// OnnxParams::test_time_mirror for this member (its probabilities: the mean over the image
  /// and its mirror; it still counts once in the votes and the disagreement).
  bool mirror = false;
  /// OnnxParams::test_time_coarse_gsd_cm for this member where not 0 (else the ensemble's): its
  /// probabilities also count a pass over the image at a coarser GSD.
  double coarse_gsd_cm = 0.0;
};

/// An ensemble's segmentation of one image (EnsembleSegmenter::segment_with_disagreement()).
struct EnsembleSegmentation {
  /// labels: argmax of the weighted mean of the members' probabilities (ties to the lower
  /// class), the image's ignore label on pixels without RGB content; probabilities: that mean
  /// (one CV_32FC1 plane per class; all 0 on pixels without RGB content); member_votes: per
  /// class, the weight share of the members whose own label is that class (all 0 on pixels
  /// without RGB content).
  Segmentation mean;
  /// CV_32FC1: per pixel, the weight share of the members whose own label differs from the
  /// mean's label, in [0, 1] (1 where the mean's argmax is no member's label); 0 on pixels
  /// without RGB content.
  cv::Mat disagreement;
  /// Per class, CV_8UC1: 255 where the members split on the class (some label the pixel with
  /// it and some do not), 0 elsewhere.
  std::vector<cv::Mat> class_split;
};

/// The members and weights of an ensemble directory's `ensemble.yaml` (format in the file
/// comment above), member paths resolved relative to the directory.
/// @throws std::invalid_argument naming the file and the problem: no such directory or file, a
///         YAML error, an unknown key, no members, a member without `model`, a weight that is
///         not a number > 0, a `mirror` that is not true or false, a `coarse_gsd_cm` that is not a
///         number (OnnxSegmenter refuses one < 0).
[[nodiscard]] inline std::vector<EnsembleMember> read_ensemble_file(const std::filesystem::path& dir) {
  const std::filesystem::path file = dir / "ensemble.yaml";
  const auto fail = [&](const std::string& what) {
    throw std::invalid_argument("EnsembleSegmenter: " + file.string() + ": " + what);
  };
  if (!std::filesystem::is_directory(dir))
    throw std::invalid_argument("EnsembleSegmenter: ensemble directory not found: " + dir.string());
  if (!std::filesystem::is_regular_file(file)) fail("file not found (an ensemble directory holds ensemble.yaml)");
  const std::string where = "EnsembleSegmenter: " + file.string();
  const detail::YamlReader r(detail::yaml_mapping(where, "an ensemble description with a list 'members'",
                                                  [&] { return YAML::LoadFile(file.string()); }),
                             where);
  r.only_keys({"members", "description"});
  std::vector<EnsembleMember> members;
  for (const detail::YamlReader& m : r.maps("members")) {
    m.only_keys({"model", "weight", "mirror", "coarse_gsd_cm"});
    EnsembleMember member;
    member.model_dir = dir / m.text("model");
    if (m.has("weight")) member.weight = m.number("weight");
    if (m.has("mirror")) member.mirror = m.flag("mirror");
    if (m.has("coarse_gsd_cm")) member.coarse_gsd_cm = m.number("coarse_gsd_cm");
    members.push_back(std::move(member));
  }
  if (members.empty()) fail("'members' must be a non-empty list of {model: DIR, weight: W}");
  return members;
}

/// Semantic segmentation by an ensemble of ONNX networks (OnnxSegmenter members); a
/// `SegmentationBackend` with probabilities.
///
/// Per image every member segments it as OnnxSegmenter does (its own input size, channel
/// order, normalisation and temperature) and gives class probabilities at the image's size;
/// the ensemble's probabilities are their weighted mean, its labels the mean's argmax (ties to
/// the lower class). segment_with_disagreement() adds where the members disagree.
///
/// Contract: SegmentationBackend's and SegmentsWithProbabilities' (checked for the bundled
/// ensemble by tests/backend_conformance.hpp). Not thread-safe (its members are not);
/// move-only.
///
/// @code
/// const auto field = adaptseg::Field::load("examples/data/dubai-tile-6");
/// const adaptseg::CameraModel camera;  // 480 x 360
/// adaptseg::EnsembleSegmenter ensemble("examples/models/ensemble-dubai", field, camera,
///                                      {.resize_to_network = true});
/// const auto s = ensemble.segment_with_disagreement(adaptseg::SimulatedSensor(field, camera).capture(waypoint));
/// @endcode
class EnsembleSegmenter {
 public:
  /// Applied to every member (classes, camera size, resampling, no-data, threads, DNN backend,
  /// test-time mirror, which a member's own `mirror` adds to, and the coarser look, which a
  /// member's own `coarse_gsd_cm` replaces); `name` is the ensemble's
  /// (OnnxParams' default, "erfnet", becomes "ensemble"; member k is named
  /// `name/<its folder>`).
  using Params = OnnxParams;

  /// Loads every member.
  /// @throws std::invalid_argument with one line naming the problem: no members, a weight that
  ///         is not finite and > 0, a member listed twice, members whose classes differ (naming
  ///         both), and whatever OnnxSegmenter throws for a member (prefixed with its number
  ///         and directory).
  explicit EnsembleSegmenter(std::vector<EnsembleMember> members, Params params = {})
      : params_(std::move(params)), specs_(std::move(members)) {
    if (specs_.empty())
      throw std::invalid_argument("EnsembleSegmenter: no members (an ensemble needs at least one network)");
    if (params_.name == OnnxParams{}.name) params_.name = "ensemble";
    double total = 0.0;
    for (std::size_t k = 0; k < specs_.size(); ++k) {
      const EnsembleMember& m = specs_[k];
      const std::string who = member_label(k);
      if (!std::isfinite(m.weight) || m.weight <= 0.0)
        throw std::invalid_argument("EnsembleSegmenter: " + who + ": weight must be a finite number > 0 (got " +
                                    std::to_string(m.weight) + ")");
      for (std::size_t j = 0; j < k; ++j)
        if (same_dir(specs_[j].model_dir, m.model_dir))
          throw std::invalid_argument("EnsembleSegmenter: " + who + " is listed twice (also member " +
                                      std::to_string(j + 1) + "); give it a larger weight instead");
      total += m.weight;
    }
    for (std::size_t k = 0; k < specs_.size(); ++k) {
      weights_.push_back(static_cast<float>(specs_[k].weight / total));
      Params p = params_;
      p.name = params_.name + "/" + specs_[k].model_dir.filename().string();
      p.test_time_mirror = params_.test_time_mirror || specs_[k].mirror;
      if (specs_[k].coarse_gsd_cm != 0.0) p.test_time_coarse_gsd_cm = specs_[k].coarse_gsd_cm;
      try {
        members_.emplace_back(specs_[k].model_dir, std::move(p));
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("EnsembleSegmenter: " + member_label(k) + ": " + e.what());
      }
      if (members_.back().classes() != members_.front().classes())
        throw std::invalid_argument("EnsembleSegmenter: " + member_label(k) + " has classes " +
                                    detail::class_list(members_.back().classes()) + ", " + member_label(0) + " has " +
                                    detail::class_list(members_.front().classes()) +
                                    "; members must share one class set");
    }
  }

  /// Loads the ensemble directory `dir` (its ensemble.yaml, read_ensemble_file()).
  /// @throws std::invalid_argument as read_ensemble_file() and the member-list constructor.
  explicit EnsembleSegmenter(const std::filesystem::path& dir, Params params = {})
      : EnsembleSegmenter(read_ensemble_file(dir), std::move(params)) {}

  /// Loads `dir` for images of `camera` over `field` (OnnxSegmenter::for_field()).
  EnsembleSegmenter(const std::filesystem::path& dir, const Field& field, const CameraModel& camera, Params params = {})
      : EnsembleSegmenter(dir, OnnxSegmenter::for_field(field, camera, std::move(params))) {}

  EnsembleSegmenter(const EnsembleSegmenter&) = delete;
  EnsembleSegmenter& operator=(const EnsembleSegmenter&) = delete;
  EnsembleSegmenter(EnsembleSegmenter&&) = default;
  EnsembleSegmenter& operator=(EnsembleSegmenter&&) = default;
  ~EnsembleSegmenter() = default;

  /// Whether `dir` is an ensemble directory (holds ensemble.yaml).
  [[nodiscard]] static bool is_ensemble_dir(const std::filesystem::path& dir) {
    return std::filesystem::is_regular_file(dir / "ensemble.yaml");
  }

  [[nodiscard]] std::string name() const { return params_.name; }
  [[nodiscard]] int num_classes() const noexcept { return members_.front().num_classes(); }
  [[nodiscard]] const std::vector<std::string>& classes() const noexcept { return members_.front().classes(); }
  [[nodiscard]] std::size_t size() const noexcept { return members_.size(); }
  /// Member k (0-based), as loaded.
  [[nodiscard]] const OnnxSegmenter& member(std::size_t k) const { return members_.at(k); }
  /// Member k's normalised weight.
  [[nodiscard]] double weight(std::size_t k) const { return weights_.at(k); }
  /// The members as given (directories and weights before normalisation).
  [[nodiscard]] const std::vector<EnsembleMember>& member_list() const noexcept { return specs_; }

  /// Labels of the mean probabilities (see EnsembleSegmentation::mean).
  /// @throws std::invalid_argument as OnnxSegmenter::segment().
  [[nodiscard]] cv::Mat segment(const Image& image) { return segment_with_probabilities(image).labels; }

  /// Labels, the mean probabilities and the member votes (SegmentsWithProbabilities; the votes
  /// feed decision input `split`).
  /// @throws std::invalid_argument as OnnxSegmenter::segment().
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) { return run(image, false).mean; }

  /// The mean, its labels, and where the members disagree.
  /// @throws std::invalid_argument as OnnxSegmenter::segment().
  [[nodiscard]] EnsembleSegmentation segment_with_disagreement(const Image& image) { return run(image, true); }

 private:
  EnsembleSegmentation run(const Image& image, bool disagreement) {
    const int nc = num_classes();
    const auto ncs = static_cast<std::size_t>(nc);
    EnsembleSegmentation out;
    std::vector<cv::Mat> member_labels;
    for (std::size_t k = 0; k < members_.size(); ++k) {
      Segmentation s = members_[k].segment_with_probabilities(image);
      if (k == 0) {
        out.mean.probabilities.resize(ncs);
        for (std::size_t c = 0; c < ncs; ++c) out.mean.probabilities[c] = s.probabilities[c] * weights_[k];
        // Member 0's labels carry the ignore pixels (pixels without RGB content, the same for all).
        out.mean.labels = s.labels.clone();
      } else {
        for (std::size_t c = 0; c < ncs; ++c)
          cv::scaleAdd(s.probabilities[c], weights_[k], out.mean.probabilities[c], out.mean.probabilities[c]);
      }
      member_labels.push_back(std::move(s.labels));
    }
    const cv::Size size = out.mean.probabilities.front().size();
    // Argmax of the mean, and the members' vote shares; pixels the members left without a class
    // (no RGB content) keep the ignore label and no votes.
    auto& votes = out.mean.member_votes;
    votes.assign(ncs, cv::Mat());
    for (auto& v : votes) v = cv::Mat::zeros(size, CV_32FC1);
    std::vector<const float*> rows(ncs);
    std::vector<float*> vote_rows(ncs);
    for (int r = 0; r < size.height; ++r) {
      for (std::size_t c = 0; c < ncs; ++c) {
        rows[c] = out.mean.probabilities[c].ptr<float>(r);
        vote_rows[c] = votes[c].ptr<float>(r);
      }
      auto* lab = out.mean.labels.ptr<std::uint8_t>(r);
      for (int x = 0; x < size.width; ++x) {
        if (lab[x] == image.ignore_label) continue;
        std::size_t best = 0;
        for (std::size_t c = 1; c < ncs; ++c)
          if (rows[c][x] > rows[best][x]) best = c;  // strict: ties keep the lower index
        lab[x] = static_cast<std::uint8_t>(best);
        for (std::size_t k = 0; k < member_labels.size(); ++k) {
          const std::uint8_t v = member_labels[k].ptr<std::uint8_t>(r)[x];
          if (v < nc) vote_rows[v][x] += weights_[k];
        }
      }
    }
    if (!disagreement) return out;
    // From the votes: the weight off the mean's label, and the classes the members split on.
    out.disagreement = cv::Mat::zeros(size, CV_32FC1);
    out.class_split.assign(ncs, cv::Mat());
    for (std::size_t c = 0; c < ncs; ++c) {
      out.class_split[c] = (votes[c] > kVoteShareTolerance) & (votes[c] < 1.0f - kVoteShareTolerance);
    }
    for (int r = 0; r < size.height; ++r) {
      const auto* lab = out.mean.labels.ptr<std::uint8_t>(r);
      auto* dis = out.disagreement.ptr<float>(r);
      for (int x = 0; x < size.width; ++x)
        if (lab[x] < nc) dis[x] = std::max(0.0f, 1.0f - votes[lab[x]].ptr<float>(r)[x]);
    }
    return out;
  }

  [[nodiscard]] std::string member_label(std::size_t k) const {
    return "member " + std::to_string(k + 1) + " (" + specs_[k].model_dir.string() + ")";
  }

  static bool same_dir(const std::filesystem::path& a, const std::filesystem::path& b) {
    std::error_code ea, eb;
    const auto ca = std::filesystem::weakly_canonical(a, ea), cb = std::filesystem::weakly_canonical(b, eb);
    return (ea || eb) ? a.lexically_normal() == b.lexically_normal() : ca == cb;
  }

  Params params_;
  std::vector<EnsembleMember> specs_;
  std::vector<float> weights_;
  std::vector<OnnxSegmenter> members_;
};

static_assert(SegmentationBackend<EnsembleSegmenter>);
static_assert(SegmentsWithProbabilities<EnsembleSegmenter>);

}  // namespace adaptseg
