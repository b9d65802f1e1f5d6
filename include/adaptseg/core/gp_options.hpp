#pragma once
/// @file
/// The options and results of `GaussianProcess` (gaussian_process.hpp), which names them
/// `GaussianProcess<K>::Options`, `FitOptions`, `FitSummary`, `Prediction`, ...: model and
/// hyperparameter-search options with their validation, what a search did, what a prediction
/// gives. Independent of the kernel.

#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/core/error.hpp>

#include <Eigen/Core>

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <string_view>
#include <vector>

namespace adaptseg {

/// What a predictive variance describes.
enum class PredictiveVariance {
  kLatent,  ///< variance of the latent f(x*) (eq:gp's sigma_*^2); scikit-learn's std with the
            ///< WhiteKernel removed from the kernel.
  kNoisy,   ///< variance of a new observation y* = f(x*) + noise: latent + sn2; what
            ///< scikit-learn's `predict(return_std=True)` returns for this kernel.
};

/// How a hyperparameter search ended (an expected outcome, never an exception).
enum class FitStatus {
  kNotOptimized,      ///< `FitOptions::optimize` was false: hyperparameters kept as given.
  kConverged,         ///< projected-gradient or relative-reduction criterion met.
  kMaxIterations,     ///< iteration budget exhausted; the best point seen is kept.
  kLineSearchFailed,  ///< no acceptable step (typical at a flat optimum); best point kept.
  kNumericalFailure,  ///< the covariance could not be factorised along the path; best point kept.
};

/// Every FitStatus by name.
inline constexpr std::array<detail::NamedValue<FitStatus>, 5> kFitStatuses{{
    {FitStatus::kNotOptimized, "not_optimized"},
    {FitStatus::kConverged, "converged"},
    {FitStatus::kMaxIterations, "max_iterations"},
    {FitStatus::kLineSearchFailed, "line_search_failed"},
    {FitStatus::kNumericalFailure, "numerical_failure"},
}};

/// Readable name of a `FitStatus`: "converged", say; "unknown" for a value out of range.
[[nodiscard]] inline std::string_view to_string(FitStatus s) { return detail::name_or(kFitStatuses, s, "unknown"); }

/// Model options (`GaussianProcess<K>::Options`), validated once by the constructor.
struct GpOptions {
  /// Subtract the target mean and divide by the target std at `fit` (then frozen).
  bool normalize_y = false;
  /// First jitter, relative to the mean of diag(K_XX); > 0 and finite.
  double initial_jitter = 1e-10;
  /// Number of jitter retries (each 10x the previous) after a failed Cholesky; 0..30.
  int max_jitter_attempts = 8;

  /// @throws std::invalid_argument naming the field.
  void validate() const {
    detail::require_positive(initial_jitter, "GaussianProcess::Options::initial_jitter");
    detail::require(max_jitter_attempts >= 0 && max_jitter_attempts <= 30,
                    "GaussianProcess::Options::max_jitter_attempts must be in [0, 30]", max_jitter_attempts);
  }
};

/// Hyperparameter-search options (`GaussianProcess<K>::FitOptions`), validated by `fit`/`refit`.
struct GpFitOptions {
  /// false: keep the kernel's hyperparameters, only condition on the data.
  bool optimize = true;
  /// Extra starts after the first (from the kernel's hyperparameters), uniform in the log
  /// bounds; >= 0.
  int restarts = 3;
  /// Seed of the restart points; same seed, same points.
  std::uint64_t seed = 0;
  /// L-BFGS-B iterations per start; >= 1.
  int max_iterations = 15000;
  /// Stop when the projected gradient's max-norm is below this (scipy's gtol); >= 0.
  double gradient_tolerance = 1e-5;
  /// Stop when the relative reduction of -LML is below this (scipy's factr * eps); >= 0.
  double relative_tolerance = 1e7 * std::numeric_limits<double>::epsilon();
  /// L-BFGS memory (scipy's maxcor); >= 1.
  int history = 10;

  /// @throws std::invalid_argument naming the field.
  void validate() const {
    detail::require(restarts >= 0, "GaussianProcess::FitOptions::restarts must be >= 0", restarts);
    detail::require(max_iterations >= 1, "GaussianProcess::FitOptions::max_iterations must be >= 1", max_iterations);
    detail::require(std::isfinite(gradient_tolerance) && gradient_tolerance >= 0.0,
                    "GaussianProcess::FitOptions::gradient_tolerance must be finite and >= 0", gradient_tolerance);
    detail::require(std::isfinite(relative_tolerance) && relative_tolerance >= 0.0,
                    "GaussianProcess::FitOptions::relative_tolerance must be finite and >= 0", relative_tolerance);
    detail::require(history >= 1, "GaussianProcess::FitOptions::history must be >= 1", history);
  }
};

/// One optimiser start.
struct GpStartSummary {
  Eigen::VectorXd initial_log_parameters;
  Eigen::VectorXd log_parameters;  ///< best point of this start
  double log_marginal_likelihood = -std::numeric_limits<double>::infinity();
  int iterations = 0;
  int evaluations = 0;
  FitStatus status = FitStatus::kNotOptimized;
};

/// Result of `fit`/`refit`.
struct GpFitSummary {
  FitStatus status = FitStatus::kNotOptimized;  ///< status of the chosen start
  double log_marginal_likelihood = 0.0;         ///< at the chosen hyperparameters
  Eigen::VectorXd log_parameters;               ///< chosen hyperparameters (log)
  std::vector<GpStartSummary> starts;           ///< empty if not optimised
  std::size_t best_start = 0;
  int evaluations = 0;  ///< LML + gradient evaluations over all starts
};

/// Posterior mean [output units] and variance [output units^2] at query rows.
struct GpPrediction {
  Eigen::VectorXd mean;
  Eigen::VectorXd variance;
};

/// Posterior mean and full covariance at query rows.
struct GpCovariancePrediction {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
};

}  // namespace adaptseg
