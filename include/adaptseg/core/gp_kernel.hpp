#pragma once
/// @file
/// What a GaussianProcess needs of its kernel (the `Kernel` concept and its parts), and the
/// paper's kernel: squared exponential times a constant plus white noise (paper eq:sqexp),
/// with one length scale or one per input (automatic relevance determination).

#include <adaptseg/core/detail/gp_simd.hpp>
#include <adaptseg/core/error.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <limits>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

// ============================================================================================
// Kernel concept
// ============================================================================================

/// Hyperparameters live in one vector in log space, with box bounds: the space in which the
/// optimiser searches (positivity for free, scale-free steps), as scikit-learn's `theta`.
template <typename K>
concept LogParameterized = requires(K k, const K ck, const Eigen::VectorXd& theta) {
  { ck.log_parameters() } -> std::same_as<Eigen::VectorXd>;
  { ck.log_lower_bounds() } -> std::same_as<Eigen::VectorXd>;
  { ck.log_upper_bounds() } -> std::same_as<Eigen::VectorXd>;
  k.set_log_parameters(theta);
};

/// The latent covariance between two input sets and its diagonal on one set: all that
/// predictions need (eq:gp's K(X*,X) and K(X*,X*)).
template <typename K>
concept LatentCovariance = requires(const K k, const Eigen::MatrixXd& a, const Eigen::MatrixXd& b,
                                    Eigen::Index dimension) {
  { k.accepts_dimension(dimension) } -> std::same_as<bool>;
  { k.cross_covariance(a, b) } -> std::same_as<Eigen::MatrixXd>;
  { k.prior_variance(a) } -> std::same_as<Eigen::VectorXd>;
};

/// Independent observation noise, added to the diagonal of the training covariance only
/// (eq:gp's K_XX = K(X,X) + sn2 I; scikit-learn's WhiteKernel).
template <typename K>
concept ObservationNoise = requires(const K k) {
  { k.noise_variance() } -> std::same_as<double>;
};

/// The derivative of the training covariance contracted with a weight matrix, so that a
/// kernel never materialises an n x n x p derivative array (Rasmussen & Williams Eq. 5.9).
template <typename K>
concept ContractedGradient = requires(const K k, const Eigen::MatrixXd& x, const Eigen::MatrixXd& w) {
  { k.contract_gradient(x, w) } -> std::same_as<Eigen::VectorXd>;
};

/// A stable name and a factory from log parameters and bounds, so that a fitted model can be
/// written to a file and read back.
template <typename K>
concept RestorableKernel = requires(const Eigen::VectorXd& v) {
  { K::kName } -> std::convertible_to<std::string_view>;
  { K::from_log_parameters(v, v, v) } -> std::same_as<K>;
};

/// A covariance function usable by `GaussianProcess`.
///
/// Semantic contract (checked for every model by the shared conformance suite in
/// tests/test_gaussian_process.cpp):
/// - Inputs are matrices with one sample per row; `accepts_dimension(D)` tells whether rows of
///   length D are valid. Every member taking inputs throws `std::invalid_argument` otherwise.
/// - `log_parameters()` has a fixed size p; `log_lower_bounds()` < `log_upper_bounds()`
///   elementwise, same size; `set_log_parameters(theta)` accepts any finite vector of size p
///   (bounds are the optimiser's business) and throws `std::invalid_argument` otherwise.
/// - `cross_covariance(A, B)` is the latent covariance k_f(a_i, b_j), |A| x |B|, without noise;
///   `cross_covariance(A, A)` is symmetric positive semi-definite and its diagonal equals
///   `prior_variance(A)`.
/// - The training covariance is `cross_covariance(X, X) + noise_variance() * I`, with
///   `noise_variance() > 0`.
/// - `contract_gradient(X, W)` returns g with g_p = sum_ij W_ij dK_ij/dtheta_p, K the training
///   covariance and theta the log parameters; W is symmetric and only its lower triangle
///   (diagonal included) is read.
/// - `K::from_log_parameters(theta, lower, upper)` rebuilds an equal kernel.
/// - Const members are safe to call concurrently; kernels own their parameters by value.
template <typename K>
concept Kernel = std::copyable<K> && LogParameterized<K> && LatentCovariance<K> && ObservationNoise<K> &&
    ContractedGradient<K> && RestorableKernel<K>;

// ============================================================================================
// Squared-exponential kernel
// ============================================================================================

/// Closed interval of a positive hyperparameter, in its natural units (not log).
struct HyperparameterBounds {
  double lower = 1e-5;  ///< > 0
  double upper = 1e5;   ///< > lower
};

/// One length scale shared by all input dimensions, or one per dimension (ARD).
enum class LengthScales { kIsotropic, kPerDimension };

/// Squared-exponential covariance plus independent noise (paper eq:sqexp):
/// k(x_i, x_j) = sf2 * exp(-1/2 * sum_d (x_id - x_jd)^2 / l_d^2) + sn2 * [i == j],
/// with one length scale (`kIsotropic`, l_d = l) or one per input dimension (`kPerDimension`).
/// The noise term applies to the same training sample only: between distinct input sets (a
/// query and the training set, or two query points) only the first term is used.
/// Covariances below ~1e-150 sf2 (r^2 >= 690) are returned as exactly 0.
///
/// Log parameters, in scikit-learn's order for `C(sf2) * RBF(l) + WhiteKernel(sn2)`:
/// theta = [log sf2, log l_1, ..., log l_L, log sn2], L = 1 or D.
/// Default bounds are scikit-learn's: [1e-5, 1e5] for each parameter.
template <LengthScales Mode>
class SquaredExponential {
 public:
  static constexpr std::string_view kName =
      Mode == LengthScales::kIsotropic ? "squared_exponential_isotropic" : "squared_exponential_ard";

  /// Bounds for the optimiser, natural units; the length-scale bounds apply to every l_d.
  struct Bounds {
    HyperparameterBounds signal_variance{};  ///< sf2 [output units^2]
    HyperparameterBounds length_scale{};     ///< l [input units]
    HyperparameterBounds noise_variance{};   ///< sn2 [output units^2]
  };

  /// Isotropic kernel.
  /// @param length_scale l [input units], finite > 0.
  /// @param signal_variance sf2 [output units^2], finite > 0.
  /// @param noise_variance sn2 [output units^2], finite > 0.
  /// @param bounds optimiser bounds; each `0 < lower < upper < inf`.
  /// @throws std::invalid_argument naming the offending parameter.
  explicit SquaredExponential(double length_scale = 1.0, double signal_variance = 1.0, double noise_variance = 1.0,
                              const Bounds& bounds = {}) requires(Mode == LengthScales::kIsotropic)
      : SquaredExponential(Eigen::VectorXd::Constant(1, length_scale), signal_variance, noise_variance, bounds, 0) {}

  /// ARD kernel for inputs of dimension `length_scales.size()`.
  /// @param length_scales l_d [input units], each finite > 0, at least one.
  /// @param signal_variance sf2 [output units^2], finite > 0.
  /// @param noise_variance sn2 [output units^2], finite > 0.
  /// @param bounds optimiser bounds; each `0 < lower < upper < inf`.
  /// @throws std::invalid_argument naming the offending parameter.
  explicit SquaredExponential(const Eigen::VectorXd& length_scales, double signal_variance = 1.0,
                              double noise_variance = 1.0,
                              const Bounds& bounds = {}) requires(Mode == LengthScales::kPerDimension)
      : SquaredExponential(length_scales, signal_variance, noise_variance, bounds, 0) {}

  /// Rebuilds a kernel from `log_parameters()`, `log_lower_bounds()`, `log_upper_bounds()`.
  /// @throws std::invalid_argument on wrong sizes, non-finite values or lower > upper.
  [[nodiscard]] static SquaredExponential from_log_parameters(const Eigen::VectorXd& theta,
                                                              const Eigen::VectorXd& lower,
                                                              const Eigen::VectorXd& upper) {
    const Eigen::Index p = theta.size();
    detail::require(Mode == LengthScales::kIsotropic ? p == 3 : p >= 3,
                    std::string(kName) + ": number of log parameters", p);
    detail::require(lower.size() == p, std::string(kName) + ": size of log lower bounds", lower.size());
    detail::require(upper.size() == p, std::string(kName) + ": size of log upper bounds", upper.size());
    for (Eigen::Index i = 0; i < p; ++i) {
      if (std::isfinite(lower(i)) && std::isfinite(upper(i)) && lower(i) < upper(i)) continue;
      // Built only on failure, and by append: GCC 12 at -O3 reports a false -Warray-bounds on
      // an operator+ chain of std::string temporaries here.
      std::string what(kName);
      what.append(": log bounds must be finite with lower < upper at index ")
          .append(std::to_string(i))
          .append(", lower");
      detail::require(false, what, lower(i));
    }
    SquaredExponential k(Eigen::VectorXd::Ones(p - 2), 1.0, 1.0, Bounds{}, 0);
    k.lower_ = lower;
    k.upper_ = upper;
    k.set_log_parameters(theta);
    return k;
  }

  /// sf2 [output units^2].
  [[nodiscard]] double signal_variance() const { return std::exp(theta_(0)); }
  /// l_d [input units]: one entry (isotropic) or D entries (ARD).
  [[nodiscard]] Eigen::VectorXd length_scales() const { return theta_.segment(1, num_length_scales()).array().exp(); }
  /// sn2 [output units^2].
  [[nodiscard]] double noise_variance() const { return std::exp(theta_(theta_.size() - 1)); }

  [[nodiscard]] Eigen::VectorXd log_parameters() const { return theta_; }
  [[nodiscard]] Eigen::VectorXd log_lower_bounds() const { return lower_; }
  [[nodiscard]] Eigen::VectorXd log_upper_bounds() const { return upper_; }

  /// @throws std::invalid_argument if `theta` has the wrong size or a non-finite entry.
  void set_log_parameters(const Eigen::VectorXd& theta) {
    detail::require(theta.size() == theta_.size(), std::string(kName) + ": size of log parameters", theta.size());
    detail::require(theta.allFinite(), std::string(kName) + ": log parameters must be finite", theta.transpose());
    theta_ = theta;
  }

  /// Isotropic: any D >= 1; ARD: D equal to the number of length scales.
  [[nodiscard]] bool accepts_dimension(Eigen::Index dimension) const {
    return Mode == LengthScales::kIsotropic ? dimension >= 1 : dimension == num_length_scales();
  }

  /// Latent covariance sf2 * exp(-r^2 / 2) between the rows of `a` and of `b` (|a| x |b|).
  /// @throws std::invalid_argument if the column counts differ or are not accepted.
  [[nodiscard]] Eigen::MatrixXd cross_covariance(const Eigen::Ref<const Eigen::MatrixXd>& a,
                                                 const Eigen::Ref<const Eigen::MatrixXd>& b) const {
    check_inputs(a, "a");
    check_inputs(b, "b");
    detail::require(a.cols() == b.cols(), std::string(kName) + ": column counts of a and b differ, b", b.cols());
    const Eigen::ArrayXd inv = inverse_length_scales(a.cols());
    // Scale first, then take differences: scikit-learn's cdist(X / l, Y / l) order, and no
    // cancellation from the |a|^2 + |b|^2 - 2ab expansion.
    const Eigen::MatrixXd as = a * inv.matrix().asDiagonal();
    const double sf2 = signal_variance();
    Eigen::MatrixXd k(a.rows(), b.rows());
    const bool same = a.data() == b.data() && a.rows() == b.rows() && a.outerStride() == b.outerStride();
    if (same) {
      // K(X, X): evaluate the strictly lower triangle only and mirror it (half the exponentials).
      k.diagonal().setConstant(sf2);
      for_each_lower_column(as, sf2, [&k](Eigen::Index j, const auto&, const auto& kj) {
        k.col(j).tail(kj.size()) = kj;
        k.row(j).tail(kj.size()) = kj.transpose();
      });
      return k;
    }
    const Eigen::MatrixXd bs = b * inv.matrix().asDiagonal();
    for (Eigen::Index j = 0; j < b.rows(); ++j) {
      auto col = k.col(j).array();
      col = (as.col(0).array() - bs(j, 0)).square();
      for (Eigen::Index d = 1; d < as.cols(); ++d) col += (as.col(d).array() - bs(j, d)).square();
    }
    detail::gp_squared_exponential(k.data(), k.size(), sf2);
    return k;
  }

  /// Prior variance of the latent function at each row of `a`: sf2 [output units^2].
  [[nodiscard]] Eigen::VectorXd prior_variance(const Eigen::Ref<const Eigen::MatrixXd>& a) const {
    check_inputs(a, "a");
    return Eigen::VectorXd::Constant(a.rows(), signal_variance());
  }

  /// g_p = sum_ij W_ij dK_ij/dtheta_p over the training covariance K of `x` (lower triangle of
  /// `w` read). dK/dlog sf2 = K_f, dK/dlog l_d = K_f .* (x_id - x_jd)^2 / l_d^2,
  /// dK/dlog sn2 = sn2 I.
  /// @throws std::invalid_argument on a dimension mismatch or a non-square `w` of wrong size.
  [[nodiscard]] Eigen::VectorXd contract_gradient(const Eigen::Ref<const Eigen::MatrixXd>& x,
                                                  const Eigen::Ref<const Eigen::MatrixXd>& w) const {
    check_inputs(x, "x");
    const Eigen::Index n = x.rows();
    detail::require(w.rows() == n && w.cols() == n,
                    std::string(kName) + ": contract_gradient weight matrix must be n x n, rows", w.rows());
    const Eigen::Index dims = x.cols();
    const Eigen::Index nl = num_length_scales();
    const Eigen::ArrayXd inv = inverse_length_scales(dims);
    const Eigen::MatrixXd xs = x * inv.matrix().asDiagonal();
    const double sf2 = signal_variance();

    double g_sf = 0.0;
    Eigen::ArrayXd g_l = Eigen::ArrayXd::Zero(nl);
    Eigen::ArrayXd wk(n);
    // Strictly below the diagonal, counted twice.
    for_each_lower_column(xs, sf2, [&](Eigen::Index j, const auto& r, const auto& kj) {
      const Eigen::Index m = kj.size();
      auto v = wk.head(m);
      v = kj * w.col(j).tail(m).array();
      g_sf += 2.0 * v.sum();
      if constexpr (Mode == LengthScales::kIsotropic) {
        g_l(0) += 2.0 * (v * r).sum();
      } else {
        for (Eigen::Index d = 0; d < dims; ++d) {
          g_l(d) += 2.0 * (v * (xs.col(d).tail(m).array() - xs(j, d)).square()).sum();
        }
      }
    });
    const double trace_w = w.diagonal().sum();
    Eigen::VectorXd g(theta_.size());
    g(0) = g_sf + sf2 * trace_w;
    g.segment(1, nl) = g_l.matrix();
    g(g.size() - 1) = noise_variance() * trace_w;
    return g;
  }

 private:
  SquaredExponential(const Eigen::VectorXd& length_scales, double signal_variance, double noise_variance,
                     const Bounds& bounds, int /*tag*/) {
    const std::string name(kName);
    detail::require(length_scales.size() >= 1, name + ": number of length scales", length_scales.size());
    for (Eigen::Index i = 0; i < length_scales.size(); ++i) {
      detail::require_positive(length_scales(i), name + ": length_scale");
    }
    detail::require_positive(signal_variance, name + ": signal_variance");
    detail::require_positive(noise_variance, name + ": noise_variance");
    check_bounds(bounds.signal_variance, name + ": bounds.signal_variance");
    check_bounds(bounds.length_scale, name + ": bounds.length_scale");
    check_bounds(bounds.noise_variance, name + ": bounds.noise_variance");
    const Eigen::Index nl = length_scales.size();
    theta_.resize(nl + 2);
    theta_(0) = std::log(signal_variance);
    theta_.segment(1, nl) = length_scales.array().log().matrix();
    theta_(nl + 1) = std::log(noise_variance);
    lower_.resize(nl + 2);
    upper_.resize(nl + 2);
    lower_(0) = std::log(bounds.signal_variance.lower);
    upper_(0) = std::log(bounds.signal_variance.upper);
    lower_.segment(1, nl).setConstant(std::log(bounds.length_scale.lower));
    upper_.segment(1, nl).setConstant(std::log(bounds.length_scale.upper));
    lower_(nl + 1) = std::log(bounds.noise_variance.lower);
    upper_(nl + 1) = std::log(bounds.noise_variance.upper);
  }

  /// Calls visit(j, r2, k) for each column j < n - 1 of the strictly lower triangle of the
  /// scaled inputs `xs` (n x D), with the arrays r2 (squared distances) and k = sf2 exp(-r2 / 2)
  /// of rows j + 1 .. n - 1. The exponentials run on several columns at once (>= kPiece values:
  /// short columns would pay the vector kernel's tail each).
  template <typename Visit>
  static void for_each_lower_column(const Eigen::MatrixXd& xs, double sf2, Visit&& visit) {
    constexpr Eigen::Index kPiece = 512;
    const Eigen::Index n = xs.rows();
    Eigen::ArrayXd r2(kPiece + n);
    Eigen::ArrayXd k(kPiece + n);
    for (Eigen::Index j0 = 0; j0 + 1 < n;) {
      Eigen::Index j1 = j0;
      Eigen::Index len = 0;
      for (; j1 + 1 < n && len < kPiece; ++j1) {
        const Eigen::Index m = n - j1 - 1;
        auto r = r2.segment(len, m);
        r = (xs.col(0).tail(m).array() - xs(j1, 0)).square();
        for (Eigen::Index d = 1; d < xs.cols(); ++d) r += (xs.col(d).tail(m).array() - xs(j1, d)).square();
        len += m;
      }
      k.head(len) = r2.head(len);
      detail::gp_squared_exponential(k.data(), len, sf2);
      for (Eigen::Index offset = 0; j0 < j1; ++j0) {
        const Eigen::Index m = n - j0 - 1;
        visit(j0, r2.segment(offset, m), k.segment(offset, m));
        offset += m;
      }
    }
  }

  static void check_bounds(const HyperparameterBounds& b, const std::string& name) {
    detail::require_positive(b.lower, name + ".lower");
    detail::require(std::isfinite(b.upper) && b.upper > b.lower, name + ".upper must be finite and > lower", b.upper);
  }

  void check_inputs(const Eigen::Ref<const Eigen::MatrixXd>& a, const char* what) const {
    if (accepts_dimension(a.cols())) return;  // the message only on failure (called per covariance)
    std::string message(kName);
    message.append(": unsupported number of input columns in ").append(what);
    detail::require(false, message, a.cols());
  }

  [[nodiscard]] Eigen::Index num_length_scales() const { return theta_.size() - 2; }

  [[nodiscard]] Eigen::ArrayXd inverse_length_scales(Eigen::Index dims) const {
    if constexpr (Mode == LengthScales::kIsotropic) {
      return Eigen::ArrayXd::Constant(dims, std::exp(-theta_(1)));
    } else {
      return (-theta_.segment(1, dims).array()).exp();
    }
  }

  Eigen::VectorXd theta_;  // [log sf2, log l_1..L, log sn2]
  Eigen::VectorXd lower_;
  Eigen::VectorXd upper_;
};

/// One length scale for all input dimensions.
using SquaredExponentialKernel = SquaredExponential<LengthScales::kIsotropic>;
/// One length scale per input dimension (automatic relevance determination).
using ArdSquaredExponentialKernel = SquaredExponential<LengthScales::kPerDimension>;

static_assert(Kernel<SquaredExponentialKernel>);
static_assert(Kernel<ArdSquaredExponentialKernel>);

}  // namespace adaptseg
