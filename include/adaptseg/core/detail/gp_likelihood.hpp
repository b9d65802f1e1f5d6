#pragma once
/// @file
/// Internals of gaussian_process.hpp: the training covariance factorised with jitter retries,
/// the log marginal likelihood with its gradient (Rasmussen & Williams Eq. 5.8 and 5.9) on the
/// padded matrices the dense kernels of detail/gp_simd.hpp work on, the minimiser's objective,
/// and the checks of training data and queries. `fit` (through
/// gp_log_likelihood) and the final factorisation share gp_factorize_into, so the optimiser and
/// the model agree to the last bit.

#include <adaptseg/core/detail/gp_numerics.hpp>
#include <adaptseg/core/detail/gp_simd.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gp_options.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#include <cmath>
#include <exception>
#include <limits>
#include <numbers>
#include <sstream>

namespace adaptseg::detail {

/// Columns n4 = 4 ceil(n / 4) of the padded matrices the dense kernels work on.
[[nodiscard]] inline Eigen::Index gp_padded_columns(Eigen::Index n) { return (n + 3) / 4 * 4; }
/// Their leading dimension: gp_padded_columns(n) rounded up to a multiple of kGpRowGroup.
[[nodiscard]] inline Eigen::Index gp_padded_rows(Eigen::Index n) {
  return (gp_padded_columns(n) + kGpRowGroup - 1) / kGpRowGroup * kGpRowGroup;
}

/// Scratch of gp_log_likelihood, kept across the evaluations of one optimiser run.
struct GpWorkspace {
  Eigen::MatrixXd a;   // K, then L, then K^-1 and the gradient weights (lower triangles)
  Eigen::MatrixXd xt;  // (L^-1)^T
};

/// The training data a likelihood reads: the first n inputs `x` and normalised targets `yn`,
/// the model's options (jitter) and its kernel (named in the messages).
template <class K>
struct GpTraining {
  Eigen::Ref<const Eigen::MatrixXd> x;
  Eigen::Ref<const Eigen::VectorXd> yn;
  const GpOptions& options;
  const K& model_kernel;

  /// Runs `factor()` (true on success); after a failure, `reset(jitter)` restores the matrix
  /// with `jitter` added to its diagonal and `factor()` runs again, jitter
  /// `initial_jitter * scale * 10^k`, k = 0..max_jitter_attempts-1. Returns the jitter used.
  /// @throws NumericalError when the last attempt fails.
  template <typename Reset, typename Factor>
  double factor_with_jitter(double scale, Reset&& reset, Factor&& factor) const {
    double jitter = 0.0;
    for (int attempt = 0;; ++attempt) {
      if (attempt > 0) {
        jitter = options.initial_jitter * scale * std::pow(10.0, attempt - 1);
        reset(jitter);
      }
      if (factor()) return jitter;
      if (attempt >= options.max_jitter_attempts) {
        std::ostringstream os;
        os << "GaussianProcess: covariance matrix (n = " << x.rows() << ") is not positive definite after "
           << options.max_jitter_attempts << " jitter retries (last jitter " << jitter
           << "); inputs nearly repeated with too little noise, or hyperparameters out of range: "
           << model_kernel.log_parameters().transpose();
        throw NumericalError(os.str());
      }
    }
  }

  /// K_XX for `kernel` into the top-left of `a` (padded to gp_padded_columns(n) with the
  /// identity; a.rows() a multiple of kGpRowGroup, >= gp_padded_rows(n)), factorised in place
  /// (dispatched Cholesky up to gp_dense_kernel_limit(), Eigen's blocked LLT above) with jitter
  /// retries: lower(a) = L. Returns the jitter.
  double factorize_into(const K& kernel, Eigen::MatrixXd& a) const {
    const Eigen::Index n = x.rows();
    const Eigen::Index n4 = gp_padded_columns(n);
    ADAPTSEG_ASSERT(a.rows() % kGpRowGroup == 0 && a.rows() >= gp_padded_rows(n) && a.cols() >= n4);
    const double noise = kernel.noise_variance();
    const auto fill = [&](double jitter) {
      a.leftCols(n4).setZero();
      a.topLeftCorner(n, n) = kernel.cross_covariance(x, x);
      a.diagonal().head(n).array() += noise + jitter;
      a.diagonal().segment(n, n4 - n).setOnes();
    };
    fill(0.0);
    const double scale = std::abs(a.diagonal().head(n).mean());
    if (n <= gp_dense_kernel_limit())
      return factor_with_jitter(scale, fill, [&] { return gp_cholesky(a.data(), n4, a.rows()); });
    return factor_with_jitter(scale, fill, [&] {
      auto l = a.topLeftCorner(n, n);
      Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(l);
      return llt.info() == Eigen::Success && l.diagonal().allFinite() && (l.diagonal().array() > 0.0).all();
    });
  }

  /// LML (and gradient) of the normalised targets for `kernel`. The dense work (Cholesky,
  /// L^-1, K^-1 = L^-T L^-1: n^3 flops in all) runs in the dispatched kernels up to
  /// gp_dense_kernel_limit(), in Eigen above.
  /// @throws NumericalError for a likelihood that is not finite, and as factorize_into.
  double log_likelihood(const K& kernel, Eigen::VectorXd* gradient, GpWorkspace& ws) const {
    const GpScopedFlushSubnormals flush;
    const Eigen::Index n = x.rows();
    const Eigen::Index n4 = gp_padded_columns(n);
    const Eigen::Index ld = gp_padded_rows(n);
    Eigen::MatrixXd& a = ws.a;
    a.resize(ld, n4);
    factorize_into(kernel, a);
    const auto l = a.topLeftCorner(n, n);
    const Eigen::VectorXd z = l.template triangularView<Eigen::Lower>().solve(yn);
    const Eigen::VectorXd alpha = l.template triangularView<Eigen::Lower>().transpose().solve(z);
    const double lml = -0.5 * z.squaredNorm() - l.diagonal().array().log().sum() -
                       0.5 * static_cast<double>(n) * std::log(2.0 * std::numbers::pi);
    if (!std::isfinite(lml)) {
      std::ostringstream os;
      os << "GaussianProcess: log marginal likelihood is not finite at log hyperparameters "
         << kernel.log_parameters().transpose();
      throw NumericalError(os.str());
    }
    if (gradient != nullptr) {
      auto w = a.topLeftCorner(n, n);
      if (n <= gp_dense_kernel_limit()) {
        ws.xt.setZero(ld, n4);
        gp_invert_lower(a.data(), ws.xt.data(), n4, ld);
        gp_gram(ws.xt.data(), a.data(), n4, ld);  // lower(a) = K^-1
      } else {
        gp_invert_lower_in_place(w);
        gp_lower_gram_in_place(w);
      }
      for (Eigen::Index j = 0; j < n; ++j) w.col(j).tail(n - j) = alpha.tail(n - j) * alpha(j) - w.col(j).tail(n - j);
      *gradient = 0.5 * kernel.contract_gradient(x, w);
    }
    return lml;
  }
};

/// Objective of the bounded minimiser (gp_multistart_minimize): -LML of `training` and its
/// gradient at log hyperparameters theta; remembers the best point seen; a failure is reported
/// as GpObjectiveAborted.
template <class K>
struct GpObjective {
  GpTraining<K> training;
  K kernel;
  GpWorkspace work;
  Eigen::VectorXd best_theta;
  double best_value = std::numeric_limits<double>::infinity();
  int evaluations = 0;

  double operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& grad) {
    try {
      kernel.set_log_parameters(theta);
      Eigen::VectorXd g;
      const double lml = training.log_likelihood(kernel, &g, work);
      ++evaluations;
      grad = -g;
      if (-lml < best_value) {
        best_value = -lml;
        best_theta = theta;
      }
      return -lml;
    } catch (...) {
      throw GpObjectiveAborted{std::current_exception()};
    }
  }
};

/// GaussianProcess's checks of training data: at least one sample, a dimension the kernel
/// accepts, as many targets as samples, all finite.
/// @throws std::invalid_argument naming the first that fails.
template <class K>
void gp_check_training_data(const K& kernel, const Eigen::Ref<const Eigen::MatrixXd>& x,
                            const Eigen::Ref<const Eigen::VectorXd>& y) {
  require(x.rows() >= 1, "GaussianProcess: number of training samples (rows of x) must be >= 1", x.rows());
  require(kernel.accepts_dimension(x.cols()),
          "GaussianProcess: kernel does not accept the input dimension (columns of x)", x.cols());
  require(y.size() == x.rows(), "GaussianProcess: size of y must equal the rows of x, size", y.size());
  require(x.allFinite(), "GaussianProcess: x must be finite, rows", x.rows());
  require(y.allFinite(), "GaussianProcess: y must be finite, size", y.size());
}

/// GaussianProcess's checks of a query: the data's dimension (`dimension` > 0) or one the
/// kernel accepts, finite.
/// @throws std::invalid_argument naming the first that fails.
template <class K>
void gp_check_query(const K& kernel, Eigen::Index dimension, const Eigen::Ref<const Eigen::MatrixXd>& xq) {
  if (dimension > 0) {
    require(xq.cols() == dimension, "GaussianProcess::predict: columns of the query must equal D", xq.cols());
  } else {
    require(kernel.accepts_dimension(xq.cols()), "GaussianProcess::predict: kernel does not accept the query dimension",
            xq.cols());
  }
  require(xq.allFinite(), "GaussianProcess::predict: query inputs must be finite, rows", xq.rows());
}

}  // namespace adaptseg::detail
