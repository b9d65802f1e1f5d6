#pragma once
/// @file
/// Internals of gaussian_process.hpp: the vectorised loops of prediction and fitting
/// (exponentials of the squared-exponential kernel, the triangular solve of the predictive
/// variance), each compiled for SSE2, AVX2 + FMA and AVX-512 and chosen once at run time.

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>

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
/// `params` and `args` are parenthesised lists, spliced after a name as they are: they cannot
/// take parentheses of their own (clang-tidy's bugprone-macro-parentheses, off for the macro).
// NOLINTBEGIN(bugprone-macro-parentheses)
#if defined(ADAPTSEG_GP_DISPATCH)
#define ADAPTSEG_GP_DISPATCHED(ret, name, params, args)                                       \
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
#define ADAPTSEG_GP_DISPATCHED(ret, name, params, args)   \
  inline ret name params { return name##_body<16> args; } \
  static_assert(true, "a use ends with a semicolon")
#endif
// NOLINTEND(bugprone-macro-parentheses)

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
      for (Eigen::Index i = std::max(b0, ps); i < n4; ++i)
        gp_rank_one_4x2<Bytes>(s, xt + i * ld + b0, xt + i * ld + ps);
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
/// Eigen's blocked LLT and the recursive triangular inverse/Gram product are faster. The limits
/// are measured crossovers (docs/benchmarks.md, "Design notes that matter for speed").
[[nodiscard]] inline Eigen::Index gp_dense_kernel_limit() {
  switch (gp_simd_level()) {
    case 2: return 768;
    case 1: return 512;
    default: return 384;
  }
}

}  // namespace detail

}  // namespace adaptseg
