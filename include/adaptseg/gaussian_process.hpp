#pragma once
/// @file
/// Exact Gaussian-process regression with a squared-exponential kernel (paper eq:prior,
/// eq:sqexp, eq:gp), hyperparameters by maximising the log marginal likelihood, online
/// updates by extending the Cholesky factor, and a line-based text format for fitted models.
///
/// Self-contained: needs Eigen 3.4, LBFGSpp (header-only, reached only through
/// detail/lbfgs.hpp) and adaptseg/error.hpp only.
/// Conventions follow scikit-learn's `GaussianProcessRegressor` with the kernel
/// `ConstantKernel(sf2) * RBF(length_scale) + WhiteKernel(sn2)` and `alpha = 0`, so that
/// results can be checked against it (see tests/tools/make_gp_fixtures.py).

#include <adaptseg/detail/lbfgs.hpp>
#include <adaptseg/error.hpp>

#include <Eigen/Cholesky>
#include <Eigen/Core>

#if defined(__SSE2__) || defined(_M_X64)
#include <xmmintrin.h>
#define ADAPTSEG_GP_HAS_MXCSR 1
#endif

#include <algorithm>
#include <charconv>
#include <cmath>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <locale>
#include <numbers>
#include <ostream>
#include <sstream>
#include <string>
#include <string_view>
#include <system_error>
#include <utility>
#include <vector>

namespace adaptseg {

// ============================================================================================
// Vectorised numerical kernels with run-time instruction-set dispatch
// ============================================================================================

namespace detail {

// The library is header-only, so its code is compiled with the consumer's flags, by default
// for baseline x86-64 (SSE2, two doubles per instruction). The two hot loops of prediction
// and fitting (exponentials, and the triangular solve of the predictive variance) are also
// compiled for AVX2 + FMA and for AVX-512 (GCC/Clang `target` attribute) and chosen once at
// run time by what the CPU supports; elsewhere (other compilers or architectures, or
// ADAPTSEG_GP_NO_DISPATCH defined) the portable version runs. Each is written once, on GCC
// vector types of `Bytes` bytes, and every element goes through the same vector code (tails
// are padded), so a result does not depend on its position in a batch; different
// instruction sets may differ in the last bits (FMA rounding).
#if defined(__GNUC__) && (defined(__x86_64__) || defined(__i386__)) && !defined(ADAPTSEG_GP_NO_DISPATCH)
#define ADAPTSEG_GP_DISPATCH 1
#endif

/// Instruction set the dispatched kernels use: 0 = baseline, 1 = AVX2 + FMA, 2 = AVX-512F.
[[nodiscard]] inline int gp_simd_level() {
#if defined(ADAPTSEG_GP_DISPATCH)
  static const int level = [] {
    __builtin_cpu_init();
    if (__builtin_cpu_supports("avx512f")) return 2;
    if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) return 1;
    return 0;
  }();
  return level;
#else
  return 0;
#endif
}

/// Defines `name(params)`, which runs `name##_body<Bytes>(args)` for the widest instruction
/// set of `gp_simd_level()`, with `name##_avx512` and `name##_avx2` compiled for those.
#if defined(ADAPTSEG_GP_DISPATCH)
#define ADAPTSEG_GP_DISPATCHED(ret, name, params, args)                                          \
  [[gnu::target("avx512f")]] inline ret name##_avx512 params { return name##_body<64> args; } \
  [[gnu::target("avx2,fma")]] inline ret name##_avx2 params { return name##_body<32> args; }  \
  inline ret name params {                                                                    \
    switch (gp_simd_level()) {                                                                \
      case 2: return name##_avx512 args;                                                      \
      case 1: return name##_avx2 args;                                                        \
      default: return name##_body<16> args;                                                   \
    }                                                                                         \
  }                                                                                           \
  static_assert(true, "a use ends with a semicolon")
#else
#define ADAPTSEG_GP_DISPATCHED(ret, name, params, args)    \
  inline ret name params { return name##_body<16> args; } \
  static_assert(true, "a use ends with a semicolon")
#endif

/// GCC vector types of 16, 32 and 64 bytes (spelled out: the attribute is not applied to a
/// dependent size).
template <int Bytes>
struct GpVector;
template <>
struct GpVector<16> {
  typedef double Double __attribute__((vector_size(16)));
  typedef unsigned long long Bits __attribute__((vector_size(16)));
};
template <>
struct GpVector<32> {
  typedef double Double __attribute__((vector_size(32)));
  typedef unsigned long long Bits __attribute__((vector_size(32)));
};
template <>
struct GpVector<64> {
  typedef double Double __attribute__((vector_size(64)));
  typedef unsigned long long Bits __attribute__((vector_size(64)));
};

/// r2 <- 0 where r2 >= kGpNegligibleR2 (covariance below ~1e-150 sf2: far below rounding of
/// any sum it enters, and it keeps subnormal numbers out at short length scales).
inline constexpr double kGpNegligibleR2 = 690.0;

/// r2[i] <- sf2 * exp(-r2[i] / 2) for r2[i] in [0, kGpNegligibleR2), else 0; r2 >= 0 (a
/// squared distance). exp by Cody-Waite reduction x = k ln2 + r, |r| <= ln2 / 2, and the
/// degree-13 Taylor polynomial of exp(r) (truncation < 0.03 ulp; total error ~1 ulp).
template <int Bytes>
[[gnu::always_inline]] inline void gp_squared_exponential_body(double* r2, Eigen::Index size, double sf2) {
  using Vd = typename GpVector<Bytes>::Double;
  using Vu = typename GpVector<Bytes>::Bits;
  constexpr Eigen::Index kLanes = Bytes / 8;
  constexpr double kLog2e = 1.4426950408889634074;
  constexpr double kLn2Hi = 6.93147180369123816490e-01;  // trailing zeros: k * kLn2Hi exact
  constexpr double kLn2Lo = 1.90821492927058770002e-10;
  constexpr double kShifter = 0x1.8p52;  // adding it rounds to an integer held in the low bits
  const auto one = [&](double* p) {
    Vd q;
    std::memcpy(&q, p, Bytes);
    const Vu keep = (Vu)(q < kGpNegligibleR2);
    const Vd x = -0.5 * (q < kGpNegligibleR2 ? q : kGpNegligibleR2 + Vd{});
    const Vd kd = x * kLog2e + kShifter;
    const Vd k = kd - kShifter;
    const Vd r = (x - k * kLn2Hi) - k * kLn2Lo;
    Vd e = 1.0 / 6227020800.0 + Vd{};  // 1/13!
    e = e * r + 1.0 / 479001600.0;
    e = e * r + 1.0 / 39916800.0;
    e = e * r + 1.0 / 3628800.0;
    e = e * r + 1.0 / 362880.0;
    e = e * r + 1.0 / 40320.0;
    e = e * r + 1.0 / 5040.0;
    e = e * r + 1.0 / 720.0;
    e = e * r + 1.0 / 120.0;
    e = e * r + 1.0 / 24.0;
    e = e * r + 1.0 / 6.0;
    e = e * r + 0.5;
    e = e * r + 1.0;
    e = e * r + 1.0;
    // 2^k: k in [-498, 0] sits in the low bits of kd; move it into the exponent field.
    const Vu scale = ((Vu)kd << 52) + (1023ULL << 52);
    const Vd y = sf2 * (e * (Vd)scale);
    q = (Vd)((Vu)y & keep);
    std::memcpy(p, &q, Bytes);
  };
  Eigen::Index i = 0;
  for (; i + kLanes <= size; i += kLanes) one(r2 + i);
  if (i < size) {
    double pad[kLanes] = {};
    std::memcpy(pad, r2 + i, static_cast<std::size_t>(size - i) * sizeof(double));
    one(pad);
    std::memcpy(r2 + i, pad, static_cast<std::size_t>(size - i) * sizeof(double));
  }
}

/// Dispatching `gp_squared_exponential_body`: r2[i] <- sf2 * exp(-r2[i] / 2) (0 beyond
/// kGpNegligibleR2) over a contiguous array.
ADAPTSEG_GP_DISPATCHED(void, gp_squared_exponential, (double* r2, Eigen::Index size, double sf2), (r2, size, sf2));

/// s[r][v] += b[r] * x[v], r < 4, v < 2, for the two vectors x at p: the rank-one step that
/// all dense kernels below are built on (four broadcasts against two vectors of lanes).
template <int Bytes>
[[gnu::always_inline]] inline void gp_rank_one_4x2(typename GpVector<Bytes>::Double (&s)[4][2], const double* b,
                                                   const double* p) {
  typename GpVector<Bytes>::Double x[2];
  std::memcpy(&x, p, 2 * Bytes);
  for (int r = 0; r < 4; ++r) {
    s[r][0] += b[r] * x[0];
    s[r][1] += b[r] * x[1];
  }
}

/// Queries per block of the predictive-variance kernel (`gp_lower_solve`).
inline constexpr Eigen::Index kGpQueryBlock = 64;

/// The lower Cholesky factor L (n x n) of the training covariance, repacked for
/// `gp_lower_solve`: rows in panels of four, n padded to n4 = 4 ceil(n / 4) with
/// identity rows. Panel p (rows i0 = 4p .. i0 + 3) holds L(i0 + r, k), k < i0, at
/// panels[8 p (p - 1) + 4 k + r]; its diagonal block's strictly lower part at
/// diagonal[4 i0 + 4 r + c] (c < r), and 1 / L(i, i) at inverse_diagonal[i].
struct GpPackedFactor {
  Eigen::Index n = 0;
  Eigen::Index n4 = 0;
  std::vector<double> panels;
  std::vector<double> diagonal;
  std::vector<double> inverse_diagonal;
  std::vector<double> z;  // L^-1 y, zero-padded to n4

  GpPackedFactor(const Eigen::Ref<const Eigen::MatrixXd>& l, const Eigen::Ref<const Eigen::VectorXd>& zv)
      : n(l.rows()), n4((l.rows() + 3) / 4 * 4) {
    const auto un4 = static_cast<std::size_t>(n4);
    panels.assign(un4 * (un4 - 4) / 2, 0.0);
    diagonal.assign(4 * un4, 0.0);
    inverse_diagonal.assign(un4, 1.0);
    z.assign(un4, 0.0);
    for (Eigen::Index i = 0; i < n; ++i) {
      const Eigen::Index i0 = i / 4 * 4;
      const Eigen::Index r = i - i0;
      double* panel = panels.data() + 2 * i0 * (i0 / 4 - 1) + r;
      for (Eigen::Index k = 0; k < i0; ++k) panel[4 * k] = l(i, k);
      for (Eigen::Index c = 0; c < r; ++c) diagonal[static_cast<std::size_t>(4 * i0 + 4 * r + c)] = l(i, i0 + c);
      inverse_diagonal[static_cast<std::size_t>(i)] = 1.0 / l(i, i);
      z[static_cast<std::size_t>(i)] = zv(i);
    }
  }
};

/// Forward substitution V = L^-1 K* for a block of kGpQueryBlock queries, with the per-query
/// sums that prediction needs: mean[q] = z^T v_q, ssq[q] = v_q^T v_q. `c` holds K* transposed
/// (query q, training point k at c[k * kGpQueryBlock + q], n4 columns, padding zero) and is
/// overwritten by V^T. Lanes are queries; four rows of L at a time against two vectors of
/// queries (8 accumulators). Only the first `lanes` queries (rounded up to a vector pair) are
/// computed.
template <int Bytes>
[[gnu::always_inline]] inline void gp_lower_solve_body(const GpPackedFactor& f, double* c, Eigen::Index lanes,
                                                       double* mean, double* ssq) {
  using Vd = typename GpVector<Bytes>::Double;
  constexpr Eigen::Index kWidth = Bytes / 8;
  constexpr Eigen::Index kGroup = 2 * kWidth;
  constexpr Eigen::Index kLd = kGpQueryBlock;
  static_assert(kGpQueryBlock % kGroup == 0);
  const auto load = [](Vd& v, const double* p) { std::memcpy(&v, p, Bytes); };
  const auto store = [](double* p, const Vd& v) { std::memcpy(p, &v, Bytes); };
  for (Eigen::Index g = 0; g < lanes; g += kGroup) {
    double* cg = c + g;
    Vd m0{}, m1{}, s0{}, s1{};
    const double* panel = f.panels.data();
    for (Eigen::Index i0 = 0; i0 < f.n4; i0 += 4) {
      Vd sum[4][2] = {};
      for (Eigen::Index k = 0; k < i0; ++k) gp_rank_one_4x2<Bytes>(sum, panel + 4 * k, cg + k * kLd);
      Vd a[4][2];
      for (int r = 0; r < 4; ++r) {
        load(a[r][0], cg + (i0 + r) * kLd);
        load(a[r][1], cg + (i0 + r) * kLd + kWidth);
        a[r][0] -= sum[r][0];
        a[r][1] -= sum[r][1];
      }
      panel += 4 * i0;
      const double* d = f.diagonal.data() + 4 * i0;
      for (int r = 0; r < 4; ++r) {
        for (int q = 0; q < r; ++q) {
          a[r][0] -= d[4 * r + q] * a[q][0];
          a[r][1] -= d[4 * r + q] * a[q][1];
        }
        const double inv = f.inverse_diagonal[static_cast<std::size_t>(i0 + r)];
        a[r][0] *= inv;
        a[r][1] *= inv;
        store(cg + (i0 + r) * kLd, a[r][0]);
        store(cg + (i0 + r) * kLd + kWidth, a[r][1]);
        const double zi = f.z[static_cast<std::size_t>(i0 + r)];
        m0 += zi * a[r][0];
        m1 += zi * a[r][1];
        s0 += a[r][0] * a[r][0];
        s1 += a[r][1] * a[r][1];
      }
    }
    store(mean + g, m0);
    store(mean + g + kWidth, m1);
    store(ssq + g, s0);
    store(ssq + g + kWidth, s1);
  }
}

/// Dispatching `gp_lower_solve_body`.
ADAPTSEG_GP_DISPATCHED(void, gp_lower_solve,
                       (const GpPackedFactor& f, double* c, Eigen::Index lanes, double* mean, double* ssq),
                       (f, c, lanes, mean, ssq));

/// Dense kernels of one likelihood evaluation on column-major n4 x n4 matrices (n4 a multiple
/// of 4) with leading dimension `ld` (a multiple of kGpRowGroup, >= n4); lanes are rows, in
/// chunks of two vectors that start at a multiple of the chunk size, so that entries above
/// the diagonal may be overwritten: only the lower triangle (diagonal included) is meaningful.
inline constexpr Eigen::Index kGpRowGroup = 16;

/// Left-looking Cholesky in place, four columns at a time: lower(a) <- L, L L^T = a.
/// Returns false on a pivot that is not positive and finite (a is then partly overwritten).
template <int Bytes>
[[gnu::always_inline]] inline bool gp_cholesky_body(double* a, Eigen::Index n4, Eigen::Index ld) {
  using Vd = typename GpVector<Bytes>::Double;
  constexpr Eigen::Index kWidth = Bytes / 8;
  for (Eigen::Index j0 = 0; j0 < n4; j0 += 4) {
    double* col = a + j0 * ld;  // column j0 + c at col + c * ld
    // a(i, j0 + c) -= sum_{k < j0} a(i, k) a(j0 + c, k), rows i >= j0 (and some above)
    for (Eigen::Index i = j0 / (2 * kWidth) * (2 * kWidth); i < n4; i += 2 * kWidth) {
      Vd sum[4][2] = {};
      for (Eigen::Index k = 0; k < j0; ++k) gp_rank_one_4x2<Bytes>(sum, a + k * ld + j0, a + k * ld + i);
      for (int c = 0; c < 4; ++c) {
        Vd s[2];
        std::memcpy(&s, col + c * ld + i, 2 * Bytes);
        s[0] -= sum[c][0];
        s[1] -= sum[c][1];
        std::memcpy(col + c * ld + i, &s, 2 * Bytes);
      }
    }
    // The 4 x 4 diagonal block, scalar.
    double l[4][4] = {};
    for (int c = 0; c < 4; ++c) {
      for (int r = c; r < 4; ++r) {
        double v = col[c * ld + j0 + r];
        for (int q = 0; q < c; ++q) v -= l[r][q] * l[c][q];
        if (r == c) {
          if (!(v > 0.0) || !std::isfinite(v)) return false;
          v = std::sqrt(v);
        } else {
          v /= l[c][c];
        }
        l[r][c] = v;
        col[c * ld + j0 + r] = v;
      }
    }
    // Rows below the block: a(i, j0 + c) <- (a(i, j0 + c) - sum_{q < c} L(i, j0 + q)
    // L(j0 + c, j0 + q)) / L(j0 + c, j0 + c); the chunk holding the block is done in scalars.
    const Eigen::Index first = (j0 + 4 + kWidth - 1) / kWidth * kWidth;
    for (Eigen::Index i = j0 + 4; i < std::min(first, n4); ++i) {
      for (int c = 0; c < 4; ++c) {
        double v = col[c * ld + i];
        for (int q = 0; q < c; ++q) v -= l[c][q] * col[q * ld + i];
        col[c * ld + i] = v / l[c][c];
      }
    }
    for (Eigen::Index i = first; i < n4; i += kWidth) {
      Vd s[4];
      for (int c = 0; c < 4; ++c) std::memcpy(&s[c], col + c * ld + i, Bytes);
      for (int c = 0; c < 4; ++c) {
        for (int q = 0; q < c; ++q) s[c] -= l[c][q] * s[q];
        s[c] /= l[c][c];
        std::memcpy(col + c * ld + i, &s[c], Bytes);
      }
    }
  }
  return true;
}

/// xt <- (L^-1)^T for L = lower(a): row i of L^-1 is column i of xt (L^-1 is lower
/// triangular, so xt(q, i) = 0 for q > i). `xt` (n4 x n4, leading dimension ld) must be zero
/// on entry.
template <int Bytes>
[[gnu::always_inline]] inline void gp_invert_lower_body(const double* a, double* xt, Eigen::Index n4, Eigen::Index ld) {
  using Vd = typename GpVector<Bytes>::Double;
  constexpr Eigen::Index kWidth = Bytes / 8;
  for (Eigen::Index i0 = 0; i0 < n4; i0 += 4) {
    // X(i0 + r, q) = (e_{i0 + r}(q) - sum_{k < i0 + r} L(i0 + r, k) X(k, q)) / L(i0 + r, i0 + r);
    // X(k, q) = 0 for k < q, so a chunk of q starting at qs needs k >= qs only.
    for (Eigen::Index qs = 0; qs < i0 + 4; qs += 2 * kWidth) {
      Vd s[4][2] = {};
      for (Eigen::Index k = qs; k < i0; ++k) gp_rank_one_4x2<Bytes>(s, a + k * ld + i0, xt + k * ld + qs);
      for (int r = 0; r < 4; ++r) {
        double e[2 * kWidth] = {};
        if (i0 + r >= qs && i0 + r < qs + 2 * kWidth) e[i0 + r - qs] = 1.0;
        Vd v[2];
        std::memcpy(&v, e, 2 * Bytes);
        const double* li = a + i0 + r;  // L(i0 + r, k) at li[k * ld]
        for (int q = 0; q < r; ++q) {
          Vd xq[2];
          std::memcpy(&xq, xt + (i0 + q) * ld + qs, 2 * Bytes);
          s[r][0] += li[(i0 + q) * ld] * xq[0];
          s[r][1] += li[(i0 + q) * ld] * xq[1];
        }
        const double d = li[(i0 + r) * ld];
        v[0] = (v[0] - s[r][0]) / d;
        v[1] = (v[1] - s[r][1]) / d;
        std::memcpy(xt + (i0 + r) * ld + qs, &v, 2 * Bytes);
      }
    }
  }
}

/// lower(a) <- lower(X^T X) = lower(K^-1) for X = L^-1 given as xt = X^T (from
/// `gp_invert_lower_body`): a(p, b) = sum_i X(i, p) X(i, b), i >= max(p, b).
template <int Bytes>
[[gnu::always_inline]] inline void gp_gram_body(const double* xt, double* a, Eigen::Index n4, Eigen::Index ld) {
  using Vd = typename GpVector<Bytes>::Double;
  constexpr Eigen::Index kWidth = Bytes / 8;
  for (Eigen::Index b0 = 0; b0 < n4; b0 += 4) {
    for (Eigen::Index ps = b0 / (2 * kWidth) * (2 * kWidth); ps < n4; ps += 2 * kWidth) {
      Vd s[4][2] = {};
      for (Eigen::Index i = std::max(b0, ps); i < n4; ++i) gp_rank_one_4x2<Bytes>(s, xt + i * ld + b0, xt + i * ld + ps);
      for (int c = 0; c < 4; ++c) std::memcpy(a + (b0 + c) * ld + ps, &s[c], 2 * Bytes);
    }
  }
}

/// Dispatching `gp_cholesky_body`, `gp_invert_lower_body`, `gp_gram_body`.
ADAPTSEG_GP_DISPATCHED(bool, gp_cholesky, (double* a, Eigen::Index n4, Eigen::Index ld), (a, n4, ld));
ADAPTSEG_GP_DISPATCHED(void, gp_invert_lower, (const double* a, double* xt, Eigen::Index n4, Eigen::Index ld),
                       (a, xt, n4, ld));
ADAPTSEG_GP_DISPATCHED(void, gp_gram, (const double* xt, double* a, Eigen::Index n4, Eigen::Index ld), (xt, a, n4, ld));

/// Largest n for which a likelihood evaluation uses the kernels above. They are not blocked
/// for the cache: each 4-column step streams the triangle once, so beyond a few hundred rows
/// Eigen's blocked LLT and the recursive triangular inverse/Gram product are faster. The
/// crossovers, measured on one AVX-512 machine (per evaluation, old = Eigen path):
/// AVX-512 n = 500: 10 ms vs 22 ms, n = 1000: 172 ms vs 143 ms; baseline n = 300: 8 ms vs
/// 12 ms, n = 500: 30 ms vs 22 ms. AVX2 was not measured (half the AVX-512 width: in between).
[[nodiscard]] inline Eigen::Index gp_dense_kernel_limit() {
  switch (gp_simd_level()) {
    case 2: return 768;
    case 1: return 512;
    default: return 384;
  }
}

}  // namespace detail

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
concept Kernel = std::copyable<K> && LogParameterized<K> && LatentCovariance<K> &&
                 ObservationNoise<K> && ContractedGradient<K> && RestorableKernel<K>;

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
  static constexpr std::string_view kName = Mode == LengthScales::kIsotropic
                                                ? "squared_exponential_isotropic"
                                                : "squared_exponential_ard";

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
  explicit SquaredExponential(double length_scale = 1.0, double signal_variance = 1.0,
                              double noise_variance = 1.0, const Bounds& bounds = {})
    requires(Mode == LengthScales::kIsotropic)
      : SquaredExponential(Eigen::VectorXd::Constant(1, length_scale), signal_variance,
                           noise_variance, bounds, 0) {}

  /// ARD kernel for inputs of dimension `length_scales.size()`.
  /// @param length_scales l_d [input units], each finite > 0, at least one.
  /// @param signal_variance sf2 [output units^2], finite > 0.
  /// @param noise_variance sn2 [output units^2], finite > 0.
  /// @param bounds optimiser bounds; each `0 < lower < upper < inf`.
  /// @throws std::invalid_argument naming the offending parameter.
  explicit SquaredExponential(const Eigen::VectorXd& length_scales, double signal_variance = 1.0,
                              double noise_variance = 1.0, const Bounds& bounds = {})
    requires(Mode == LengthScales::kPerDimension)
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
      detail::require(std::isfinite(lower(i)) && std::isfinite(upper(i)) && lower(i) < upper(i),
                      std::string(kName) + ": log bounds must be finite with lower < upper at index " +
                          std::to_string(i) + ", lower",
                      lower(i));
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
  [[nodiscard]] Eigen::VectorXd length_scales() const {
    return theta_.segment(1, num_length_scales()).array().exp();
  }
  /// sn2 [output units^2].
  [[nodiscard]] double noise_variance() const { return std::exp(theta_(theta_.size() - 1)); }

  [[nodiscard]] Eigen::VectorXd log_parameters() const { return theta_; }
  [[nodiscard]] Eigen::VectorXd log_lower_bounds() const { return lower_; }
  [[nodiscard]] Eigen::VectorXd log_upper_bounds() const { return upper_; }

  /// @throws std::invalid_argument if `theta` has the wrong size or a non-finite entry.
  void set_log_parameters(const Eigen::VectorXd& theta) {
    detail::require(theta.size() == theta_.size(), std::string(kName) + ": size of log parameters",
                    theta.size());
    detail::require(theta.allFinite(), std::string(kName) + ": log parameters must be finite",
                    theta.transpose());
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
    detail::require(a.cols() == b.cols(), std::string(kName) + ": column counts of a and b differ, b",
                    b.cols());
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
  SquaredExponential(const Eigen::VectorXd& length_scales, double signal_variance,
                     double noise_variance, const Bounds& bounds, int /*tag*/) {
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
    detail::require(std::isfinite(b.upper) && b.upper > b.lower, name + ".upper must be finite and > lower",
                    b.upper);
  }

  void check_inputs(const Eigen::Ref<const Eigen::MatrixXd>& a, const char* what) const {
    detail::require(accepts_dimension(a.cols()),
                    std::string(kName) + ": unsupported number of input columns in " + what, a.cols());
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

// ============================================================================================
// Internals
// ============================================================================================

namespace detail {

// Cache-blocked Eigen path for large n (see gp_dense_kernel_limit).

/// Below this size the recursive triangular kernels run unblocked.
inline constexpr Eigen::Index kGpTriangularBlock = 48;

/// lower(a) <- L^{-1}, where L = lower(a) is invertible (recursive LAPACK trtri, n^3/3 flops).
inline void gp_invert_lower_in_place(Eigen::Ref<Eigen::MatrixXd> a) {
  const Eigen::Index n = a.rows();
  if (n <= kGpTriangularBlock) {
    for (Eigen::Index j = n - 1; j >= 0; --j) {
      a(j, j) = 1.0 / a(j, j);
      const Eigen::Index m = n - j - 1;
      if (m > 0) {
        const Eigen::VectorXd t =
            a.bottomRightCorner(m, m).template triangularView<Eigen::Lower>() * a.col(j).tail(m);
        a.col(j).tail(m) = -a(j, j) * t;
      }
    }
    return;
  }
  const Eigen::Index n1 = n / 2;
  const Eigen::Index n2 = n - n1;
  gp_invert_lower_in_place(a.topLeftCorner(n1, n1));
  gp_invert_lower_in_place(a.bottomRightCorner(n2, n2));
  // [A 0; B C]^{-1} = [A^-1 0; -C^-1 B A^-1, C^-1]
  const Eigen::MatrixXd t =
      a.bottomLeftCorner(n2, n1) * a.topLeftCorner(n1, n1).template triangularView<Eigen::Lower>();
  a.bottomLeftCorner(n2, n1).noalias() =
      -(a.bottomRightCorner(n2, n2).template triangularView<Eigen::Lower>() * t);
}

/// lower(a) <- lower(L^T L), where L = lower(a) (recursive LAPACK lauum, n^3/3 flops).
inline void gp_lower_gram_in_place(Eigen::Ref<Eigen::MatrixXd> a) {
  const Eigen::Index n = a.rows();
  if (n <= kGpTriangularBlock) {
    const Eigen::MatrixXd l = a.template triangularView<Eigen::Lower>();
    const Eigen::MatrixXd g = l.transpose() * l;
    a.template triangularView<Eigen::Lower>() = g;
    return;
  }
  const Eigen::Index n1 = n / 2;
  const Eigen::Index n2 = n - n1;
  // [P 0; Q R]^T [P 0; Q R] = [P^T P + Q^T Q, Q^T R; R^T Q, R^T R]
  gp_lower_gram_in_place(a.topLeftCorner(n1, n1));
  a.topLeftCorner(n1, n1).template selfadjointView<Eigen::Lower>().rankUpdate(
      a.bottomLeftCorner(n2, n1).transpose());
  const Eigen::MatrixXd t =
      a.bottomRightCorner(n2, n2).template triangularView<Eigen::Lower>().transpose() *
      a.bottomLeftCorner(n2, n1);
  a.bottomLeftCorner(n2, n1) = t;
  gp_lower_gram_in_place(a.bottomRightCorner(n2, n2));
}

/// Flushes subnormal results to zero and reads subnormal operands as zero (x86 FTZ/DAZ) for
/// the current thread while alive, and restores the previous mode on destruction (also when
/// an exception passes). At short length scales the factorisation and the triangular products
/// pass through numbers below 2.2e-308, whose arithmetic is ~100x slower; flushing changes
/// results only by amounts below that threshold. No-op on other architectures.
class GpScopedFlushSubnormals {
 public:
#if defined(ADAPTSEG_GP_HAS_MXCSR)
  GpScopedFlushSubnormals() : saved_(_mm_getcsr()) { _mm_setcsr(saved_ | kFlushToZero | kDenormalsAreZero); }
  ~GpScopedFlushSubnormals() { _mm_setcsr(saved_); }
#else
  GpScopedFlushSubnormals() = default;
#endif
  GpScopedFlushSubnormals(const GpScopedFlushSubnormals&) = delete;
  GpScopedFlushSubnormals& operator=(const GpScopedFlushSubnormals&) = delete;

 private:
#if defined(ADAPTSEG_GP_HAS_MXCSR)
  static constexpr unsigned kFlushToZero = 0x8000u;
  static constexpr unsigned kDenormalsAreZero = 0x0040u;
  unsigned saved_;
#endif
};

/// Deterministic generator for restart points (SplitMix64: tiny, portable, same on every
/// standard library, unlike std::uniform_real_distribution).
class GpSplitMix64 {
 public:
  explicit GpSplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

/// Thrown by the objective to leave the minimiser; carries the real exception.
struct GpObjectiveAborted {
  std::exception_ptr cause;
};

inline std::string gp_trim(std::string_view s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string_view::npos) return {};
  const auto last = s.find_last_not_of(" \t\r");
  return std::string(s.substr(first, last - first + 1));
}

/// 'text', built without operator+ (GCC 12 -Wrestrict false positive on "'" + s + "'").
inline std::string gp_quote(std::string_view s) {
  std::string out;
  out.reserve(s.size() + 2);
  out.push_back('\'');
  out.append(s);
  out.push_back('\'');
  return out;
}

inline std::vector<std::string_view> gp_split(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < s.size() && s[i] != ' ' && s[i] != '\t') ++i;
    if (i > start) out.push_back(s.substr(start, i - start));
  }
  return out;
}

}  // namespace detail

// ============================================================================================
// GaussianProcess
// ============================================================================================

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

/// Readable name of a `FitStatus`.
[[nodiscard]] inline std::string_view to_string(FitStatus s) {
  switch (s) {
    case FitStatus::kNotOptimized: return "not_optimized";
    case FitStatus::kConverged: return "converged";
    case FitStatus::kMaxIterations: return "max_iterations";
    case FitStatus::kLineSearchFailed: return "line_search_failed";
    case FitStatus::kNumericalFailure: return "numerical_failure";
  }
  return "unknown";
}

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
///   gp.save("model.gp");                                  // readable text
///   auto same = GaussianProcess<SquaredExponentialKernel>::load("model.gp");
/// @endcode
template <Kernel K>
class GaussianProcess {
 public:
  using KernelType = K;

  /// Model options, validated once by the constructor.
  struct Options {
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
                      "GaussianProcess::Options::max_jitter_attempts must be in [0, 30]",
                      max_jitter_attempts);
    }
  };

  /// Hyperparameter-search options, validated by `fit`/`refit`.
  struct FitOptions {
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
      detail::require(max_iterations >= 1, "GaussianProcess::FitOptions::max_iterations must be >= 1",
                      max_iterations);
      detail::require(std::isfinite(gradient_tolerance) && gradient_tolerance >= 0.0,
                      "GaussianProcess::FitOptions::gradient_tolerance must be finite and >= 0",
                      gradient_tolerance);
      detail::require(std::isfinite(relative_tolerance) && relative_tolerance >= 0.0,
                      "GaussianProcess::FitOptions::relative_tolerance must be finite and >= 0",
                      relative_tolerance);
      detail::require(history >= 1, "GaussianProcess::FitOptions::history must be >= 1", history);
    }
  };

  /// One optimiser start.
  struct StartSummary {
    Eigen::VectorXd initial_log_parameters;
    Eigen::VectorXd log_parameters;  ///< best point of this start
    double log_marginal_likelihood = -std::numeric_limits<double>::infinity();
    int iterations = 0;
    int evaluations = 0;
    FitStatus status = FitStatus::kNotOptimized;
  };

  /// Result of `fit`/`refit`.
  struct FitSummary {
    FitStatus status = FitStatus::kNotOptimized;  ///< status of the chosen start
    double log_marginal_likelihood = 0.0;          ///< at the chosen hyperparameters
    Eigen::VectorXd log_parameters;                ///< chosen hyperparameters (log)
    std::vector<StartSummary> starts;              ///< empty if not optimised
    std::size_t best_start = 0;
    int evaluations = 0;  ///< LML + gradient evaluations over all starts
  };

  /// Posterior mean [output units] and variance [output units^2] at query rows.
  struct Prediction {
    Eigen::VectorXd mean;
    Eigen::VectorXd variance;
  };

  /// Posterior mean and full covariance at query rows.
  struct CovariancePrediction {
    Eigen::VectorXd mean;
    Eigen::MatrixXd covariance;
  };

  /// @throws std::invalid_argument if `options` is invalid (message names the field).
  explicit GaussianProcess(K kernel, const Options& options = {})
      : kernel_(std::move(kernel)), options_(options) {
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
    check_training_data(x, y);
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
    check_training_data(x, y);
    store_data(x, y);
    yn_.head(n_) = (y_.head(n_).array() - y_mean_) / y_std_;
    factorize();
  }

  /// Sets new hyperparameters (no optimisation) and refactorises the current data.
  /// @throws std::invalid_argument if the kernel does not accept the data's dimension.
  void set_kernel(K kernel) {
    if (n_ > 0) {
      detail::require(kernel.accepts_dimension(dimension_),
                      "GaussianProcess::set_kernel: kernel does not accept input dimension", dimension_);
    }
    kernel_ = std::move(kernel);
    if (n_ > 0) factorize();
  }

  /// Adds one observation in O(n^2) (one triangular solve) by extending the Cholesky factor;
  /// hyperparameters and normalisation stay as they are. Afterwards `predict_mean` costs an
  /// extra O(n^2) per call until the next `fit`/`refit`/`condition`/`set_kernel`. If the extended factor is not positive definite
  /// (a nearly repeated input with tiny noise), falls back to an O(n^3) refactorisation with
  /// jitter retries.
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
    check_query(xq);
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
    check_query(xq);
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
  [[nodiscard]] CovariancePrediction predict_covariance(
      const Eigen::Ref<const Eigen::MatrixXd>& xq, PredictiveVariance kind = PredictiveVariance::kLatent) const {
    check_query(xq);
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
  [[nodiscard]] double log_marginal_likelihood(const Eigen::VectorXd& theta, Eigen::VectorXd* gradient = nullptr) const {
    detail::require(n_ > 0, "GaussianProcess::log_marginal_likelihood: number of training samples must be > 0", n_);
    K kernel = kernel_;
    kernel.set_log_parameters(theta);
    Workspace work;
    return evaluate(kernel, gradient, work);
  }

  // ---- accessors ----------------------------------------------------------------------------

  [[nodiscard]] const K& kernel() const { return kernel_; }
  [[nodiscard]] const Options& options() const { return options_; }
  /// Number of training samples.
  [[nodiscard]] Eigen::Index size() const { return n_; }
  /// Input dimension D (0 before any data).
  [[nodiscard]] Eigen::Index dimension() const { return dimension_; }
  /// n x D training inputs.
  [[nodiscard]] Eigen::MatrixXd training_inputs() const { return x_.topRows(n_); }
  /// n training targets, original units.
  [[nodiscard]] Eigen::VectorXd training_targets() const { return y_.head(n_); }
  /// Frozen normalisation mean [output units] (0 without normalisation).
  [[nodiscard]] double y_mean() const { return y_mean_; }
  /// Frozen normalisation std [output units] (1 without normalisation).
  [[nodiscard]] double y_std() const { return y_std_; }
  /// Diagonal jitter in use (0 when the plain factorisation succeeded).
  [[nodiscard]] double jitter() const { return jitter_; }

  // ---- persistence --------------------------------------------------------------------------

  /// Everything that defines a fitted model: what a file format stores to restore it exactly.
  struct State {
    K kernel;                 ///< hyperparameters and their bounds
    Options options;
    double y_mean = 0.0;      ///< frozen target normalisation (0 and 1 without normalize_y)
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
    detail::require(std::isfinite(s.y_std) && s.y_std > 0.0, "GaussianProcess::from_state: y_std must be finite and > 0",
                    s.y_std);
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

  /// Writes the model as text (format in `load`); leaves `os`'s formatting state unchanged.
  /// Numbers are written in the classic "C" locale whatever the global one (load reads them
  /// with `std::from_chars`, which knows no other).
  /// @throws std::invalid_argument if the stream fails.
  void save(std::ostream& os) const {
    std::ostringstream s;
    s.imbue(std::locale::classic());
    s.precision(std::numeric_limits<double>::max_digits10);
    const auto vec = [&s](std::string_view key, const Eigen::VectorXd& v) {
      s << key << ' ' << v.size();
      for (Eigen::Index i = 0; i < v.size(); ++i) s << ' ' << v(i);
      s << '\n';
    };
    s << kMagic << ' ' << kFormatVersion << '\n';
    s << "kernel " << K::kName << '\n';
    vec("log_parameters", kernel_.log_parameters());
    vec("log_lower_bounds", kernel_.log_lower_bounds());
    vec("log_upper_bounds", kernel_.log_upper_bounds());
    s << "normalize_y " << (options_.normalize_y ? 1 : 0) << '\n';
    s << "y_mean " << y_mean_ << '\n';
    s << "y_std " << y_std_ << '\n';
    s << "initial_jitter " << options_.initial_jitter << '\n';
    s << "max_jitter_attempts " << options_.max_jitter_attempts << '\n';
    s << "dimension " << dimension_ << '\n';
    s << "samples " << n_ << '\n';
    for (Eigen::Index i = 0; i < n_; ++i) {
      for (Eigen::Index d = 0; d < dimension_; ++d) s << x_(i, d) << ' ';
      s << y_(i) << '\n';
    }
    s << "end " << kMagic << '\n';
    os << s.str();
    detail::require(static_cast<bool>(os), "GaussianProcess::save: output stream failed, good()", os.good());
  }

  /// Writes the model to `path` (created or truncated).
  /// @throws std::invalid_argument if the file cannot be written.
  void save(const std::filesystem::path& path) const {
    std::ofstream f(path);
    detail::require(static_cast<bool>(f), "GaussianProcess::save: cannot open file for writing", path);
    save(f);
  }

  /// Reads a model written by `save` and refactorises it; reads exactly up to and including
  /// the `end` line, so the model can be embedded in a larger stream.
  ///
  /// Format (one item per line; blank lines and lines starting with '#' are ignored):
  /// @code
  ///   adaptseg.gaussian_process 1
  ///   kernel <K::kName>
  ///   log_parameters <p> <theta_1> ... <theta_p>
  ///   log_lower_bounds <p> ...
  ///   log_upper_bounds <p> ...
  ///   normalize_y <0|1>
  ///   y_mean <mean>
  ///   y_std <std>
  ///   initial_jitter <value>
  ///   max_jitter_attempts <count>
  ///   dimension <D>
  ///   samples <n>
  ///   <x_1> ... <x_D> <y>        (n lines)
  ///   end adaptseg.gaussian_process
  /// @endcode
  /// @throws std::invalid_argument naming the line and what was expected, on a truncated or
  ///         garbled input, another kernel type or an unsupported version; NumericalError.
  [[nodiscard]] static GaussianProcess load(std::istream& is) {
    Reader r{is};
    {
      const auto t = r.expect(kMagic, 1);
      detail::require(t[1] == kFormatVersion,
                      r.where() + "unsupported format version (this library reads " +
                          std::string(kFormatVersion) + "), version",
                      t[1]);
    }
    {
      const auto t = r.expect("kernel", 1);
      detail::require(t[1] == K::kName,
                      r.where() + "kernel type does not match this GaussianProcess (" + std::string(K::kName) +
                          "), kernel",
                      t[1]);
    }
    const Eigen::VectorXd theta = r.vector("log_parameters");
    const Eigen::VectorXd lower = r.vector("log_lower_bounds");
    const Eigen::VectorXd upper = r.vector("log_upper_bounds");
    K kernel = K::from_log_parameters(theta, lower, upper);
    Options options;
    const long normalize = r.integer("normalize_y");
    detail::require(normalize == 0 || normalize == 1, r.where() + "normalize_y must be 0 or 1", normalize);
    options.normalize_y = normalize == 1;
    const double mean = r.real("y_mean");
    const double stddev = r.real("y_std");
    detail::require(stddev > 0.0, r.where() + "y_std must be > 0", stddev);
    options.initial_jitter = r.real("initial_jitter");
    const long attempts = r.integer("max_jitter_attempts");
    detail::require(attempts >= 0 && attempts <= 30, r.where() + "max_jitter_attempts must be in [0, 30]", attempts);
    options.max_jitter_attempts = static_cast<int>(attempts);
    const long dimension = r.integer("dimension");
    const long samples = r.integer("samples");
    detail::require(samples >= 0 && samples <= 100'000'000, r.where() + "samples must be in [0, 1e8]", samples);
    detail::require(dimension >= (samples > 0 ? 1 : 0) && dimension <= 1'000'000,
                    r.where() + "dimension must be in [1, 1e6] (0 allowed without samples)", dimension);
    // The announced sizes are not trusted for allocation: the dimension must be the kernel's,
    // and the samples are stored as their lines arrive (memory bounded by the input's size).
    detail::require(dimension == 0 || kernel.accepts_dimension(static_cast<Eigen::Index>(dimension)),
                    r.where() + "the kernel does not accept dimension", dimension);
    GaussianProcess gp(std::move(kernel), options);
    gp.y_mean_ = mean;
    gp.y_std_ = stddev;
    const Eigen::Index n = static_cast<Eigen::Index>(samples);
    const Eigen::Index dims = static_cast<Eigen::Index>(dimension);
    std::vector<double> values;  // row-major, dims + 1 per sample
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto tokens = r.next("sample " + std::to_string(i + 1) + " of " + std::to_string(n));
      detail::require(static_cast<Eigen::Index>(tokens.size()) == dims + 1,
                      r.where() + "a sample line needs " + std::to_string(dims + 1) + " numbers, found",
                      tokens.size());
      for (const auto& token : tokens) values.push_back(r.parse_real(token));
    }
    r.expect("end", 1);
    if (n > 0) {
      const Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>> rows(
          values.data(), n, dims + 1);
      const Eigen::MatrixXd x = rows.leftCols(dims);
      const Eigen::VectorXd y = rows.col(dims);
      gp.condition(x, y);
    } else {
      gp.dimension_ = dims;
    }
    return gp;
  }

  /// Reads a model from `path`.
  /// @throws std::invalid_argument if the file cannot be opened or is malformed (the message
  ///         names the path); NumericalError.
  [[nodiscard]] static GaussianProcess load(const std::filesystem::path& path) {
    std::ifstream f(path);
    detail::require(static_cast<bool>(f), "GaussianProcess::load: cannot open file", path);
    try {
      return load(f);
    } catch (const std::invalid_argument& e) {
      throw std::invalid_argument(path.string() + ": " + e.what());
    }
  }

 private:
  static constexpr std::string_view kMagic = "adaptseg.gaussian_process";
  static constexpr std::string_view kFormatVersion = "1";
  /// Fresh L-BFGS-B runs per start after a failed line search.
  static constexpr int kMaxSolverRestarts = 20;

  /// Line-based tokenizer for `load`.
  struct Reader {
    explicit Reader(std::istream& input) : is(input) {}
    std::istream& is;
    long line_number = 0;
    std::string line;

    [[nodiscard]] std::string where() const {
      return "GaussianProcess::load: line " + std::to_string(line_number) + ": ";
    }

    std::vector<std::string> next(const std::string& expected) {
      while (true) {
        if (!std::getline(is, line)) {
          throw std::invalid_argument("GaussianProcess::load: unexpected end of input after line " +
                                      std::to_string(line_number) + " (truncated file?), expected " + expected);
        }
        ++line_number;
        const std::string t = detail::gp_trim(line);
        if (t.empty() || t.front() == '#') continue;
        std::vector<std::string> out;
        for (auto v : detail::gp_split(t)) out.emplace_back(v);
        return out;
      }
    }

    std::vector<std::string> expect(std::string_view key, std::size_t values) {
      auto t = next(detail::gp_quote(key));
      detail::require(!t.empty() && t[0] == key && t.size() == values + 1,
                      where() + "expected '" + std::string(key) + "' followed by " + std::to_string(values) +
                          " value(s), got",
                      detail::gp_quote(line));
      return t;
    }

    double parse_real(const std::string& token) const {
      double v = 0.0;
      const auto* end = token.data() + token.size();
      const auto [ptr, ec] = std::from_chars(token.data(), end, v);
      detail::require(ec == std::errc() && ptr == end && std::isfinite(v), where() + "expected a finite number, got",
                      detail::gp_quote(token));
      return v;
    }

    long parse_integer(const std::string& token) const {
      long v = 0;
      const auto* end = token.data() + token.size();
      const auto [ptr, ec] = std::from_chars(token.data(), end, v);
      detail::require(ec == std::errc() && ptr == end, where() + "expected an integer, got", detail::gp_quote(token));
      return v;
    }

    double real(std::string_view key) { return parse_real(expect(key, 1)[1]); }
    long integer(std::string_view key) { return parse_integer(expect(key, 1)[1]); }

    Eigen::VectorXd vector(std::string_view key) {
      auto t = next(detail::gp_quote(key));
      detail::require(t.size() >= 2 && t[0] == key, where() + "expected '" + std::string(key) + " <count> <values>', got",
                      detail::gp_quote(line));
      const long count = parse_integer(t[1]);
      detail::require(count >= 1 && static_cast<std::size_t>(count) + 2 == t.size(),
                      where() + "'" + std::string(key) + "' announces " + t[1] + " values, found",
                      t.size() - 2);
      Eigen::VectorXd v(count);
      for (Eigen::Index i = 0; i < count; ++i) v(i) = parse_real(t[static_cast<std::size_t>(i) + 2]);
      return v;
    }
  };

  void check_training_data(const Eigen::Ref<const Eigen::MatrixXd>& x, const Eigen::Ref<const Eigen::VectorXd>& y) const {
    detail::require(x.rows() >= 1, "GaussianProcess: number of training samples (rows of x) must be >= 1", x.rows());
    detail::require(kernel_.accepts_dimension(x.cols()),
                    "GaussianProcess: kernel does not accept the input dimension (columns of x)", x.cols());
    detail::require(y.size() == x.rows(), "GaussianProcess: size of y must equal the rows of x, size", y.size());
    detail::require(x.allFinite(), "GaussianProcess: x must be finite, rows", x.rows());
    detail::require(y.allFinite(), "GaussianProcess: y must be finite, size", y.size());
  }

  void check_query(const Eigen::Ref<const Eigen::MatrixXd>& xq) const {
    if (dimension_ > 0) {
      detail::require(xq.cols() == dimension_, "GaussianProcess::predict: columns of the query must equal D",
                      xq.cols());
    } else {
      detail::require(kernel_.accepts_dimension(xq.cols()),
                      "GaussianProcess::predict: kernel does not accept the query dimension", xq.cols());
    }
    detail::require(xq.allFinite(), "GaussianProcess::predict: query inputs must be finite, rows", xq.rows());
  }

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

  /// Runs `factor()` (true on success); after a failure, `reset(jitter)` restores the matrix
  /// with `jitter` added to its diagonal and `factor()` runs again, jitter
  /// `initial_jitter * scale * 10^k`, k = 0..max_jitter_attempts-1. Returns the jitter used.
  /// @throws NumericalError when the last attempt fails (n: the matrix size, for the message).
  template <typename Reset, typename Factor>
  double factor_with_jitter(Eigen::Index n, double scale, Reset&& reset, Factor&& factor) const {
    double jitter = 0.0;
    for (int attempt = 0;; ++attempt) {
      if (attempt > 0) {
        jitter = options_.initial_jitter * scale * std::pow(10.0, attempt - 1);
        reset(jitter);
      }
      if (factor()) return jitter;
      if (attempt >= options_.max_jitter_attempts) {
        std::ostringstream os;
        os << "GaussianProcess: covariance matrix (n = " << n << ") is not positive definite after "
           << options_.max_jitter_attempts << " jitter retries (last jitter " << jitter
           << "); inputs nearly repeated with too little noise, or hyperparameters out of range: "
           << kernel_.log_parameters().transpose();
        throw NumericalError(os.str());
      }
    }
  }

  /// Scratch of `evaluate`, kept across the evaluations of one optimiser run.
  struct Workspace {
    Eigen::MatrixXd a;   // K, then L, then K^-1 and the gradient weights (lower triangles)
    Eigen::MatrixXd xt;  // (L^-1)^T
  };

  /// Columns n4 = 4 ceil(n / 4) and leading dimension (a multiple of kGpRowGroup) of the
  /// padded matrices the dense kernels work on.
  static Eigen::Index padded_columns(Eigen::Index n) { return (n + 3) / 4 * 4; }
  static Eigen::Index padded_rows(Eigen::Index n) {
    return (padded_columns(n) + detail::kGpRowGroup - 1) / detail::kGpRowGroup * detail::kGpRowGroup;
  }

  /// K_XX of the first n_ samples for `kernel` into the top-left of `a` (padded to
  /// padded_columns(n_) with the identity; a.rows() a multiple of kGpRowGroup, >=
  /// padded_rows(n_)), factorised in place (dispatched Cholesky up to
  /// `detail::gp_dense_kernel_limit()`, Eigen's blocked LLT above) with jitter retries:
  /// lower(a) = L. Returns the jitter. `fit` (through `evaluate`) and `factorize` share it, so
  /// the optimiser and the final model agree to the last bit.
  double factorize_into(const K& kernel, Eigen::MatrixXd& a) const {
    const Eigen::Index n = n_;
    const Eigen::Index n4 = padded_columns(n);
    ADAPTSEG_ASSERT(a.rows() % detail::kGpRowGroup == 0 && a.rows() >= padded_rows(n) && a.cols() >= n4);
    const auto x = x_.topRows(n);
    const double noise = kernel.noise_variance();
    const auto fill = [&](double jitter) {
      a.leftCols(n4).setZero();
      a.topLeftCorner(n, n) = kernel.cross_covariance(x, x);
      a.diagonal().head(n).array() += noise + jitter;
      a.diagonal().segment(n, n4 - n).setOnes();
    };
    fill(0.0);
    const double scale = std::abs(a.diagonal().head(n).mean());
    if (n <= detail::gp_dense_kernel_limit()) {
      return factor_with_jitter(n, scale, fill, [&] { return detail::gp_cholesky(a.data(), n4, a.rows()); });
    }
    return factor_with_jitter(n, scale, fill, [&] {
      auto l = a.topLeftCorner(n, n);
      Eigen::LLT<Eigen::Ref<Eigen::MatrixXd>, Eigen::Lower> llt(l);
      return llt.info() == Eigen::Success && l.diagonal().allFinite() && (l.diagonal().array() > 0.0).all();
    });
  }

  /// LML (and gradient) of the normalised training targets for `kernel`. The dense work
  /// (Cholesky, L^-1, K^-1 = L^-T L^-1: n^3 flops in all) runs in the dispatched kernels up to
  /// `detail::gp_dense_kernel_limit()`, in Eigen above.
  double evaluate(const K& kernel, Eigen::VectorXd* gradient, Workspace& ws) const {
    const detail::GpScopedFlushSubnormals flush;
    const Eigen::Index n = n_;
    const Eigen::Index n4 = padded_columns(n);
    const Eigen::Index ld = padded_rows(n);
    const auto x = x_.topRows(n);
    Eigen::MatrixXd& a = ws.a;
    a.resize(ld, n4);
    factorize_into(kernel, a);
    const auto l = a.topLeftCorner(n, n);
    const Eigen::VectorXd z = l.template triangularView<Eigen::Lower>().solve(yn_.head(n));
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
      if (n <= detail::gp_dense_kernel_limit()) {
        ws.xt.setZero(ld, n4);
        detail::gp_invert_lower(a.data(), ws.xt.data(), n4, ld);
        detail::gp_gram(ws.xt.data(), a.data(), n4, ld);  // lower(a) = K^-1
      } else {
        detail::gp_invert_lower_in_place(w);
        detail::gp_lower_gram_in_place(w);
      }
      for (Eigen::Index j = 0; j < n; ++j) {
        w.col(j).tail(n - j) = alpha.tail(n - j) * alpha(j) - w.col(j).tail(n - j);
      }
      *gradient = 0.5 * kernel.contract_gradient(x, w);
    }
    return lml;
  }

  /// Factorises K_XX of the current data and hyperparameters into l_, z_, alpha_.
  void factorize() {
    ADAPTSEG_ASSERT(n_ > 0);
    const detail::GpScopedFlushSubnormals flush;
    const Eigen::Index n = n_;
    reserve(padded_rows(n));
    jitter_ = factorize_into(kernel_, l_);
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

  /// Objective of the bounded minimiser: -LML and its gradient; remembers the best point seen.
  struct Objective {
    const GaussianProcess* gp;
    K kernel;
    Workspace work;
    Eigen::VectorXd best_theta;
    double best_value = std::numeric_limits<double>::infinity();
    int evaluations = 0;

    double operator()(const Eigen::VectorXd& theta, Eigen::VectorXd& grad) {
      try {
        kernel.set_log_parameters(theta);
        Eigen::VectorXd g;
        const double lml = gp->evaluate(kernel, &g, work);
        ++evaluations;
        grad = -g;
        if (-lml < best_value) {
          best_value = -lml;
          best_theta = theta;
        }
        return -lml;
      } catch (...) {
        throw detail::GpObjectiveAborted{std::current_exception()};
      }
    }
  };

  void optimize(const FitOptions& fo, FitSummary& summary) {
    const Eigen::VectorXd lower = kernel_.log_lower_bounds();
    const Eigen::VectorXd upper = kernel_.log_upper_bounds();
    detail::GpSplitMix64 rng(fo.seed);
    detail::BoxMinimizerSettings settings{.history = fo.history,
                                          .gradient_tolerance = fo.gradient_tolerance,
                                          .relative_tolerance = fo.relative_tolerance,
                                          .max_iterations = fo.max_iterations};
    double best = std::numeric_limits<double>::infinity();
    for (int r = 0; r <= fo.restarts; ++r) {
      StartSummary start;
      Eigen::VectorXd theta = kernel_.log_parameters();
      if (r > 0) {
        for (Eigen::Index i = 0; i < theta.size(); ++i) theta(i) = lower(i) + rng.uniform() * (upper(i) - lower(i));
      }
      theta = theta.cwiseMax(lower).cwiseMin(upper);
      start.initial_log_parameters = theta;
      Objective objective{this, kernel_, {}, {}, std::numeric_limits<double>::infinity(), 0};
      // The minimiser signals a failed line search (or a non-descent direction from its
      // subspace minimisation) by an exception. Like scipy's driver, restart from the best
      // point seen with a fresh quasi-Newton memory while that still improves the objective.
      int runs = 0;
      while (true) {
        const double before = objective.best_value;
        settings.max_iterations = std::max(1, fo.max_iterations - start.iterations);
        try {
          start.iterations += detail::minimize_in_box(objective, theta, lower, upper, settings);
          start.status = start.iterations >= fo.max_iterations ? FitStatus::kMaxIterations : FitStatus::kConverged;
          break;
        } catch (const detail::GpObjectiveAborted& aborted) {
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
        const bool improved =
            objective.best_value < before &&
            (!std::isfinite(before) || before - objective.best_value > fo.relative_tolerance * std::max(1.0, std::abs(before)));
        if (!improved || ++runs > kMaxSolverRestarts || start.iterations >= fo.max_iterations) break;
        theta = objective.best_theta;
      }
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
    const StartSummary& chosen = summary.starts[summary.best_start];
    summary.status = chosen.status;
    kernel_.set_log_parameters(chosen.log_parameters);
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
