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

#include <adaptseg/core/detail/named_rows.hpp>

#include <algorithm>
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
  split,           ///< Σ_{C ∈ L} 1[0 < v_C < 1], v_C the members' vote share: members split on L (beyond the paper)
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

/// Every decision input, in enum order, as a list (e.g. a GridInputs of them all).
inline constexpr std::array<DecisionInput, kDecisionInputCount> kEveryDecisionInputList = [] {
  std::array<DecisionInput, kDecisionInputCount> all{};
  for (std::size_t k = 0; k < kDecisionInputCount; ++k) all[k] = kDecisionInputs[k].input;
  return all;
}();

namespace detail {
/// Every decision input: pixel_input_values()'s default.
inline constexpr std::array<bool, kDecisionInputCount> kEveryDecisionInput = [] {
  std::array<bool, kDecisionInputCount> all{};
  for (bool& w : all) w = true;
  return all;
}();
}  // namespace detail

/// The values of every decision input, in enum order (NaN where unknown: an input that needs
/// probabilities from a labels-only backend, or a cell without field pixels seen).
using DecisionInputValues = std::array<double, kDecisionInputCount>;

[[nodiscard]] constexpr std::size_t index_of(DecisionInput i) noexcept { return static_cast<std::size_t>(i); }
[[nodiscard]] constexpr const DecisionInputInfo& info(DecisionInput i) noexcept { return kDecisionInputs[index_of(i)]; }
[[nodiscard]] inline std::string to_string(DecisionInput i) { return std::string(info(i).name); }

/// Parses an input's name.
/// @throws std::invalid_argument naming every input for anything else.
[[nodiscard]] inline DecisionInput parse_decision_input(std::string_view name) {
  return detail::row_named(kDecisionInputs, name, "decision input").input;
}

/// Member vote shares within this of 0 or 1 count as none or all of the members (weight shares
/// summed in float may miss 1 by an ulp): where a class's share lies strictly inside, the members
/// split on it (input `split`, EnsembleSegmentation::class_split).
inline constexpr float kVoteShareTolerance = 1e-4f;

namespace detail {

/// pixel_input_rows()'s parts, chunk by chunk of kChunk pixels: what is wanted, the ensemble's
/// split, the probability mass, the entropy and the two most likely classes, and the outputs.
struct InputRows {
  static constexpr std::size_t kChunk = 64;
  static constexpr float kNan = std::numeric_limits<float>::quiet_NaN();

  /// One chunk's sums over the classes.
  struct Chunk {
    std::array<float, kChunk> sum{}, entropy{}, p_first{}, p_second{};
    std::array<std::size_t, kChunk> first{}, second{};
    std::array<float, kChunk> ambiguity{}, expected_error{}, second_choice{};
  };

  InputRows(std::span<const float* const> probabilities_, const std::array<bool, 256>& in_interest_,
            const std::array<bool, kDecisionInputCount>& wanted_, const std::array<float*, kDecisionInputCount>& out_)
      : probabilities(probabilities_),
        in_interest(in_interest_),
        wanted(wanted_),
        out(out_),
        classes(probabilities_.size()),
        with_entropy(want(DecisionInput::entropy)),
        ranked(want(DecisionInput::second_choice) || want(DecisionInput::low_confidence)),
        from_probabilities(classes > 0 && (want(DecisionInput::ambiguity) || want(DecisionInput::expected_error) ||
                                           ranked || with_entropy)) {}

  [[nodiscard]] bool want(DecisionInput i) const { return wanted[index_of(i)] && out[index_of(i)] != nullptr; }

  /// split: the members' vote shares on the classes of L strictly between none and all.
  void split(std::span<const float* const> votes, std::size_t x0, std::size_t m) const {
    std::array<float, kChunk> vote_sum{}, split_count{};
    for (std::size_t c = 0; c < votes.size() && c < 256; ++c) {
      const float* v = votes[c] + x0;
      for (std::size_t x = 0; x < m; ++x) vote_sum[x] += v[x];
      if (in_interest[c])
        for (std::size_t x = 0; x < m; ++x)
          split_count[x] += (v[x] > kVoteShareTolerance && v[x] < 1.0f - kVoteShareTolerance) ? 1.0f : 0.0f;
    }
    for (std::size_t x = 0; x < m; ++x)
      out[index_of(DecisionInput::split)][x0 + x] = vote_sum[x] > 0.0f ? split_count[x] : kNan;  // no votes: unknown
  }

  /// Without probabilities: every input that needs them unknown.
  void unknown(std::size_t x0, std::size_t m) const {
    for (DecisionInput i : {DecisionInput::ambiguity, DecisionInput::expected_error, DecisionInput::second_choice,
                            DecisionInput::low_confidence, DecisionInput::entropy})
      if (want(i)) std::fill_n(out[index_of(i)] + x0, m, kNan);
  }

  /// The probability mass, the entropy, the two most likely classes (first, then second: of
  /// classes 0 and 1 the larger first, ties to class 0; then each class c >= 2 in turn).
  void rank(Chunk& k, std::size_t x0, std::size_t m) const {
    if (ranked) {
      for (std::size_t x = 0; x < m; ++x) {
        const float a = probabilities[0][x0 + x], b = classes > 1 ? probabilities[1][x0 + x] : a;
        const bool one = classes > 1 && b > a;
        k.first[x] = one ? 1 : 0;
        k.second[x] = classes > 1 ? (one ? 0 : 1) : 0;
        k.p_first[x] = one ? b : a;
        k.p_second[x] = one ? a : b;
      }
    }
    for (std::size_t c = 0; c < classes; ++c) {
      const float* p = probabilities[c] + x0;
      for (std::size_t x = 0; x < m; ++x) k.sum[x] += p[x];
      if (with_entropy)
        for (std::size_t x = 0; x < m; ++x)
          if (p[x] > 0.0f) k.entropy[x] -= p[x] * std::log(p[x]);
      if (ranked && c >= 2)
        for (std::size_t x = 0; x < m; ++x) {
          if (p[x] > k.p_first[x]) {
            k.second[x] = k.first[x], k.p_second[x] = k.p_first[x];
            k.first[x] = c, k.p_first[x] = p[x];
          } else if (p[x] > k.p_second[x]) {
            k.second[x] = c, k.p_second[x] = p[x];
          }
        }
    }
  }

  /// The inputs read from the probabilities; no probabilities at a pixel (no data): unknown.
  void write(const Chunk& k, std::size_t x0, std::size_t m) const {
    const float log_classes = classes > 1 ? std::log(static_cast<float>(classes)) : 1.0f;
    for (std::size_t x = 0; x < m; ++x) {
      const bool data = k.sum[x] > 0.0f;
      if (want(DecisionInput::ambiguity))
        out[index_of(DecisionInput::ambiguity)][x0 + x] = data ? k.ambiguity[x] : kNan;
      if (want(DecisionInput::expected_error))
        out[index_of(DecisionInput::expected_error)][x0 + x] = data ? k.expected_error[x] : kNan;
      if (want(DecisionInput::second_choice))
        out[index_of(DecisionInput::second_choice)][x0 + x] = data ? k.second_choice[x] : kNan;
      if (want(DecisionInput::low_confidence))
        out[index_of(DecisionInput::low_confidence)][x0 + x] = data ? (k.p_first[x] < 0.6f ? 1.0f : 0.0f) : kNan;
      if (with_entropy)
        out[index_of(DecisionInput::entropy)][x0 + x] = data ? (classes > 1 ? k.entropy[x] / log_classes : 0.0f) : kNan;
    }
  }

  std::span<const float* const> probabilities;
  const std::array<bool, 256>& in_interest;
  const std::array<bool, kDecisionInputCount>& wanted;
  const std::array<float*, kDecisionInputCount>& out;
  std::size_t classes;
  bool with_entropy, ranked, from_probabilities;
};

}  // namespace detail

/// The per-pixel quantity behind every input, for `n` labelled pixels at once (one row of an
/// image, say): `labels[x]` the label l of pixel x (a class index; anything outside 0..255 is no
/// class), `probabilities[c][x]` the class probabilities (no planes for a labels-only backend:
/// the inputs that need them are NaN), `in_interest[c]` true for the classes of L, and an
/// ensemble's member vote shares `votes[c][x]` per class (no planes for one network: `split` is
/// NaN). `boundary` holds the σ indicator (its cell value is σ(1 − σ) of the mean,
/// cell_value()). Writes `out[k][x]` for each input k `wanted` (each `out[k]` n floats; those not
/// wanted are not touched, their work skipped: the entropy's logarithms, the two most likely
/// classes). Every formula is written once, here, as loops over the pixels the compiler can
/// vectorise; pixel_input_values() is the same for one pixel.
template <class Label>
inline void pixel_input_rows(std::size_t n, const Label* labels, std::span<const float* const> probabilities,
                             std::span<const float* const> votes, const std::array<bool, 256>& in_interest,
                             const std::array<bool, kDecisionInputCount>& wanted,
                             const std::array<float*, kDecisionInputCount>& out) {
  const detail::InputRows rows{probabilities, in_interest, wanted, out};
  for (std::size_t x0 = 0; x0 < n; x0 += detail::InputRows::kChunk) {
    const std::size_t m = std::min(detail::InputRows::kChunk, n - x0);
    const Label* l = labels + x0;
    // σ's indicator (and boundary's: the same pixel quantity).
    for (DecisionInput i : {DecisionInput::sigma, DecisionInput::boundary})
      if (rows.want(i))
        for (std::size_t x = 0; x < m; ++x)
          out[index_of(i)][x0 + x] =
              l[x] >= 0 && l[x] < 256 && in_interest[static_cast<std::size_t>(l[x])] ? 1.0f : 0.0f;
    if (rows.want(DecisionInput::split)) rows.split(votes, x0, m);
    if (!rows.from_probabilities) {
      rows.unknown(x0, m);
      continue;
    }
    detail::InputRows::Chunk chunk;
    rows.rank(chunk, x0, m);
    for (std::size_t c = 0; c < rows.classes && c < 256; ++c) {
      if (!in_interest[c]) continue;
      const float* p = probabilities[c] + x0;
      for (std::size_t x = 0; x < m; ++x) {
        chunk.ambiguity[x] += (p[x] > 0.2f && p[x] < 0.8f) ? 1.0f : 0.0f;
        chunk.expected_error[x] += static_cast<std::size_t>(l[x]) == c ? 1.0f - p[x] : p[x];
      }
      if (rows.ranked)
        for (std::size_t x = 0; x < m; ++x)
          chunk.second_choice[x] += (c == chunk.second[x] && c != chunk.first[x] && p[x] > 0.2f) ? 1.0f : 0.0f;
    }
    rows.write(chunk, x0, m);
  }
}

/// pixel_input_rows() at one labelled pixel: `label` l, the class probabilities `p` (empty for
/// a labels-only backend), and an ensemble's member vote shares `votes` per class (empty for one
/// network); the inputs not `wanted` NaN.
[[nodiscard]] inline std::array<float, kDecisionInputCount> pixel_input_values(
    int label, std::span<const float> p, const std::array<bool, 256>& in_interest, std::span<const float> votes = {},
    const std::array<bool, kDecisionInputCount>& wanted = detail::kEveryDecisionInput) {
  std::array<float, kDecisionInputCount> v;
  v.fill(std::numeric_limits<float>::quiet_NaN());
  std::array<float*, kDecisionInputCount> out{};
  for (std::size_t k = 0; k < kDecisionInputCount; ++k) out[k] = &v[k];
  std::array<const float*, 256> p_at{}, vote_at{};
  for (std::size_t c = 0; c < p.size() && c < 256; ++c) p_at[c] = &p[c];
  for (std::size_t c = 0; c < votes.size() && c < 256; ++c) vote_at[c] = &votes[c];
  pixel_input_rows(1, &label, std::span<const float* const>(p_at.data(), std::min<std::size_t>(p.size(), 256)),
                   std::span<const float* const>(vote_at.data(), std::min<std::size_t>(votes.size(), 256)), in_interest,
                   wanted, out);
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
  /// Field pixels of the cell's whole image footprint, where it overhangs its region too (its
  /// gain counted over every pixel its image covers: GainExtent::images); 0: `field_px`.
  double footprint_px = 0.0;
  [[nodiscard]] double value(DecisionInput i) const noexcept { return values[index_of(i)]; }
  /// The field pixels the cell's gain is counted over and forecast for (CellGainModel::forecast).
  [[nodiscard]] double gain_px() const noexcept { return footprint_px > 0.0 ? footprint_px : field_px; }
  /// value(i) · field_px, 0 where unknown: how much of input i the cell holds (how cells rank).
  [[nodiscard]] double mass(DecisionInput i) const noexcept {
    const double v = value(i);
    return std::isfinite(v) ? v * field_px : 0.0;
  }
};

}  // namespace adaptseg
