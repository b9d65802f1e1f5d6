#pragma once
/// @file
/// Internals of gaussian_process.hpp: the multi-start hyperparameter search. Each start runs
/// the bounded L-BFGS-B minimiser (detail/lbfgs.hpp) on -LML, first from the kernel's
/// hyperparameters, then from `FitOptions::restarts` seeded pseudo-random points in the log
/// bounds (scikit-learn's `n_restarts_optimizer`); a failed line search restarts from the best
/// point seen with a fresh quasi-Newton memory while that still improves (as scipy's driver).

#include <adaptseg/core/detail/gp_numerics.hpp>
#include <adaptseg/core/detail/lbfgs.hpp>
#include <adaptseg/core/error.hpp>
#include <adaptseg/core/gp_options.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <string>
#include <utility>

namespace adaptseg::detail {

/// Fresh L-BFGS-B runs per start after a failed line search.
inline constexpr int kGpMaxSolverRestarts = 20;

/// One start of gp_multistart_minimize() from `theta`: the minimiser signals a failed line
/// search (or a non-descent direction from its subspace minimisation) by an exception; like
/// scipy's driver, restart from the best point seen with a fresh quasi-Newton memory while that
/// still improves the objective. Fills `start`'s iterations and status.
template <class Objective>
void gp_minimize_start(Objective& objective, Eigen::VectorXd& theta, const Eigen::VectorXd& lower,
                       const Eigen::VectorXd& upper, const GpFitOptions& fo, BoxMinimizerSettings& settings,
                       GpStartSummary& start) {
  int runs = 0;
  while (true) {
    const double before = objective.best_value;
    settings.max_iterations = std::max(1, fo.max_iterations - start.iterations);
    try {
      start.iterations += minimize_in_box(objective, theta, lower, upper, settings);
      start.status = start.iterations >= fo.max_iterations ? FitStatus::kMaxIterations : FitStatus::kConverged;
      break;
    } catch (const GpObjectiveAborted& aborted) {
      try {
        std::rethrow_exception(aborted.cause);
      } catch (const NumericalError&) {
        start.status = FitStatus::kNumericalFailure;
      }
      break;
    } catch (const std::exception&) {
      start.status = FitStatus::kLineSearchFailed;
      ++start.iterations;
    }
    const bool improved = objective.best_value < before &&
                          (!std::isfinite(before) ||
                           before - objective.best_value > fo.relative_tolerance * std::max(1.0, std::abs(before)));
    if (!improved || ++runs > kGpMaxSolverRestarts || start.iterations >= fo.max_iterations) break;
    theta = objective.best_theta;
  }
}

/// Runs the search and returns the best log hyperparameters found; fills `summary` (starts,
/// evaluations, the chosen start and its status). `make_objective()` gives a fresh objective
/// per start: callable as `double(const Eigen::VectorXd& theta, Eigen::VectorXd& grad)`
/// (-LML and its gradient), with members `best_value`, `best_theta` (the best point it saw)
/// and `evaluations`; it reports a numerical failure by throwing GpObjectiveAborted.
/// @throws NumericalError if no start could evaluate the objective at all.
template <class MakeObjective>
[[nodiscard]] Eigen::VectorXd gp_multistart_minimize(const Eigen::VectorXd& initial, const Eigen::VectorXd& lower,
                                                     const Eigen::VectorXd& upper, const GpFitOptions& fo,
                                                     GpFitSummary& summary, MakeObjective make_objective) {
  GpSplitMix64 rng(fo.seed);
  BoxMinimizerSettings settings{.history = fo.history,
                                .gradient_tolerance = fo.gradient_tolerance,
                                .relative_tolerance = fo.relative_tolerance,
                                .max_iterations = fo.max_iterations};
  double best = std::numeric_limits<double>::infinity();
  for (int r = 0; r <= fo.restarts; ++r) {
    GpStartSummary start;
    Eigen::VectorXd theta = initial;
    if (r > 0) {
      for (Eigen::Index i = 0; i < theta.size(); ++i) theta(i) = lower(i) + rng.uniform() * (upper(i) - lower(i));
    }
    theta = theta.cwiseMax(lower).cwiseMin(upper);
    start.initial_log_parameters = theta;
    auto objective = make_objective();
    gp_minimize_start(objective, theta, lower, upper, fo, settings, start);
    start.evaluations = objective.evaluations;
    summary.evaluations += objective.evaluations;
    if (objective.evaluations > 0) {
      start.log_parameters = objective.best_theta;
      start.log_marginal_likelihood = -objective.best_value;
      if (objective.best_value < best) {
        best = objective.best_value;
        summary.best_start = summary.starts.size();
      }
    } else {
      start.log_parameters = start.initial_log_parameters;
    }
    summary.starts.push_back(std::move(start));
  }
  if (!std::isfinite(best)) {
    throw NumericalError("GaussianProcess::fit: the covariance could not be factorised at any start point (" +
                         std::to_string(summary.starts.size()) + " starts)");
  }
  const GpStartSummary& chosen = summary.starts[summary.best_start];
  summary.status = chosen.status;
  return chosen.log_parameters;
}

}  // namespace adaptseg::detail
