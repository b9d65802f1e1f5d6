#pragma once
/// @file
/// What a top-level image tells the decision about the cells a descent may re-map (beyond the
/// paper, whose only input is the image's σ, Eq. `eq:vr`): the decision inputs, each the mean
/// over a cell's field pixels of one per-pixel quantity of the segmentation and, where the
/// backend gives them, its class probabilities (SegmentsWithProbabilities) and its members'
/// votes (an ensemble, EnsembleSegmenter).
///
/// One place per input: to add one, add its enumerator, its row of `kDecisionInputs` and its
/// formula in `pixel_input_values()`. Everything downstream reads the table: the per-image
/// summary (image_summary.hpp), the calibration samples and the choice of input
/// (cell_gain_model.hpp, calibration.hpp), the model file, the command line and the study tool
/// (examples/tools/cell_study.cpp). No OpenCV here: the decision side compiles without it.

#include <array>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace adaptseg {

/// A decision input. L = the labels of interest, p_C = the backend's probability of class C at
/// a pixel, l = its label; a cell's value is the mean over its field pixels (`boundary`: a
/// function of that mean, cell_value()).
enum class DecisionInput : int {
  sigma,           ///< 1[l ∈ L]: the cell's σ (paper Eq. `eq:vr`)
  boundary,        ///< σ(1 − σ) of the cell's σ: how much boundary of L the cell can hold
  ambiguity,       ///< Σ_{C ∈ L} 1[0.2 < p_C < 0.8]: pixels the backend hesitates on about a class of L
  expected_error,  ///< Σ_{C ∈ L} (l = C ? 1 − p_C : p_C): expected pixels wrong about L if the labels are kept
  second_choice,   ///< Σ_{C ∈ L} 1[C is the second most likely class and p_C > 0.2]
  low_confidence,  ///< 1[max_C p_C < 0.6]: generic hesitation, blind to L
  entropy,         ///< −Σ_C p_C ln p_C / ln(classes): generic, blind to L
  split,           ///< Σ_{C ∈ L} 1[0 < v_C < 1], v_C the members' vote share for C: an ensemble's members split on a class of L (beyond the paper; issue 31)
};

/// One row of the table of inputs.
struct DecisionInputInfo {
  DecisionInput input;
  std::string_view name;     ///< in model files, on the command line and in tables
  bool needs_probabilities;  ///< false: computed from the labels alone
  std::string_view meaning;
  bool needs_members = false;  ///< true: needs an ensemble's member votes (Segmentation::member_votes)
};

/// Every decision input, in enum order.
inline constexpr std::array<DecisionInputInfo, 8> kDecisionInputs{{
    {DecisionInput::sigma, "sigma", false, "share of the cell labelled in L"},
    {DecisionInput::boundary, "boundary", false, "sigma (1 - sigma) of the cell"},
    {DecisionInput::ambiguity, "ambiguity", true, "share of pixels with 0.2 < p_C < 0.8 for a class C of L"},
    {DecisionInput::expected_error, "expected_error", true,
     "expected share of pixels wrong about L if the top-level labels are kept"},
    {DecisionInput::second_choice, "second_choice", true,
     "share of pixels where a class of L is second most likely with p > 0.2"},
    {DecisionInput::low_confidence, "low_confidence", true, "share of pixels whose most likely class has p < 0.6"},
    {DecisionInput::entropy, "entropy", true, "mean normalised entropy of the class probabilities"},
    {DecisionInput::split, "split", false, "share of pixels where an ensemble's members split on a class of L", true},
}};

inline constexpr std::size_t kDecisionInputCount = kDecisionInputs.size();

/// The values of every decision input, in enum order (NaN where unknown: an input that needs
/// probabilities from a labels-only backend, or a cell without field pixels seen).
using DecisionInputValues = std::array<double, kDecisionInputCount>;

[[nodiscard]] constexpr std::size_t index_of(DecisionInput i) noexcept { return static_cast<std::size_t>(i); }
[[nodiscard]] constexpr const DecisionInputInfo& info(DecisionInput i) noexcept { return kDecisionInputs[index_of(i)]; }
[[nodiscard]] inline std::string to_string(DecisionInput i) { return std::string(info(i).name); }

/// Parses an input's name.
/// @throws std::invalid_argument naming every input for anything else.
[[nodiscard]] inline DecisionInput parse_decision_input(std::string_view name) {
  std::string all;
  for (const auto& row : kDecisionInputs) {
    if (row.name == name) return row.input;
    all += (all.empty() ? "" : ", ") + std::string(row.name);
  }
  throw std::invalid_argument("decision input must be one of " + all + ", not '" + std::string(name) + "'");
}

/// Member vote shares within this of 0 or 1 count as none or all of the members (weight shares
/// summed in float may miss 1 by an ulp): where a class's share lies strictly inside, the members
/// split on it (input `split`, EnsembleSegmentation::class_split).
inline constexpr float kVoteShareTolerance = 1e-4f;

/// The per-pixel quantity behind every input at one labelled pixel: `label` l, the class
/// probabilities `p` (empty for a labels-only backend: the inputs that need them are NaN),
/// `in_interest[c]` true for the classes of L, and an ensemble's member vote shares `votes` per
/// class (empty for one network: `split` is NaN). `boundary` holds the σ indicator (its cell
/// value is σ(1 − σ) of the mean, cell_value()).
[[nodiscard]] inline std::array<float, kDecisionInputCount> pixel_input_values(int label, std::span<const float> p,
                                                                              const std::array<bool, 256>& in_interest,
                                                                              std::span<const float> votes = {}) {
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  std::array<float, kDecisionInputCount> v;
  v.fill(nan);
  const float in = label >= 0 && label < 256 && in_interest[static_cast<std::size_t>(label)] ? 1.0f : 0.0f;
  v[index_of(DecisionInput::sigma)] = in;
  v[index_of(DecisionInput::boundary)] = in;
  float vote_sum = 0.0f, split = 0.0f;
  for (std::size_t c = 0; c < votes.size() && c < 256; ++c) {
    vote_sum += votes[c];
    if (in_interest[c])
      split += (votes[c] > kVoteShareTolerance && votes[c] < 1.0f - kVoteShareTolerance) ? 1.0f : 0.0f;
  }
  if (vote_sum > 0.0f) v[index_of(DecisionInput::split)] = split;  // no votes at this pixel: unknown
  const std::size_t n = p.size();
  if (n == 0) return v;
  // The two most likely classes, the probability mass, the entropy.
  std::size_t first = 0, second = n > 1 ? 1 : 0;
  if (n > 1 && p[1] > p[0]) first = 1, second = 0;
  float sum = 0.0f, entropy = 0.0f;
  for (std::size_t c = 0; c < n; ++c) {
    sum += p[c];
    if (p[c] > 0.0f) entropy -= p[c] * std::log(p[c]);
    if (c < 2) continue;
    if (p[c] > p[first]) {
      second = first;
      first = c;
    } else if (p[c] > p[second]) {
      second = c;
    }
  }
  if (!(sum > 0.0f)) return v;  // no probabilities at this pixel (no data)
  float ambiguity = 0.0f, expected_error = 0.0f, second_choice = 0.0f;
  for (std::size_t c = 0; c < n && c < 256; ++c) {
    if (!in_interest[c]) continue;
    ambiguity += (p[c] > 0.2f && p[c] < 0.8f) ? 1.0f : 0.0f;
    expected_error += static_cast<std::size_t>(label) == c ? 1.0f - p[c] : p[c];
    second_choice += (c == second && c != first && p[c] > 0.2f) ? 1.0f : 0.0f;
  }
  v[index_of(DecisionInput::ambiguity)] = ambiguity;
  v[index_of(DecisionInput::expected_error)] = expected_error;
  v[index_of(DecisionInput::second_choice)] = second_choice;
  v[index_of(DecisionInput::low_confidence)] = p[first] < 0.6f ? 1.0f : 0.0f;
  v[index_of(DecisionInput::entropy)] = n > 1 ? entropy / std::log(static_cast<float>(n)) : 0.0f;
  return v;
}

/// A cell's value of input `i` from the mean of its per-pixel quantity.
[[nodiscard]] inline double cell_value(DecisionInput i, double pixel_mean) noexcept {
  return i == DecisionInput::boundary ? pixel_mean * (1.0 - pixel_mean) : pixel_mean;
}

/// A cell a descent may re-map, as the top-level image saw it: every decision input over its
/// field pixels, and how many there are.
struct CellInputs {
  DecisionInputValues values{};
  double field_px = 0.0;  ///< map pixels of field in the cell that the top-level image saw
  [[nodiscard]] double value(DecisionInput i) const noexcept { return values[index_of(i)]; }
  /// value(i) · field_px, 0 where unknown: how much of input i the cell holds (how cells rank).
  [[nodiscard]] double mass(DecisionInput i) const noexcept {
    const double v = value(i);
    return std::isfinite(v) ? v * field_px : 0.0;
  }
};

}  // namespace adaptseg
