#pragma once
/// @file
/// Exact Gaussian-process regression with a squared-exponential kernel (paper eq:prior,
/// eq:sqexp, eq:gp), hyperparameters by maximising the log marginal likelihood, online
/// updates by extending the Cholesky factor. A fitted model is saved and restored through its
/// State (`state()`, `from_state`); the file format is in gp_io.hpp, not here.
///
/// Needs Eigen 3.4 and LBFGSpp (through detail/lbfgs.hpp) only. The kernels: gp_kernel.hpp;
/// options and results: gp_options.hpp; vectorised loops: detail/gp_simd.hpp; dense algebra:
/// detail/gp_numerics.hpp; the likelihood: detail/gp_likelihood.hpp; the multi-start search:
/// detail/gp_optimize.hpp.
/// Conventions follow scikit-learn's `GaussianProcessRegressor` with the kernel
/// `ConstantKernel(sf2) * RBF(length_scale) + WhiteKernel(sn2)` and `alpha = 0`, so that
/// results can be checked against it (see tests/tools/make_gp_fixtures.py).

#include <adaptseg/core/detail/gp_likelihood.hpp>
#include <adaptseg/core/detail/gp_numerics.hpp>
#include <adaptseg/core/detail/gp_optimize.hpp>
#include <adaptseg/core/detail/gp_simd.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gp_kernel.hpp>
#include <adaptseg/core/gp_options.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

namespace adaptseg {

/// Exact GP regression, zero prior mean (paper eq:prior) on optionally normalised targets,
/// covariance from a `Kernel` (paper eq:sqexp), posterior by eq:gp computed as Rasmussen &
/// Williams Algorithm 2.1 (Cholesky of K_XX = K(X,X) + sn2 I).
///
/// - `fit` chooses the hyperparameters maximising the log marginal likelihood (R&W Eq. 5.8,
///   gradient Eq. 5.9) with bounded L-BFGS-B (LBFGSpp) from the kernel's hyperparameters,
///   then from `FitOptions::restarts` deterministic pseudo-random points in the log bounds
///   (scikit-learn's `n_restarts_optimizer`), keeping the best.
/// - Normalisation (`Options::normalize_y`, scikit-learn's `normalize_y=True`): targets become
///   (y - mean) / std, mean and std (population) computed by `fit` and then **frozen** until
///   the next `fit`/`refit`: `add_observation` and `condition` reuse them. Before any fit they
///   are 0 and 1. A std below 10 * eps * max(1, |mean|) is taken as 1 (constant targets). The
///   log marginal likelihood is that of the normalised targets (as in scikit-learn);
///   predictions are in the original units.
/// - Online use: `add_observation` extends the Cholesky factor in O(n^2), hyperparameters and
///   normalisation unchanged. Law: after `add_observation(x, y)` the model equals
///   `condition(X + x, y + y)` (same hyperparameters, frozen normalisation), up to rounding.
/// - Robustness: a factorisation that fails is retried with diagonal jitter
///   `initial_jitter * mean(diag K_XX) * 10^k`, k = 0..max_jitter_attempts-1; the jitter used
///   is kept (`jitter()`) and applied to later observations; failure after that throws
///   `NumericalError`. Non-finite inputs throw `std::invalid_argument`.
/// - Thread safety: const members may run concurrently; no global state, nothing printed.
///   Numerical kernels run with subnormals flushed to zero (x86 FTZ/DAZ, scoped to the call
///   and restored; see `detail::GpScopedFlushSubnormals`).
/// - Speed: the dense work of fitting (Cholesky, L^-1, K^-1) and of `predict` (exponentials,
///   forward substitution) runs in small kernels compiled for the baseline and, with GCC/Clang
///   on x86, also for AVX2 + FMA and AVX-512F, chosen once at run time by the CPU (define
///   ADAPTSEG_GP_NO_DISPATCH for the baseline only). Results agree across these to rounding.
///
/// Example:
/// @code
///   using adaptseg::GaussianProcess, adaptseg::SquaredExponentialKernel;
///   GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(0.5, 1.0, 0.1),
///                                                {.normalize_y = true});
///   Eigen::MatrixXd x(4, 1);  x << 0.0, 0.3, 0.6, 0.9;   // one sample per row
///   Eigen::VectorXd y(4);     y << 0.1, 0.5, 0.4, -0.2;
///   const auto summary = gp.fit(x, y, {.restarts = 3});  // summary.status: FitStatus
///   Eigen::MatrixXd xq(1, 1); xq << 0.45;
///   const auto p = gp.predict(xq);                     // p.mean(0), p.variance(0)
///   gp.add_observation(Eigen::VectorXd::Constant(1, 1.2), -0.4);  // O(n^2), no refit
///   auto same = GaussianProcess<SquaredExponentialKernel>::from_state(gp.state());
/// @endcode
template <Kernel K>
class GaussianProcess {
 public:
  using KernelType = K;

  using Options = GpOptions;
  using FitOptions = GpFitOptions;
  using StartSummary = GpStartSummary;
  using FitSummary = GpFitSummary;
  using Prediction = GpPrediction;
  using CovariancePrediction = GpCovariancePrediction;

  /// @throws std::invalid_argument if `options` is invalid (message names the field).
  explicit GaussianProcess(K kernel, const Options& options = {}) : kernel_(std::move(kernel)), options_(options) {
    options_.validate();
  }

  // ---- fitting ------------------------------------------------------------------------------

  /// Replaces the training data by (x, y), recomputes the normalisation, optionally optimises
  /// the hyperparameters, and factorises. O(n^3) per LML evaluation.
  /// @param x n x D inputs, one sample per row, n >= 1, finite.
  /// @param y n targets [output units], finite.
  /// @param fit_options whether and how to optimise the hyperparameters (validated).
  /// @throws std::invalid_argument on bad input or options; NumericalError if K_XX cannot be
  ///         factorised even with jitter at every hyperparameter tried.
  FitSummary fit(const Eigen::Ref<const Eigen::MatrixXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y,
                 const FitOptions& fit_options = {}) {
    fit_options.validate();
    detail::gp_check_training_data(kernel_, x, y);
    store_data(x, y);
    compute_normalization();
    return fit_current(fit_options);
  }

  /// `fit` on the current training data (normalisation recomputed): the scheduled
  /// re-optimisation after online updates.
  /// @throws as `fit`; std::invalid_argument if there is no data.
  FitSummary refit(const FitOptions& fit_options = {}) {
    fit_options.validate();
    detail::require(n_ > 0, "GaussianProcess::refit: number of training samples must be > 0", n_);
    compute_normalization();
    return fit_current(fit_options);
  }

  /// Replaces the training data, keeping hyperparameters and the frozen normalisation, and
  /// factorises in O(n^3): the batch equivalent of a sequence of `add_observation`.
  /// @throws std::invalid_argument on bad input; NumericalError.
  void condition(const Eigen::Ref<const Eigen::MatrixXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y) {
    detail::gp_check_training_data(kernel_, x, y);
    store_data(x, y);
    yn_.head(n_) = (y_.head(n_).array() - y_mean_) / y_std_;
    factorize();
  }

  /// Sets new hyperparameters (no optimisation) and refactorises the current data.
  /// @throws std::invalid_argument if the kernel does not accept the data's dimension.
  void set_kernel(K kernel) {
    if (n_ > 0)
      detail::require(kernel.accepts_dimension(dimension_),
                      "GaussianProcess::set_kernel: kernel does not accept input dimension", dimension_);
    kernel_ = std::move(kernel);
    if (n_ > 0) factorize();
  }

  /// Adds one observation in O(n^2) by extending the Cholesky factor; hyperparameters and
  /// normalisation stay. `predict_mean` then costs O(n^2) more per call until the next `fit`,
  /// `refit`, `condition` or `set_kernel`. An extended factor that is not positive definite (a
  /// nearly repeated input, tiny noise) falls back to an O(n^3) refactorisation with jitter.
  /// @param x input of dimension D (the data's, or any the kernel accepts if there is none).
  /// @param y target [output units].
  /// @throws std::invalid_argument on non-finite values or a wrong dimension; NumericalError.
  void add_observation(const Eigen::Ref<const Eigen::VectorXd>& x, double y) {
    detail::require(x.allFinite(), "GaussianProcess::add_observation: x must be finite", x.transpose());
    detail::require_finite(y, "GaussianProcess::add_observation: y");
    if (n_ == 0) {
      detail::require(kernel_.accepts_dimension(x.size()),
                      "GaussianProcess::add_observation: kernel does not accept the dimension of x", x.size());
      dimension_ = x.size();
    }
    detail::require(x.size() == dimension_, "GaussianProcess::add_observation: dimension of x", x.size());
    reserve(n_ + 1);
    const Eigen::Index n = n_;
    x_.row(n) = x.transpose();
    y_(n) = y;
    yn_(n) = (y - y_mean_) / y_std_;
    if (n == 0) {
      n_ = 1;
      factorize();
      return;
    }
    const detail::GpScopedFlushSubnormals flush;
    const Eigen::VectorXd k = kernel_.cross_covariance(x_.topRows(n), x_.row(n));
    const double kxx = kernel_.prior_variance(x_.row(n))(0) + kernel_.noise_variance() + jitter_;
    auto l_old = l_.topLeftCorner(n, n).template triangularView<Eigen::Lower>();
    const Eigen::VectorXd l = l_old.solve(k);
    const double d2 = kxx - l.squaredNorm();
    if (!(d2 > 0.0) || !std::isfinite(d2)) {
      n_ = n + 1;
      factorize();
      return;
    }
    const double lnn = std::sqrt(d2);
    l_.row(n).head(n) = l.transpose();
    l_(n, n) = lnn;
    z_(n) = (yn_(n) - l.dot(z_.head(n))) / lnn;
    quad_ += z_(n) * z_(n);
    half_log_det_ += std::log(lnn);
    n_ = n + 1;
    // alpha = L^-T z would cost a second pass over L; `predict` works from z, and
    // `predict_mean` recomputes alpha while it is stale.
    alpha_current_ = false;
  }

  /// Ensures room for `capacity` samples so that `add_observation` does not reallocate
  /// (`fit` and `condition` leave room for max(32, n/4) more; beyond that a reallocation
  /// copies the factor once, O(n^2), and adds the same headroom again). Memory: capacity^2
  /// doubles for the factor.
  void reserve(Eigen::Index capacity) {
    if (capacity <= x_.rows() && dimension_ == x_.cols()) return;
    const Eigen::Index wanted = std::max(capacity, n_ + std::max<Eigen::Index>(32, n_ / 4));
    // A multiple of kGpRowGroup rows: the factor is computed in place by the dense kernels.
    const Eigen::Index cap = (wanted + detail::kGpRowGroup - 1) / detail::kGpRowGroup * detail::kGpRowGroup;
    Eigen::MatrixXd x(cap, dimension_);
    Eigen::VectorXd y(cap), yn(cap), z(cap), alpha(cap);
    Eigen::MatrixXd l(cap, cap);
    if (n_ > 0) {
      x.topRows(n_) = x_.topRows(n_);
      y.head(n_) = y_.head(n_);
      yn.head(n_) = yn_.head(n_);
      z.head(n_) = z_.head(n_);
      alpha.head(n_) = alpha_.head(n_);
      l.topLeftCorner(n_, n_).template triangularView<Eigen::Lower>() =
          l_.topLeftCorner(n_, n_).template triangularView<Eigen::Lower>();
    }
    x_ = std::move(x);
    y_ = std::move(y);
    yn_ = std::move(yn);
    z_ = std::move(z);
    alpha_ = std::move(alpha);
    l_ = std::move(l);
  }

  // ---- prediction ---------------------------------------------------------------------------

  /// Posterior mean and variance at each row of `xq` (paper eq:gp, R&W Alg. 2.1), in the
  /// original target units; variances are clipped at 0 like scikit-learn. With no training
  /// data, the prior. O(m n^2).
  /// @param xq m x D query inputs, finite.
  /// @param kind latent f variance (default) or noisy y variance.
  /// @throws std::invalid_argument on a wrong dimension or non-finite input.
  [[nodiscard]] Prediction predict(const Eigen::Ref<const Eigen::MatrixXd>& xq,
                                   PredictiveVariance kind = PredictiveVariance::kLatent) const {
    detail::gp_check_query(kernel_, dimension_, xq);
    const detail::GpScopedFlushSubnormals flush;
    const Eigen::Index m = xq.rows();
    Prediction out{Eigen::VectorXd::Zero(m), kernel_.prior_variance(xq)};
    if (n_ > 0) {
      // Per block of queries: K*^T (queries x n), then v = L^-1 k* for each query with
      // mean = v^T z (= k*^T K^-1 y) and variance = prior - v^T v, all in one pass.
      constexpr Eigen::Index kBlock = detail::kGpQueryBlock;
      const detail::GpPackedFactor factor(l_.topLeftCorner(n_, n_), z_.head(n_));
      Eigen::MatrixXd c = Eigen::MatrixXd::Zero(kBlock, factor.n4);
      Eigen::Matrix<double, kBlock, 1> mean, ssq;
      for (Eigen::Index s = 0; s < m; s += kBlock) {
        const Eigen::Index rows = std::min(kBlock, m - s);
        c.topLeftCorner(rows, n_) = kernel_.cross_covariance(xq.middleRows(s, rows), x_.topRows(n_));
        detail::gp_lower_solve(factor, c.data(), rows, mean.data(), ssq.data());
        out.mean.segment(s, rows) = mean.head(rows);
        out.variance.segment(s, rows) -= ssq.head(rows);
      }
    }
    out.variance = out.variance.cwiseMax(0.0);
    if (kind == PredictiveVariance::kNoisy) out.variance.array() += kernel_.noise_variance();
    out.mean = out.mean.array() * y_std_ + y_mean_;
    out.variance *= y_std_ * y_std_;
    return out;
  }

  /// Posterior mean only, O(m n) (plus O(n^2) after `add_observation`, see there).
  /// @throws std::invalid_argument on a wrong dimension or non-finite input.
  [[nodiscard]] Eigen::VectorXd predict_mean(const Eigen::Ref<const Eigen::MatrixXd>& xq) const {
    detail::gp_check_query(kernel_, dimension_, xq);
    Eigen::VectorXd mean = Eigen::VectorXd::Zero(xq.rows());
    if (n_ > 0) {
      const detail::GpScopedFlushSubnormals flush;
      const Eigen::MatrixXd ks = kernel_.cross_covariance(xq, x_.topRows(n_));
      if (alpha_current_) {
        mean.noalias() = ks * alpha_.head(n_);
      } else {
        const Eigen::VectorXd alpha =
            l_.topLeftCorner(n_, n_).template triangularView<Eigen::Lower>().transpose().solve(z_.head(n_));
        mean.noalias() = ks * alpha;
      }
    }
    return (mean.array() * y_std_ + y_mean_).matrix();
  }

  /// Posterior mean and full covariance K(X*,X*) - K(X*,X) K_XX^-1 K(X,X*) (eq:gp), plus
  /// sn2 I for `kNoisy`; original units. O(m^2 n + m n^2) time, m^2 memory.
  /// @throws std::invalid_argument on a wrong dimension or non-finite input.
  [[nodiscard]] CovariancePrediction predict_covariance(const Eigen::Ref<const Eigen::MatrixXd>& xq,
                                                        PredictiveVariance kind = PredictiveVariance::kLatent) const {
    detail::gp_check_query(kernel_, dimension_, xq);
    const detail::GpScopedFlushSubnormals flush;
    CovariancePrediction out{Eigen::VectorXd::Zero(xq.rows()), kernel_.cross_covariance(xq, xq)};
    if (n_ > 0) {
      Eigen::MatrixXd v = kernel_.cross_covariance(x_.topRows(n_), xq);
      l_.topLeftCorner(n_, n_).template triangularView<Eigen::Lower>().solveInPlace(v);
      out.mean.noalias() = v.transpose() * z_.head(n_);
      out.covariance.noalias() -= v.transpose() * v;
    }
    if (kind == PredictiveVariance::kNoisy) out.covariance.diagonal().array() += kernel_.noise_variance();
    out.mean = out.mean.array() * y_std_ + y_mean_;
    out.covariance *= y_std_ * y_std_;
    return out;
  }

  // ---- likelihood ---------------------------------------------------------------------------

  /// Log marginal likelihood of the (normalised) training targets at the current
  /// hyperparameters (R&W Eq. 5.8 / Alg. 2.1 line 8): -y^T K^-1 y / 2 - sum log L_ii - n/2 log 2pi.
  /// 0 with no data.
  [[nodiscard]] double log_marginal_likelihood() const {
    if (n_ == 0) return 0.0;
    return -0.5 * quad_ - half_log_det_ - 0.5 * static_cast<double>(n_) * std::log(2.0 * std::numbers::pi);
  }

  /// Log marginal likelihood of the current training data at log hyperparameters `theta`, and
  /// optionally its gradient w.r.t. theta (R&W Eq. 5.9: 1/2 tr((a a^T - K^-1) dK/dtheta)).
  /// O(n^3); the model is not changed.
  /// @throws std::invalid_argument on a wrong-size or non-finite theta, or no data;
  ///         NumericalError if K_XX cannot be factorised even with jitter.
  [[nodiscard]] double log_marginal_likelihood(const Eigen::VectorXd& theta,
                                               Eigen::VectorXd* gradient = nullptr) const {
    detail::require(n_ > 0, "GaussianProcess::log_marginal_likelihood: number of training samples must be > 0", n_);
    K kernel = kernel_;
    kernel.set_log_parameters(theta);
    detail::GpWorkspace work;
    return training().log_likelihood(kernel, gradient, work);
  }

  // ---- accessors ----------------------------------------------------------------------------

  [[nodiscard]] const K& kernel() const { return kernel_; }
  [[nodiscard]] const Options& options() const { return options_; }
  [[nodiscard]] Eigen::Index size() const { return n_; }                            ///< training samples n
  [[nodiscard]] Eigen::Index dimension() const { return dimension_; }               ///< D (0 before any data)
  [[nodiscard]] Eigen::MatrixXd training_inputs() const { return x_.topRows(n_); }  ///< n x D
  [[nodiscard]] Eigen::VectorXd training_targets() const { return y_.head(n_); }    ///< n, original units
  [[nodiscard]] double y_mean() const { return y_mean_; }  ///< frozen normalisation mean (0 without normalize_y)
  [[nodiscard]] double y_std() const { return y_std_; }    ///< frozen normalisation std (1 without normalize_y)
  /// Diagonal jitter in use (0 when the plain factorisation succeeded).
  [[nodiscard]] double jitter() const { return jitter_; }

  // ---- persistence --------------------------------------------------------------------------

  /// Everything that defines a fitted model: what a file format stores to restore it exactly.
  struct State {
    K kernel;  ///< hyperparameters and their bounds
    Options options;
    double y_mean = 0.0;  ///< frozen target normalisation (0 and 1 without normalize_y)
    double y_std = 1.0;
    Eigen::MatrixXd inputs;   ///< n x D training inputs (online additions included)
    Eigen::VectorXd targets;  ///< n training targets [output units]
  };

  /// The model's state (see State); `from_state(state())` predicts exactly as this model.
  [[nodiscard]] State state() const {
    return State{kernel_, options_, y_mean_, y_std_, training_inputs(), training_targets()};
  }

  /// Restores a model from its state and factorises it.
  /// @throws std::invalid_argument for invalid options, a y_std that is not finite and > 0, a
  ///         y_mean that is not finite, inputs and targets of different lengths, non-finite
  ///         data, or a dimension the kernel does not accept; NumericalError.
  [[nodiscard]] static GaussianProcess from_state(State s) {
    detail::require(std::isfinite(s.y_std) && s.y_std > 0.0,
                    "GaussianProcess::from_state: y_std must be finite and > 0", s.y_std);
    detail::require_finite(s.y_mean, "GaussianProcess::from_state: y_mean");
    GaussianProcess gp(std::move(s.kernel), s.options);
    gp.y_mean_ = s.y_mean;
    gp.y_std_ = s.y_std;
    if (s.inputs.rows() > 0 || s.targets.size() > 0) {
      detail::require(gp.kernel_.accepts_dimension(s.inputs.cols()),
                      "GaussianProcess::from_state: the kernel does not accept dimension", s.inputs.cols());
      gp.condition(s.inputs, s.targets);
    } else {
      gp.dimension_ = s.inputs.cols();
    }
    return gp;
  }

 private:
  void store_data(const Eigen::Ref<const Eigen::MatrixXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y) {
    n_ = 0;
    dimension_ = x.cols();
    x_.resize(0, dimension_);
    reserve(x.rows() + std::max<Eigen::Index>(32, x.rows() / 4));  // headroom for online updates
    n_ = x.rows();
    x_.topRows(n_) = x;
    y_.head(n_) = y;
  }

  void compute_normalization() {
    if (options_.normalize_y) {
      const auto y = y_.head(n_).array();
      y_mean_ = y.mean();
      const double sd = std::sqrt((y - y_mean_).square().mean());
      y_std_ = sd < 10.0 * std::numeric_limits<double>::epsilon() * std::max(1.0, std::abs(y_mean_)) ? 1.0 : sd;
    } else {
      y_mean_ = 0.0;
      y_std_ = 1.0;
    }
    yn_.head(n_) = (y_.head(n_).array() - y_mean_) / y_std_;
  }

  /// The training data as the likelihood reads it (detail/gp_likelihood.hpp).
  [[nodiscard]] detail::GpTraining<K> training() const { return {x_.topRows(n_), yn_.head(n_), options_, kernel_}; }

  /// Factorises K_XX of the current data and hyperparameters into l_, z_, alpha_.
  void factorize() {
    ADAPTSEG_ASSERT(n_ > 0);
    const detail::GpScopedFlushSubnormals flush;
    const Eigen::Index n = n_;
    reserve(detail::gp_padded_rows(n));
    jitter_ = training().factorize_into(kernel_, l_);
    const auto l = l_.topLeftCorner(n, n);
    z_.head(n) = l.template triangularView<Eigen::Lower>().solve(yn_.head(n));
    alpha_.head(n) = l.template triangularView<Eigen::Lower>().transpose().solve(z_.head(n));
    alpha_current_ = true;
    quad_ = z_.head(n).squaredNorm();
    half_log_det_ = l.diagonal().array().log().sum();
  }

  FitSummary fit_current(const FitOptions& fo) {
    FitSummary summary;
    if (fo.optimize) optimize(fo, summary);
    factorize();
    summary.log_parameters = kernel_.log_parameters();
    summary.log_marginal_likelihood = log_marginal_likelihood();
    return summary;
  }

  void optimize(const FitOptions& fo, FitSummary& summary) {
    const Eigen::VectorXd theta = detail::gp_multistart_minimize(
        kernel_.log_parameters(), kernel_.log_lower_bounds(), kernel_.log_upper_bounds(), fo, summary, [this] {
          return detail::GpObjective<K>{training(), kernel_, {}, {}, std::numeric_limits<double>::infinity(), 0};
        });
    kernel_.set_log_parameters(theta);
  }

  K kernel_;
  Options options_;
  Eigen::Index n_ = 0;
  Eigen::Index dimension_ = 0;
  // Storage with capacity (rows/size >= n_), so that add_observation is O(n^2) without copies.
  Eigen::MatrixXd x_;      // inputs, first n_ rows
  Eigen::VectorXd y_;      // targets, original units
  Eigen::VectorXd yn_;     // normalised targets
  Eigen::MatrixXd l_;      // lower Cholesky factor of K_XX (+ jitter_), top-left n_ x n_
  Eigen::VectorXd z_;      // L^-1 yn
  Eigen::VectorXd alpha_;  // K_XX^-1 yn, valid while alpha_current_
  bool alpha_current_ = false;
  double y_mean_ = 0.0;
  double y_std_ = 1.0;
  double jitter_ = 0.0;
  double quad_ = 0.0;          // yn^T K^-1 yn
  double half_log_det_ = 0.0;  // sum log L_ii
};

}  // namespace adaptseg
