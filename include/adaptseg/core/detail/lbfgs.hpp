#pragma once
/// @file
/// The one place that names LBFGSpp (https://github.com/yixuan/LBFGSpp): bounded L-BFGS-B
/// minimisation for GaussianProcess::fit, and the line search it runs with.
///
/// Supported: LBFGSpp 0.1.0 (Debian 12's `liblbfgspp-dev`), whose `LBFGSBSolver` takes a
/// line-search *class* with a static `LineSearch(f, fx, x, grad, step, step_max, drt, xp,
/// param)`. Later releases (0.2, 0.3) changed that interface and are not supported; a port
/// changes this file only. CMake finds LBFGSpp with cmake/FindLBFGSpp.cmake (installed with
/// the package).

#include <Eigen/Core>
#include <LBFGSB.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace adaptseg::detail {

/// Strong-Wolfe line search (Nocedal & Wright, Algorithms 3.5 and 3.6: bracketing with 4x
/// extrapolation, then zoom by safeguarded cubic interpolation), as the `LineSearch` policy of
/// `LBFGSpp::LBFGSBSolver`. LBFGSpp 0.1.0's More-Thuente search extrapolates by 1.1x and can
/// re-evaluate one point until its budget is spent; this one needs about half the evaluations
/// on GP likelihoods. Steps never exceed `step_max` (the distance to the box). If the budget
/// runs out, the best point with sufficient decrease is accepted; without one it throws
/// `std::runtime_error`, which the caller treats as a failed line search.
template <typename Scalar>
class GpLineSearch {
  using Vector = Eigen::Matrix<Scalar, Eigen::Dynamic, 1>;

 public:
  template <typename Objective>
  static void LineSearch(Objective& f, Scalar& fx, Vector& x, Vector& grad, Scalar& step, const Scalar& step_max,
                         const Vector& drt, const Vector& xp, const LBFGSpp::LBFGSBParam<Scalar>& param) {
    const Scalar f0 = fx;
    const Scalar d0 = grad.dot(drt);
    if (!(d0 < 0) || !(step_max > 0)) throw std::runtime_error("GpLineSearch: not a descent direction");
    const Scalar c1 = param.ftol;
    const Scalar c2 = param.wolfe;
    // lo: best point so far with sufficient decrease (0 = start); hi: other end of the bracket.
    Point lo{Scalar(0), f0, d0, xp, grad};
    Point hi{};
    bool bracketed = false;
    Scalar t = std::min(step, step_max);
    for (int it = 0; it < param.max_linesearch; ++it) {
      x.noalias() = xp + t * drt;
      const Scalar ft = f(x, grad);
      const Scalar dt = grad.dot(drt);
      if (!std::isfinite(ft) || ft > f0 + c1 * t * d0 || ft >= lo.f) {
        hi = Point{t, ft, dt, {}, {}};
        bracketed = true;
      } else {
        if (std::abs(dt) <= -c2 * d0) {  // strong Wolfe: accept
          fx = ft;
          step = t;
          return;
        }
        const Point previous = lo;
        lo = Point{t, ft, dt, x, grad};
        if (bracketed && dt * (hi.t - t) >= 0) {
          hi = previous;
        } else if (!bracketed && dt >= 0) {
          hi = previous;
          bracketed = true;
        }
      }
      if (!bracketed) {
        if (t >= step_max) break;  // still descending at the box: take the boundary step
        t = std::min(step_max, Scalar(4) * t);
        continue;
      }
      t = interpolate(lo, hi);
      if (!(std::abs(hi.t - lo.t) > std::numeric_limits<Scalar>::epsilon() * std::max(Scalar(1), lo.t))) break;
    }
    if (lo.t > 0) {
      x = lo.x;
      grad = lo.g;
      fx = lo.f;
      step = lo.t;
      return;
    }
    x = xp;
    grad = lo.g;
    throw std::runtime_error("GpLineSearch: no step with sufficient decrease");
  }

 private:
  struct Point {
    Scalar t = 0;
    Scalar f = 0;
    Scalar d = 0;  // directional derivative
    Vector x;
    Vector g;
  };

  /// Minimiser of the cubic through both ends, kept in the middle 80% of the bracket.
  static Scalar interpolate(const Point& a, const Point& b) {
    const Scalar lo = std::min(a.t, b.t);
    const Scalar hi = std::max(a.t, b.t);
    const Scalar margin = Scalar(0.1) * (hi - lo);
    Scalar t = Scalar(0.5) * (a.t + b.t);
    if (std::isfinite(a.f) && std::isfinite(b.f) && std::isfinite(b.d)) {
      const Scalar d1 = a.d + b.d - Scalar(3) * (a.f - b.f) / (a.t - b.t);
      const Scalar disc = d1 * d1 - a.d * b.d;
      if (disc >= 0) {
        const Scalar d2 = std::copysign(std::sqrt(disc), b.t - a.t);
        const Scalar den = b.d - a.d + Scalar(2) * d2;
        if (den != 0) {
          const Scalar c = b.t - (b.t - a.t) * (b.d + d2 - d1) / den;
          if (std::isfinite(c)) t = c;
        }
      }
    }
    return std::clamp(t, lo + margin, hi - margin);
  }
};

/// Settings of one bounded minimisation (minimize_in_box).
struct BoxMinimizerSettings {
  int history = 10;                  ///< L-BFGS memory (pairs kept)
  double gradient_tolerance = 1e-5;  ///< stop when the projected gradient's norm is below this
  /// Stop when one step improves the objective by less than this (relative).
  double relative_tolerance = 1e7 * std::numeric_limits<double>::epsilon();
  int max_iterations = 15000;  ///< iteration budget
};

/// Minimises `f` (`double f(const Eigen::VectorXd& x, Eigen::VectorXd& gradient)`) over the
/// box [lower, upper] from `x` (inside the box) with L-BFGS-B and GpLineSearch; `x` ends at the
/// last accepted point. Returns the iterations taken.
/// @throws std::exception (LBFGSpp's, or GpLineSearch's std::runtime_error) when a line
///         search fails or the direction is not a descent direction; whatever `f` throws
///         passes through unchanged.
template <typename Objective>
int minimize_in_box(Objective& f, Eigen::VectorXd& x, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                    const BoxMinimizerSettings& settings) {
  LBFGSpp::LBFGSBParam<double> param;  // outlives the solver, which keeps a reference
  param.m = settings.history;
  param.epsilon = settings.gradient_tolerance;
  param.epsilon_rel = 0.0;
  param.past = 1;
  param.delta = settings.relative_tolerance;
  param.max_iterations = settings.max_iterations;
  LBFGSpp::LBFGSBSolver<double, GpLineSearch> solver(param);
  double fx = 0.0;
  return solver.minimize(f, x, fx, lower, upper);
}

}  // namespace adaptseg::detail
