#pragma once
/// @file
/// Internals of gaussian_process.hpp: blocked triangular inversion and Gram products, a scope
/// that flushes subnormals, and the seeded random generator of the optimiser's restarts.

#include <Eigen/Core>

#if defined(__SSE2__) || defined(_M_X64)
#include <xmmintrin.h>
#define ADAPTSEG_GP_HAS_MXCSR 1
#endif

#include <cstdint>
#include <exception>

namespace adaptseg {

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
        const Eigen::VectorXd t = a.bottomRightCorner(m, m).template triangularView<Eigen::Lower>() * a.col(j).tail(m);
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
  a.bottomLeftCorner(n2, n1).noalias() = -(a.bottomRightCorner(n2, n2).template triangularView<Eigen::Lower>() * t);
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
  a.topLeftCorner(n1, n1).template selfadjointView<Eigen::Lower>().rankUpdate(a.bottomLeftCorner(n2, n1).transpose());
  const Eigen::MatrixXd t =
      a.bottomRightCorner(n2, n2).template triangularView<Eigen::Lower>().transpose() * a.bottomLeftCorner(n2, n1);
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

}  // namespace detail

}  // namespace adaptseg
