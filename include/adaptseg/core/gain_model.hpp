#pragma once
/// @file
/// The gain model of the decision function (paper §3.2.2-3.2.3, Eq. `eq:veg2h`; docs/method.md,
/// "The decision function"):
/// Gaussian-process regressions that forecast what re-mapping a region from a lower altitude
/// changes, fitted to initialisation samples. The decision rules that weigh these forecasts
/// against time are separate types (UtilityPolicy, FrontAwarePolicy).

#include <adaptseg/core/cell_gain_model.hpp>
#include <adaptseg/core/decision.hpp>
#include <adaptseg/core/detail/interpolate.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gaussian_process.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <span>
#include <utility>
#include <vector>

namespace adaptseg {

/// Forecasts of one descent (one region, one lower altitude).
struct GainForecast {
  double delta_sigma = 0.0;     ///< μ_O: σ_{h_max} − σ_{h'}
  double delta_miou = 0.0;      ///< μ_I: mIoU_{h_max} − mIoU_{h'} over L on the region (< 0: lower is better)
  double delta_miou_std = 0.0;  ///< I's predictive standard deviation
  /// μ_C: share of the region's field pixels whose label will change with L involved
  /// (Relabelling::interest_share); NaN for a model without C.
  double relabelled = std::numeric_limits<double>::quiet_NaN();
  /// C's predictive standard deviation of its mean (latent: the model's uncertainty).
  double relabelled_std = std::numeric_limits<double>::quiet_NaN();
  /// C's predictive standard deviation of one region's observed share (noise included).
  double relabelled_noisy_std = std::numeric_limits<double>::quiet_NaN();
};

/// A candidate's score with `f`'s forecasts filled in; the utility and the policy's own terms
/// are the policy's to set.
[[nodiscard]] inline CandidateScore scored(const Candidate& c, const GainForecast& f) {
  CandidateScore s;
  s.gsd_cm = c.gsd_cm;
  s.predicted_delta_sigma = f.delta_sigma;
  s.predicted_delta_miou = f.delta_miou;
  s.predicted_delta_miou_std = f.delta_miou_std;
  return s;
}

/// Gain per second of a descent's extra time (a free descent that gains is worth +inf).
[[nodiscard]] inline double utility(double gain, double extra_time_s) {
  if (extra_time_s > 0.0) return gain / extra_time_s;
  return gain > 0.0 ? std::numeric_limits<double>::infinity() : 0.0;
}

/// The O, I and C regressions.
///
/// - O (paper Eq. `eq:veg2h`, left): Δσ on (Δh [m], σ_{h_max}); the current image's σ is the
///   only thing the UAV knows when it decides, so it is an input (docs/method.md, "The
///   decision function").
/// - I (Eq. `eq:veg2h`, right): ΔmIoU on Δσ (GainInputs::delta_sigma, the paper's), or on
///   (Δσ, Δh) (GainInputs::delta_sigma_and_height, beyond the paper: where the backend keeps σ
///   nearly unchanged across altitudes, e.g. a ground-truth oracle, Δσ alone predicts the same
///   gain for every altitude; Δh tells I how much finer the re-mapping is). Needs ground
///   truth, so it is fixed after initialisation.
/// - C (beyond the paper): the share χ of the region's field pixels a descent relabels with a
///   label of interest involved, as χ = σ(1 − σ) · ρ(Δh, σ) with σ = σ_{h_max}: the GP
///   regresses ρ = χ / (σ(1 − σ)) on the samples where σ(1 − σ) >= `kMinSigmaForC`. A descent
///   relabels along the boundaries of L, which vanish where a region shows none of L and where
///   it shows nothing else; χ itself grows, and scatters, with σ(1 − σ) (a stationary GP fitted
///   to it overfits), ρ is of one scale everywhere. Unlike the gain it is observable in
///   flight (no ground truth: the region's map before and after), so a policy can compare what
///   each descent changed with what C forecast and correct its next forecasts
///   (FrontAwarePolicy). With C comes η(Δh), the field gain per relabelled share: for each
///   descent height of the samples, the least-squares slope (through the origin) of their
///   normalised field gain (RegionSample::normalized_field_gain) on their relabelled share;
///   linear in Δh between those heights, constant beyond. A descent to the field's own GSD
///   relabels only to correct (η ≈ 1 with a ground-truth oracle), one to a GSD barely finer
///   than the top moves errors about as much as it corrects them (η ≈ 0.07 at 12.5 cm/px from
///   15 on the Dubai tiles): η says how much of a relabelling is gain.
///
/// With DescentCoverage::ranked, the descent's cells are forecast by a CellGainModel instead of
/// C and η (set_cells(); fitted by calibration to single cells re-mapped alone).
///
/// All three: ARD squared-exponential kernel plus noise, normalised targets, hyperparameters
/// by maximum marginal likelihood. Online (§3.2.3), `update` adds the observed (Δh, σ_{h_max})
/// → Δσ to O by an O(n²) Cholesky extension and re-optimises O's hyperparameters every
/// `refit_every` updates (0: never).
class GainModel {
 public:
  using Gp = GaussianProcess<ArdSquaredExponentialKernel>;

  /// Samples with a smaller σ(1 − σ) do not enter C (ρ is not measurable there).
  static constexpr double kMinSigmaForC = 0.005;
  /// Lower bound of C's length scale along σ: ρ varies with σ on the scale of the class's
  /// share, not of its noise.
  static constexpr double kMinSigmaLengthScale = 0.05;

  /// The inputs of I (see the class comment).
  enum class GainInputs {
    delta_sigma,             ///< ΔmIoU from Δσ (the paper's Eq. `eq:veg2h`)
    delta_sigma_and_height,  ///< ΔmIoU from (Δσ, Δh)
  };

  /// How `fit` fits the regressions.
  struct FitOptions {
    GainInputs gain_inputs = GainInputs::delta_sigma_and_height;
    int restarts = 3;        ///< deterministic hyperparameter restarts per GP, >= 0
    std::uint64_t seed = 0;  ///< of the restarts
  };

  /// η at one descent height.
  struct EfficiencyPoint {
    double delta_h_m = 0.0;
    double efficiency = 0.0;
  };

  /// @throws std::invalid_argument for models of the wrong input dimension (O, C: 2; I: 1 or
  ///         2) or without data, `refit_every` < 0, or C without efficiency points (finite,
  ///         η >= 0, heights strictly increasing).
  GainModel(Gp o, Gp i, std::optional<Gp> c = std::nullopt, std::vector<EfficiencyPoint> efficiency = {},
            int refit_every = 0)
      : o_(std::move(o)),
        i_(std::move(i)),
        c_(std::move(c)),
        efficiency_(std::move(efficiency)),
        refit_every_(refit_every) {
    detail::require(!c_ || !efficiency_.empty(), "GainModel: C needs efficiency points; count", efficiency_.size());
    for (std::size_t k = 0; k < efficiency_.size(); ++k)
      detail::require(std::isfinite(efficiency_[k].delta_h_m) && std::isfinite(efficiency_[k].efficiency) &&
                          efficiency_[k].efficiency >= 0.0 &&
                          (k == 0 || efficiency_[k].delta_h_m > efficiency_[k - 1].delta_h_m),
                      "GainModel: efficiency points need finite heights in increasing order and finite eta >= 0; "
                      "eta",
                      efficiency_[k].efficiency);
    detail::require(o_.size() > 0 && o_.dimension() == 2,
                    "GainModel: O must hold data with 2 inputs (delta_h, sigma); dimension", o_.dimension());
    detail::require(i_.size() > 0 && (i_.dimension() == 1 || i_.dimension() == 2),
                    "GainModel: I must hold data with 1 input (delta_sigma) or 2 (delta_sigma, delta_h); dimension",
                    i_.dimension());
    detail::require(!c_ || (c_->size() > 0 && c_->dimension() == 2),
                    "GainModel: C must hold data with 2 inputs (delta_h, sigma); dimension", c_ ? c_->dimension() : 0);
    detail::require(refit_every_ >= 0, "GainModel: refit_every must be >= 0", refit_every_);
  }

  /// Fits O, I and C to initialisation samples (hyperparameters by maximum marginal
  /// likelihood, `restarts` deterministic restarts from `seed`).
  /// @throws std::invalid_argument if there is no sample or a sample is not finite;
  ///         NumericalError if a GP cannot be factorised.
  [[nodiscard]] static GainModel fit(std::span<const RegionSample> samples, const FitOptions& options) {
    detail::require(!samples.empty(), "GainModel::fit: number of samples must be > 0", 0);
    detail::require(options.restarts >= 0, "GainModel::fit: restarts must be >= 0", options.restarts);
    const auto n = static_cast<Eigen::Index>(samples.size());
    const bool by_height = options.gain_inputs == GainInputs::delta_sigma_and_height;
    Eigen::MatrixXd xo(n, 2), xi(n, by_height ? 2 : 1);
    Eigen::VectorXd yo(n), yi(n);
    for (Eigen::Index k = 0; k < n; ++k) {
      const RegionSample& s = samples[static_cast<std::size_t>(k)];
      xo(k, 0) = s.delta_h_m;
      xo(k, 1) = s.sigma_top;
      yo(k) = s.delta_sigma();
      xi(k, 0) = s.delta_sigma();
      if (by_height) xi(k, 1) = s.delta_h_m;
      yi(k) = s.delta_miou();
    }
    Gp o = two_input_gp(xo);
    // C on the samples whose σ lets ρ be measured (all of them if fewer than two do).
    std::vector<Eigen::Index> rows_c;
    for (Eigen::Index k = 0; k < n; ++k)
      if (boundary(samples[static_cast<std::size_t>(k)].sigma_top) >= kMinSigmaForC) rows_c.push_back(k);
    if (rows_c.size() < 2) {
      rows_c.clear();
      for (Eigen::Index k = 0; k < n; ++k) rows_c.push_back(k);
    }
    Eigen::MatrixXd xc(static_cast<Eigen::Index>(rows_c.size()), 2);
    Eigen::VectorXd yr(xc.rows());
    for (Eigen::Index r = 0; r < xc.rows(); ++r) {
      const RegionSample& s = samples[static_cast<std::size_t>(rows_c[static_cast<std::size_t>(r)])];
      xc.row(r) = xo.row(rows_c[static_cast<std::size_t>(r)]);
      yr(r) = s.relabelled.interest_share / std::max(boundary(s.sigma_top), kMinSigmaForC);
    }
    Gp c = two_input_gp(xc, kMinSigmaLengthScale);
    ArdSquaredExponentialKernel::Bounds ib;
    ib.length_scale = {1e-3, 1e2};
    ib.signal_variance = {1e-4, 1e2};
    ib.noise_variance = {1e-8, 1e1};
    Eigen::VectorXd il(xi.cols());
    il(0) = std::clamp(spread(xi.col(0)), 1e-3, 1e2);
    if (by_height) il(1) = spread(xi.col(1));
    Gp i(ArdSquaredExponentialKernel(il, 1.0, 0.1, ib), {.normalize_y = true});
    (void)o.fit(xo, yo, {.restarts = options.restarts, .seed = options.seed});
    (void)i.fit(xi, yi, {.restarts = options.restarts, .seed = options.seed + 1});
    (void)c.fit(xc, yr, {.restarts = options.restarts, .seed = options.seed + 2});
    std::vector<EfficiencyPoint> efficiency = fit_efficiency(samples);
    return GainModel(std::move(o), std::move(i), std::move(c), std::move(efficiency));
  }

  /// `fit` with the default options.
  [[nodiscard]] static GainModel fit(std::span<const RegionSample> samples) { return fit(samples, FitOptions{}); }

  /// The forecasts of re-mapping a region whose top-level image has semantic ratio `sigma_top`
  /// from `delta_h_m` [m] lower: ΔmIoU = μ_I(μ_O(Δh, σ)[, Δh]) (paper Eq. `eq:veg2h`) and μ_C.
  [[nodiscard]] GainForecast forecast(double delta_h_m, double sigma_top) const {
    GainForecast f;
    const Eigen::RowVector2d x(delta_h_m, sigma_top);
    f.delta_sigma = o_.predict_mean(x)(0);
    Eigen::MatrixXd qi(1, i_.dimension());
    qi(0, 0) = f.delta_sigma;
    if (qi.cols() == 2) qi(0, 1) = delta_h_m;
    const auto p = i_.predict(qi);
    f.delta_miou = p.mean(0);
    f.delta_miou_std = std::sqrt(std::max(0.0, p.variance(0)));
    if (c_) {  // χ = σ(1 − σ) · ρ
      const auto pc = c_->predict(x);
      const double sigma = boundary(sigma_top);
      f.relabelled = std::clamp(sigma * pc.mean(0), 0.0, 1.0);
      f.relabelled_std = sigma * std::sqrt(std::max(0.0, pc.variance(0)));
      const double noise = c_->kernel().noise_variance() * c_->y_std() * c_->y_std();
      f.relabelled_noisy_std = sigma * std::sqrt(std::max(0.0, pc.variance(0)) + noise);
    }
    return f;
  }

  /// The paper's online adaptation (§3.2.3): the descent's (Δh, σ_{h_max}) → Δσ joins O.
  void update(const DescentOutcome& out) {
    o_.add_observation(Eigen::Vector2d(out.top_altitude_m - out.sub_altitude_m, out.sigma_top),
                       out.sigma_top - out.sigma_sub);
    ++updates_;
    if (refit_every_ > 0 && updates_ % refit_every_ == 0)
      (void)o_.refit({.restarts = 1, .seed = static_cast<std::uint64_t>(updates_)});
  }

  [[nodiscard]] const Gp& o_model() const noexcept { return o_; }
  [[nodiscard]] const Gp& i_model() const noexcept { return i_; }
  /// C, absent in a model built without it (the paper's utility rule needs only O and I).
  [[nodiscard]] const std::optional<Gp>& c_model() const noexcept { return c_; }
  /// What I predicts from (its input dimension).
  [[nodiscard]] GainInputs gain_inputs() const noexcept {
    return i_.dimension() == 2 ? GainInputs::delta_sigma_and_height : GainInputs::delta_sigma;
  }
  [[nodiscard]] int refit_every() const noexcept { return refit_every_; }
  /// η at `delta_h_m` [m] (see the class comment); 0 for a model without C.
  [[nodiscard]] double efficiency(double delta_h_m) const noexcept {
    if (efficiency_.empty()) return 0.0;
    return detail::interpolate_flat(efficiency_, delta_h_m, &EfficiencyPoint::delta_h_m, &EfficiencyPoint::efficiency);
  }
  /// η's points (empty for a model without C).
  [[nodiscard]] const std::vector<EfficiencyPoint>& efficiency_points() const noexcept { return efficiency_; }
  /// The cell gain model (DescentCoverage::ranked), absent unless calibration set one.
  [[nodiscard]] const std::optional<CellGainModel>& cells() const noexcept { return cells_; }
  void set_cells(std::optional<CellGainModel> cells) { cells_ = std::move(cells); }
  /// The flown field's mean top-level entropy for the cell gain model (CellGainModel::
  /// set_field_entropy; nothing without one).
  void set_field_entropy(double u) noexcept {
    if (cells_) cells_->set_field_entropy(u);
  }
  /// @throws std::invalid_argument for a negative value.
  void set_refit_every(int k) {
    detail::require(k >= 0, "GainModel::set_refit_every: refit_every must be >= 0", k);
    refit_every_ = k;
  }
  /// Online updates since construction.
  [[nodiscard]] int updates() const noexcept { return updates_; }

 private:
  /// fit()'s η per descent height (samples of one candidate GSD share Δh up to rounding): the
  /// least-squares slope through the origin of the normalised field gain on χ, at least 0.
  static std::vector<EfficiencyPoint> fit_efficiency(std::span<const RegionSample> samples) {
    std::vector<EfficiencyPoint> efficiency;
    std::vector<double> num, den;
    for (const RegionSample& s : samples) {
      std::size_t k = 0;
      while (k < efficiency.size() && std::abs(efficiency[k].delta_h_m - s.delta_h_m) > 1e-6) ++k;
      if (k == efficiency.size()) {
        efficiency.push_back({s.delta_h_m, 0.0});
        num.push_back(0.0);
        den.push_back(0.0);
      }
      num[k] += s.normalized_field_gain() * s.relabelled.interest_share;
      den[k] += s.relabelled.interest_share * s.relabelled.interest_share;
    }
    for (std::size_t k = 0; k < efficiency.size(); ++k)
      efficiency[k].efficiency = den[k] > 0.0 ? std::max(0.0, num[k] / den[k]) : 0.0;
    std::sort(efficiency.begin(), efficiency.end(),
              [](const EfficiencyPoint& a, const EfficiencyPoint& b) { return a.delta_h_m < b.delta_h_m; });
    return efficiency;
  }

  /// σ(1 − σ) of σ clamped to [0, 1]: how much boundary of L a region can have.
  static double boundary(double sigma) {
    const double s = std::clamp(sigma, 0.0, 1.0);
    return s * (1.0 - s);
  }

  static double spread(const Eigen::VectorXd& v) {
    const double sd = std::sqrt((v.array() - v.mean()).square().mean());
    return std::clamp(sd, 1e-2, 1e2);
  }

  /// An unfitted GP on (Δh, σ) with length scales started at the inputs' spread and bounded
  /// below by `min_length_scale`.
  static Gp two_input_gp(const Eigen::MatrixXd& x, double min_length_scale = 1e-2) {
    ArdSquaredExponentialKernel::Bounds b;
    b.length_scale = {min_length_scale, 1e3};
    b.signal_variance = {1e-4, 1e2};
    b.noise_variance = {1e-8, 1e1};
    const auto start = [&](Eigen::Index d) { return std::max(spread(x.col(d)), min_length_scale); };
    return Gp(ArdSquaredExponentialKernel(Eigen::Vector2d(start(0), start(1)), 1.0, 0.1, b), {.normalize_y = true});
  }

  Gp o_;
  Gp i_;
  std::optional<Gp> c_;
  std::vector<EfficiencyPoint> efficiency_;
  std::optional<CellGainModel> cells_;
  int refit_every_ = 0;
  int updates_ = 0;
};

}  // namespace adaptseg
