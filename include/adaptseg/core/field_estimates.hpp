#pragma once
/// @file
/// What the front-aware rule (front_aware_policy.hpp) estimates about the field it flies, from
/// what the UAV has seen of it so far: the field's share of the labels of interest σ̂ and its
/// mean cell-model input X̂ (FieldShareEstimate), and the field factor s by which its descents
/// relabel more or less than forecast (FieldScale). docs/method.md, "The front-aware rule".

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <utility>

namespace adaptseg {

/// σ̂, the field's share of the labels of interest L, and X̂, its mean cell-model input per field
/// pixel, from the top-level images so far (area weighted), the part of the field not yet seen
/// taken at the seen mean shrunk towards the training fields' mean with a weight of k fields.
///
/// σ̂'s uncertainty is a hierarchical model: the field's mean σ spread τ about the training
/// fields' mean, the mean of a seen share S spread v / S about the field's, v = k·τ²; then
/// Var σ̂ = (1 − S)²·τ²·k / (k + S) + (1 − S)·v, zero once the field is seen.
class FieldShareEstimate {
 public:
  /// `prior_sigma`: the training fields' mean σ (0: unknown; σ̂ is then the mean σ of the
  /// top-level images so far, without a spread).
  explicit FieldShareEstimate(double prior_sigma = 0.0) noexcept : prior_sigma_(prior_sigma) {}

  /// Forgets every image (a new mission); keeps the prior.
  void reset() noexcept { *this = FieldShareEstimate(prior_sigma_); }

  /// One top-level image: its σ, its region's share of the field, the region's mean input (NaN:
  /// unknown, left out of X̂) and its mean entropy (NaN: unknown, left out of entropy()).
  void add(double sigma, double region_share, double region_input,
           double region_entropy = std::numeric_limits<double>::quiet_NaN()) noexcept {
    if (std::isfinite(region_entropy)) {
      seen_entropy_ += region_share * region_entropy;
      seen_entropy_share_ += region_share;
    }
    sigma_sum_ += sigma;
    ++sigma_count_;
    seen_share_ += region_share;
    seen_interest_ += region_share * sigma;
    if (std::isfinite(region_input)) {
      seen_input_ += region_share * region_input;
      seen_input_share_ += region_share;
    }
  }

  /// a / σ̂ for a region of share a of the field (a relabelled share of the region, times η, as
  /// a field-level gain), and Var σ̂ / σ̂²; k and τ of the prior. {0, 0} where σ̂ is not > 0.
  [[nodiscard]] std::pair<double, double> gain_weight(double region_share, double k, double tau) const noexcept {
    double sigma = 0.0;
    double sigma_var = 0.0;
    if (prior_sigma_ > 0.0) {
      const double rest = (seen_interest_ + k * prior_sigma_) / (seen_share_ + k);
      const double unseen = std::max(0.0, 1.0 - seen_share_);
      sigma = seen_interest_ + unseen * rest;
      const double tau2 = tau * tau;
      sigma_var = unseen * unseen * tau2 * k / (k + seen_share_) + unseen * k * tau2;
    } else {
      sigma = sigma_sum_ / static_cast<double>(sigma_count_);
    }
    if (!(sigma > 0.0)) return {0.0, 0.0};
    return {region_share / sigma, sigma_var / (sigma * sigma)};
  }

  /// The field's mean top-level entropy: the seen regions' mean shrunk towards `prior` (the
  /// training fields' mean) with weight k, as X̂'s unseen part is; `prior` with none seen. Unlike
  /// X̂ the seen part is not taken as known: a field seen whole keeps k / (1 + k) of the prior.
  [[nodiscard]] double entropy(double prior, double k) const noexcept {
    return (seen_entropy_ + k * prior) / (seen_entropy_share_ + k);
  }

  /// X̂: the regions seen so far, the unseen part at their mean shrunk towards `prior_input`
  /// (the training fields' mean input; 0: unknown, the seen mean alone) with weight k.
  [[nodiscard]] double input(double prior_input, double k) const noexcept {
    const double unseen = std::max(0.0, 1.0 - seen_input_share_);
    const double rest = prior_input > 0.0         ? (seen_input_ + k * prior_input) / (seen_input_share_ + k)
                        : seen_input_share_ > 0.0 ? seen_input_ / seen_input_share_
                                                  : 0.0;
    return seen_input_ + unseen * rest;
  }

 private:
  double prior_sigma_ = 0.0;         ///< mean σ of the training fields (0: unknown)
  double sigma_sum_ = 0.0;           ///< σ of the top-level images so far
  std::size_t sigma_count_ = 0;      ///< ... and their number
  double seen_share_ = 0.0;          ///< field share of the top-level regions seen so far
  double seen_interest_ = 0.0;       ///< ... and Σ share · σ over them
  double seen_input_ = 0.0;          ///< Σ share · the region's mean input, where known
  double seen_input_share_ = 0.0;    ///< ... the share of the field those regions cover
  double seen_entropy_ = 0.0;        ///< Σ share · the region's mean entropy, where known
  double seen_entropy_share_ = 0.0;  ///< ... the share of the field those regions cover
};

/// A field factor's estimate: the mean and variance of its posterior (FieldScale).
struct FactorEstimate {
  double mean = 1.0;
  double var = 0.0;

  /// A forecast gain (of a descent, or of the field's curve) `base` before the factor, times the
  /// factor. A gain the training fields saw (base >= 0) scales with it and turns into a loss
  /// where a scene check found the finer look worse (mean < 0); a loss the training fields saw
  /// (base < 0: a descent GSD that lost there) stays a loss whatever the factor: |mean|·base.
  /// Without it, a field where descending loses would forecast a gain for exactly the descents
  /// the training fields saw lose.
  [[nodiscard]] double scaled(double base) const noexcept { return base >= 0.0 ? mean * base : std::abs(mean) * base; }
};

/// The field factor s: how much more (s > 1) or less than forecast this field's descents
/// relabel. Prior N(1, ω²); each observation y = s·μ + ε, ε ~ N(0, noise), updates its posterior
/// (conjugate Gaussian): precision 1/ω² + Σ μ²/noise, mean (1/ω² + Σ μ·y/noise) / precision.
class FieldScale {
 public:
  /// ω > 0, the prior's spread.
  explicit FieldScale(double prior_sd = 0.5) noexcept : prior_sd_(prior_sd), var_(prior_sd * prior_sd) {}

  [[nodiscard]] double mean() const noexcept { return mean_; }
  [[nodiscard]] double var() const noexcept { return var_; }
  [[nodiscard]] double sd() const noexcept { return std::sqrt(var_); }

  /// One observation y of s·μ with noise variance `noise` (> 0); `nonnegative`: the posterior
  /// mean kept >= 0 (a descent cannot relabel less than nothing).
  void observe(double mu, double y, double noise, bool nonnegative) noexcept {
    precision_sum_ += mu * mu / noise;
    evidence_sum_ += mu * y / noise;
    const double prior_precision = 1.0 / (prior_sd_ * prior_sd_);
    const double precision = prior_precision + precision_sum_;
    mean_ = (prior_precision + evidence_sum_) / precision;
    if (nonnegative) mean_ = std::max(0.0, mean_);
    var_ = 1.0 / precision;
  }

  /// s's estimate now.
  [[nodiscard]] FactorEstimate estimate() const noexcept { return {mean_, var_}; }

  /// A forecast gain `base` before s, times s (FactorEstimate::scaled).
  [[nodiscard]] double scaled(double base) const noexcept { return estimate().scaled(base); }

  /// The estimate of a second factor s' that moves b times as far from 1 as s does, s' = 1 +
  /// c·(s − 1) + e (FrontAwarePolicy::Params::relabel_transfer b), with its own prior spread ω'
  /// (`gain_sd`; FrontAwarePolicy::Params::relabel_field_sd) told apart from s's ω: c = min(b,
  /// ω'/ω) (s cannot explain more of s''s spread between fields than there is), e the part of the
  /// spread between fields that c·s does not explain, Var e = ω'² − c²·ω². Mean 1 + c·(mean − 1),
  /// variance c²·Var(s) + ω'² − c²·ω²: ω'² before any observation, whatever ω. ω' = ω (the
  /// one-argument form): c = b, Var e = (1 − b²)·ω²; b = 1: s's own; b = 0: the prior, however
  /// much s has learnt.
  [[nodiscard]] FactorEstimate transferred(double b, double gain_sd) const noexcept {
    const double r = gain_sd / prior_sd_;
    const double c = std::min(b, r);
    const double mean = c == 1.0 ? mean_ : 1.0 + c * (mean_ - 1.0);
    return {mean, c * c * var_ + std::max(0.0, r * r - c * c) * prior_sd_ * prior_sd_};
  }

  /// transferred(b, ω): s' of s's own prior spread.
  [[nodiscard]] FactorEstimate transferred(double b) const noexcept { return transferred(b, prior_sd_); }

 private:
  double prior_sd_ = 0.5;
  double mean_ = 1.0;
  double var_ = 0.25;
  double precision_sum_ = 0.0;
  double evidence_sum_ = 0.0;
};

}  // namespace adaptseg
