// Tests for adaptseg/core/gaussian_process.hpp: kernel concept, a conformance suite run on every
// kernel model, agreement with scikit-learn (fixtures from tests/tools/make_gp_fixtures.py),
// and properties (gradient, online updates, degenerate data, persistence).

#include <adaptseg/core/gaussian_process.hpp>

#include <doctest/doctest.h>

#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <limits>
#include <map>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

using adaptseg::ArdSquaredExponentialKernel;
using adaptseg::FitStatus;
using adaptseg::GaussianProcess;
using adaptseg::PredictiveVariance;
using adaptseg::SquaredExponentialKernel;

// ---- concept tests ---------------------------------------------------------------------------

// Positive: the shipped kernels.
static_assert(adaptseg::Kernel<SquaredExponentialKernel>);
static_assert(adaptseg::Kernel<ArdSquaredExponentialKernel>);
static_assert(adaptseg::LogParameterized<SquaredExponentialKernel>);
static_assert(adaptseg::LatentCovariance<ArdSquaredExponentialKernel>);
static_assert(adaptseg::ObservationNoise<SquaredExponentialKernel>);
static_assert(adaptseg::ContractedGradient<ArdSquaredExponentialKernel>);
static_assert(adaptseg::RestorableKernel<SquaredExponentialKernel>);

// A kernel with everything, to derive the negative cases from by removing one piece.
struct CompleteKernel {
  static constexpr std::string_view kName = "complete";
  static CompleteKernel from_log_parameters(const Eigen::VectorXd&, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return {};
  }
  Eigen::VectorXd log_parameters() const { return {}; }
  Eigen::VectorXd log_lower_bounds() const { return {}; }
  Eigen::VectorXd log_upper_bounds() const { return {}; }
  void set_log_parameters(const Eigen::VectorXd&) {}
  bool accepts_dimension(Eigen::Index) const { return true; }
  Eigen::MatrixXd cross_covariance(const Eigen::MatrixXd&, const Eigen::MatrixXd&) const { return {}; }
  Eigen::VectorXd prior_variance(const Eigen::MatrixXd&) const { return {}; }
  double noise_variance() const { return 1.0; }
  Eigen::VectorXd contract_gradient(const Eigen::MatrixXd&, const Eigen::MatrixXd&) const { return {}; }
};
static_assert(adaptseg::Kernel<CompleteKernel>);

struct NoGradient : CompleteKernel {
  void contract_gradient() const = delete;
};
struct NoNoise {  // everything but noise_variance
  [[maybe_unused]] static constexpr std::string_view kName = "no_noise";
  static NoNoise from_log_parameters(const Eigen::VectorXd&, const Eigen::VectorXd&, const Eigen::VectorXd&) {
    return {};
  }
  Eigen::VectorXd log_parameters() const { return {}; }
  Eigen::VectorXd log_lower_bounds() const { return {}; }
  Eigen::VectorXd log_upper_bounds() const { return {}; }
  void set_log_parameters(const Eigen::VectorXd&) {}
  bool accepts_dimension(Eigen::Index) const { return true; }
  Eigen::MatrixXd cross_covariance(const Eigen::MatrixXd&, const Eigen::MatrixXd&) const { return {}; }
  Eigen::VectorXd prior_variance(const Eigen::MatrixXd&) const { return {}; }
  Eigen::VectorXd contract_gradient(const Eigen::MatrixXd&, const Eigen::MatrixXd&) const { return {}; }
};
struct FloatCovariance : CompleteKernel {  // wrong return type
  Eigen::MatrixXf cross_covariance(const Eigen::MatrixXd&, const Eigen::MatrixXd&) const { return {}; }
};
struct NoName : CompleteKernel {
  [[maybe_unused]] static constexpr int kName = 0;  // not a string
};
struct Immutable : CompleteKernel {  // cannot be set from the optimiser
  void set_log_parameters(const Eigen::VectorXd&) = delete;
};
struct NotCopyable : CompleteKernel {
  NotCopyable() = default;
  NotCopyable(const NotCopyable&) = delete;
  NotCopyable& operator=(const NotCopyable&) = delete;
};
static_assert(!adaptseg::Kernel<NoGradient> && !adaptseg::ContractedGradient<NoGradient>);
static_assert(!adaptseg::Kernel<NoNoise> && !adaptseg::ObservationNoise<NoNoise>);
static_assert(!adaptseg::Kernel<FloatCovariance> && !adaptseg::LatentCovariance<FloatCovariance>);
static_assert(!adaptseg::Kernel<NoName> && !adaptseg::RestorableKernel<NoName>);
static_assert(!adaptseg::Kernel<Immutable> && !adaptseg::LogParameterized<Immutable>);
static_assert(!adaptseg::Kernel<NotCopyable>);
static_assert(!adaptseg::Kernel<int>);
static_assert(!adaptseg::Kernel<Eigen::MatrixXd>);

// ---- helpers -----------------------------------------------------------------------------------

/// max_i |a_i - b_i| / scale
double scaled_error(const Eigen::VectorXd& a, const Eigen::VectorXd& b, double scale) {
  REQUIRE(a.size() == b.size());
  return (a - b).cwiseAbs().maxCoeff() / scale;
}

/// max_i |a_i - b_i| / |b_i| (b_i != 0)
double relative_error(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  REQUIRE(a.size() == b.size());
  return ((a - b).array().abs() / b.array().abs()).maxCoeff();
}

Eigen::MatrixXd random_inputs(Eigen::Index n, Eigen::Index d, unsigned seed, double lo = 0.0, double hi = 5.0) {
  adaptseg::detail::GpSplitMix64 rng(seed);
  Eigen::MatrixXd x(n, d);
  for (Eigen::Index i = 0; i < n; ++i)
    for (Eigen::Index j = 0; j < d; ++j) x(i, j) = lo + (hi - lo) * rng.uniform();
  return x;
}

Eigen::VectorXd smooth_targets(const Eigen::MatrixXd& x, unsigned seed, double noise = 0.1) {
  adaptseg::detail::GpSplitMix64 rng(seed);
  Eigen::VectorXd y(x.rows());
  for (Eigen::Index i = 0; i < x.rows(); ++i) {
    double v = 3.0 + std::sin(x(i, 0));
    for (Eigen::Index j = 1; j < x.cols(); ++j) v += 0.5 * std::cos(0.7 * x(i, j));
    y(i) = v + noise * (rng.uniform() - 0.5);
  }
  return y;
}

// ---- scikit-learn fixtures -----------------------------------------------------------------------

struct Fixture {
  std::string name;
  bool ard = false;
  Eigen::Index dimension = 0;
  bool normalize = false;
  double sf2 = 0, ls = 0, sn2 = 0;
  double bounds[6] = {};
  int restarts = 0;
  Eigen::MatrixXd x;
  Eigen::VectorXd y;
  Eigen::VectorXd eval_theta;
  double lml = 0;
  Eigen::VectorXd lml_gradient;
  Eigen::MatrixXd xt;
  Eigen::VectorXd mean, latent_var, noisy_var;
  Eigen::MatrixXd latent_cov;
  Eigen::VectorXd fitted_theta;
  double fitted_lml = 0;
};

Eigen::VectorXd read_values(std::istringstream& ls) {
  std::vector<double> v;
  double d = 0;
  while (ls >> d) v.push_back(d);
  return Eigen::Map<Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

std::string next_line(std::ifstream& in) {
  std::string line;
  while (std::getline(in, line)) {
    if (!line.empty() && line[0] != '#') return line;
  }
  throw std::runtime_error("fixture truncated");
}

Fixture load_fixture(const std::string& name) {
  const std::string path = std::string(ADAPTSEG_TEST_DATA_DIR) + "/gp/" + name + ".txt";
  std::ifstream in(path);
  REQUIRE_MESSAGE(in.good(), "cannot open fixture " << path);
  Fixture f;
  f.name = name;
  while (true) {
    std::istringstream ls(next_line(in));
    std::string key;
    ls >> key;
    if (key == "end") break;
    if (key == "kernel") {
      std::string k;
      ls >> k;
      f.ard = k == "ard";
    } else if (key == "dimension") {
      ls >> f.dimension;
    } else if (key == "normalize_y") {
      int v = 0;
      ls >> v;
      f.normalize = v != 0;
    } else if (key == "initial") {
      std::string a, b, c;
      ls >> a >> f.sf2 >> b >> f.ls >> c >> f.sn2;
    } else if (key == "bounds") {
      for (double& b : f.bounds) ls >> b;
    } else if (key == "restarts") {
      ls >> f.restarts;
    } else if (key == "train" || key == "test") {
      Eigen::Index n = 0;
      ls >> n;
      const Eigen::Index extra = key == "train" ? 1 : 3;
      Eigen::MatrixXd rows(n, f.dimension + extra);
      for (Eigen::Index i = 0; i < n; ++i) {
        std::istringstream rs(next_line(in));
        const Eigen::VectorXd v = read_values(rs);
        REQUIRE(v.size() == rows.cols());
        rows.row(i) = v.transpose();
      }
      if (key == "train") {
        f.x = rows.leftCols(f.dimension);
        f.y = rows.col(f.dimension);
      } else {
        f.xt = rows.leftCols(f.dimension);
        f.mean = rows.col(f.dimension);
        f.latent_var = rows.col(f.dimension + 1);
        f.noisy_var = rows.col(f.dimension + 2);
      }
    } else if (key == "latent_covariance") {
      Eigen::Index m = 0;
      ls >> m;
      f.latent_cov.resize(m, m);
      for (Eigen::Index i = 0; i < m; ++i) {
        std::istringstream rs(next_line(in));
        f.latent_cov.row(i) = read_values(rs).transpose();
      }
    } else if (key == "eval_theta") {
      f.eval_theta = read_values(ls);
    } else if (key == "lml") {
      ls >> f.lml;
    } else if (key == "lml_gradient") {
      f.lml_gradient = read_values(ls);
    } else if (key == "fitted_theta") {
      f.fitted_theta = read_values(ls);
    } else if (key == "fitted_lml") {
      ls >> f.fitted_lml;
    }
  }
  return f;
}

const std::vector<std::string>& fixture_names() {
  static const std::vector<std::string> names = {"iso_1d_smooth",
                                                 "iso_1d_noisy_normalized",
                                                 "iso_1d_low_noise",
                                                 "iso_2d",
                                                 "ard_2d_normalized",
                                                 "badly_scaled_1d_normalized",
                                                 "badly_scaled_ard_2d_normalized",
                                                 "badly_scaled_1d_raw"};
  return names;
}

template <typename K>
typename K::Bounds fixture_bounds(const Fixture& f) {
  typename K::Bounds b;
  b.signal_variance = {f.bounds[0], f.bounds[1]};
  b.length_scale = {f.bounds[2], f.bounds[3]};
  b.noise_variance = {f.bounds[4], f.bounds[5]};
  return b;
}

template <typename K>
K fixture_kernel(const Fixture& f) {
  if constexpr (std::is_same_v<K, ArdSquaredExponentialKernel>) {
    return K(Eigen::VectorXd::Constant(f.dimension, f.ls), f.sf2, f.sn2, fixture_bounds<K>(f));
  } else {
    return K(f.ls, f.sf2, f.sn2, fixture_bounds<K>(f));
  }
}

/// Runs `check` with a GaussianProcess of the fixture's kernel type, conditioned on its data
/// at the initial hyperparameters (normalisation computed as scikit-learn does in fit).
template <typename Check>
void with_fixture_model(const Fixture& f, Check&& check) {
  const auto run = [&](auto kernel) {
    using K = decltype(kernel);
    typename GaussianProcess<K>::Options options;
    options.normalize_y = f.normalize;
    GaussianProcess<K> gp(kernel, options);
    gp.fit(f.x, f.y, {.optimize = false});
    check(gp);
  };
  if (f.ard) {
    run(fixture_kernel<ArdSquaredExponentialKernel>(f));
  } else {
    run(fixture_kernel<SquaredExponentialKernel>(f));
  }
}

}  // namespace

// ============================================================================================
// Kernel conformance suite: every model of adaptseg::Kernel runs it.
// ============================================================================================

namespace {
template <typename K>
K conformance_kernel(Eigen::Index dims) {
  if constexpr (std::is_same_v<K, ArdSquaredExponentialKernel>) {
    Eigen::VectorXd ls(dims);
    for (Eigen::Index d = 0; d < dims; ++d) ls(d) = 0.7 + 0.5 * static_cast<double>(d);
    return K(ls, 1.7, 0.05);
  } else {
    return K(0.9, 1.7, 0.05);
  }
}
}  // namespace

TEST_CASE_TEMPLATE("kernel conformance: covariance, parameters, contracted gradient", K, SquaredExponentialKernel,
                   ArdSquaredExponentialKernel) {
  for (Eigen::Index dims : {1, 2, 3}) {
    CAPTURE(dims);
    const K k = conformance_kernel<K>(dims);
    REQUIRE(k.accepts_dimension(dims));
    CHECK_FALSE(k.accepts_dimension(0));
    const Eigen::MatrixXd a = random_inputs(7, dims, 1);
    const Eigen::MatrixXd b = random_inputs(4, dims, 2);

    // cross_covariance: shape, symmetry, transposition, diagonal = prior_variance, PSD.
    const Eigen::MatrixXd kab = k.cross_covariance(a, b);
    CHECK(kab.rows() == 7);
    CHECK(kab.cols() == 4);
    // Symmetric up to rounding (vectorised and scalar exp may differ in the last bit).
    const double sf2 = k.prior_variance(a)(0);
    CHECK((kab - k.cross_covariance(b, a).transpose()).cwiseAbs().maxCoeff() <= 4e-16 * sf2);
    const Eigen::MatrixXd kaa = k.cross_covariance(a, a);
    CHECK((kaa - kaa.transpose()).cwiseAbs().maxCoeff() <= 4e-16 * sf2);
    CHECK((kaa.diagonal() - k.prior_variance(a)).cwiseAbs().maxCoeff() < 1e-15);
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(kaa);
    CHECK(eig.eigenvalues().minCoeff() > -1e-12);
    CHECK(k.noise_variance() > 0.0);
    CHECK_THROWS_AS((void)k.cross_covariance(a, random_inputs(3, dims + 1, 3)), std::invalid_argument);

    // Parameters: sizes, bounds, round trip, from_log_parameters.
    const Eigen::VectorXd theta = k.log_parameters();
    CHECK(k.log_lower_bounds().size() == theta.size());
    CHECK(k.log_upper_bounds().size() == theta.size());
    CHECK((k.log_lower_bounds().array() < k.log_upper_bounds().array()).all());
    K k2 = k;
    Eigen::VectorXd theta2 = theta.array() + 0.1;
    k2.set_log_parameters(theta2);
    CHECK(k2.log_parameters() == theta2);
    CHECK_THROWS_AS(k2.set_log_parameters(Eigen::VectorXd::Zero(theta.size() + 1)), std::invalid_argument);
    Eigen::VectorXd bad = theta;
    bad(0) = std::nan("");
    CHECK_THROWS_AS(k2.set_log_parameters(bad), std::invalid_argument);
    const K k3 = K::from_log_parameters(theta, k.log_lower_bounds(), k.log_upper_bounds());
    CHECK(k3.log_parameters() == theta);
    CHECK((k3.cross_covariance(a, b) - kab).cwiseAbs().maxCoeff() == 0.0);

    // contract_gradient against central differences of sum_ij W_ij K_ij (lower triangle of W).
    Eigen::MatrixXd w = random_inputs(7, 7, 4, -1.0, 1.0);
    w = (w + w.transpose()).eval();
    const Eigen::VectorXd g = k.contract_gradient(a, w);
    REQUIRE(g.size() == theta.size());
    Eigen::MatrixXd w_lower_only = w.template triangularView<Eigen::Lower>();  // upper must be ignored
    w_lower_only.template triangularView<Eigen::StrictlyUpper>().setConstant(1e6);
    CHECK((k.contract_gradient(a, w_lower_only) - g).cwiseAbs().maxCoeff() == 0.0);
    for (Eigen::Index p = 0; p < theta.size(); ++p) {
      const double h = 1e-5;
      const auto weighted = [&](double delta) {
        K kk = k;
        Eigen::VectorXd t = theta;
        t(p) += delta;
        kk.set_log_parameters(t);
        Eigen::MatrixXd kxx = kk.cross_covariance(a, a);
        kxx.diagonal().array() += kk.noise_variance();
        return (w.array() * kxx.array()).sum();
      };
      const double fd = (weighted(h) - weighted(-h)) / (2.0 * h);
      CAPTURE(p);
      CHECK(std::abs(g(p) - fd) <= 1e-7 * std::max(1.0, std::abs(fd)));
    }
  }
}

TEST_CASE("squared exponential: value of eq:sqexp and argument checks") {
  const SquaredExponentialKernel k(2.0, 3.0, 0.5);
  Eigen::MatrixXd a(1, 2), b(1, 2);
  a << 0.0, 0.0;
  b << 1.0, 2.0;  // r^2 = 5, l = 2
  CHECK(k.cross_covariance(a, b)(0, 0) == doctest::Approx(3.0 * std::exp(-0.5 * 5.0 / 4.0)).epsilon(1e-15));
  CHECK(k.signal_variance() == doctest::Approx(3.0));
  CHECK(k.noise_variance() == doctest::Approx(0.5));
  CHECK(k.length_scales()(0) == doctest::Approx(2.0));

  Eigen::VectorXd ls(2);
  ls << 1.0, 4.0;
  const ArdSquaredExponentialKernel ard(ls, 3.0, 0.5);
  CHECK(ard.cross_covariance(a, b)(0, 0) == doctest::Approx(3.0 * std::exp(-0.5 * (1.0 + 4.0 / 16.0))).epsilon(1e-15));
  CHECK_FALSE(ard.accepts_dimension(1));
  CHECK(ard.log_parameters().size() == 4);

  CHECK_THROWS_WITH_AS(SquaredExponentialKernel(-1.0), doctest::Contains("length_scale"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(SquaredExponentialKernel(1.0, 0.0), doctest::Contains("signal_variance"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(SquaredExponentialKernel(1.0, 1.0, std::nan("")), doctest::Contains("noise_variance"),
                       std::invalid_argument);
  SquaredExponentialKernel::Bounds bad;
  bad.noise_variance = {1.0, 0.5};
  CHECK_THROWS_WITH_AS(SquaredExponentialKernel(1.0, 1.0, 1.0, bad), doctest::Contains("bounds.noise_variance.upper"),
                       std::invalid_argument);
  CHECK_THROWS_AS(ArdSquaredExponentialKernel(Eigen::VectorXd(0)), std::invalid_argument);
}

namespace {
// The instruction sets this CPU can run: 0 = baseline, 1 = AVX2 + FMA, 2 = AVX-512F. Each
// compiled variant is called directly, so an AVX-512 machine tests the AVX2 kernels too.
std::vector<int> runnable_simd_levels() {
  std::vector<int> out{0};
#if defined(ADAPTSEG_GP_DISPATCH)
  if (__builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma")) out.push_back(1);
  if (__builtin_cpu_supports("avx512f")) out.push_back(2);
#endif
  return out;
}
}  // namespace

#if defined(ADAPTSEG_GP_DISPATCH)
#define GP_AT_LEVEL(level, name, ...)                            \
  ((level) == 2   ? adaptseg::detail::name##_avx512(__VA_ARGS__) \
   : (level) == 1 ? adaptseg::detail::name##_avx2(__VA_ARGS__)   \
                  : adaptseg::detail::name##_body<16>(__VA_ARGS__))
#else
#define GP_AT_LEVEL(level, name, ...) adaptseg::detail::name##_body<16>(__VA_ARGS__)
#endif

TEST_CASE("vectorised kernels: every instruction set this CPU runs, and the dispatched one, against the reference") {
  using adaptseg::detail::kGpQueryBlock;
  // sf2 * exp(-r2 / 2), 0 from r2 = 690 on; sizes that leave a tail for every vector width.
  std::vector<double> r2 = {0.0, 1e-300, 4e-17, 0.5, 689.999, 690.0, 1e3};
  adaptseg::detail::GpSplitMix64 rng(7);
  for (int i = 0; i < 2000; ++i) r2.push_back(700.0 * rng.uniform());
  r2.push_back(3.0);
  const auto check_exp = [&](const std::vector<double>& got) {
    for (std::size_t i = 0; i < r2.size(); ++i) {
      const double ref = r2[i] < 690.0 ? 1.7 * std::exp(-0.5 * r2[i]) : 0.0;
      if (ref == 0.0) {
        CHECK(got[i] == 0.0);
      } else {
        CHECK(std::abs(got[i] - ref) <= 4.0 * std::numeric_limits<double>::epsilon() * ref);
      }
    }
  };
  std::vector<double> dispatched = r2;
  adaptseg::detail::gp_squared_exponential(dispatched.data(), static_cast<Eigen::Index>(r2.size()), 1.7);
  check_exp(dispatched);
  for (const int level : runnable_simd_levels()) {
    CAPTURE(level);
    std::vector<double> got = r2;
    GP_AT_LEVEL(level, gp_squared_exponential, got.data(), static_cast<Eigen::Index>(r2.size()), 1.7);
    check_exp(got);
    CHECK(got[0] == 1.7);
  }

  // v = L^-1 k per query, mean = z^T v, ssq = v^T v, for n with and without padding.
  for (const Eigen::Index n : {Eigen::Index{1}, Eigen::Index{13}, Eigen::Index{72}}) {
    CAPTURE(n);
    const Eigen::MatrixXd a = random_inputs(n, n, 11);
    const Eigen::MatrixXd spd = a * a.transpose() + static_cast<double>(n) * Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd l = spd.llt().matrixL();
    const Eigen::VectorXd z = random_inputs(n, 1, 12, -1.0, 1.0);
    const adaptseg::detail::GpPackedFactor factor(l, z);
    Eigen::MatrixXd c = Eigen::MatrixXd::Zero(kGpQueryBlock, factor.n4);
    c.leftCols(n) = random_inputs(kGpQueryBlock, n, 13);
    const Eigen::Index lanes = 37;
    for (const int level : runnable_simd_levels()) {
      CAPTURE(level);
      Eigen::MatrixXd v = c;
      Eigen::VectorXd mean(kGpQueryBlock), ssq(kGpQueryBlock);
      GP_AT_LEVEL(level, gp_lower_solve, factor, v.data(), lanes, mean.data(), ssq.data());
      for (Eigen::Index q = 0; q < lanes; ++q) {
        const Eigen::VectorXd ref = l.triangularView<Eigen::Lower>().solve(c.row(q).head(n).transpose());
        CHECK(scaled_error(v.row(q).head(n).transpose(), ref, ref.cwiseAbs().maxCoeff()) < 1e-13);
        CHECK(mean(q) == doctest::Approx(z.dot(ref)).epsilon(1e-12));
        CHECK(ssq(q) == doctest::Approx(ref.squaredNorm()).epsilon(1e-12));
      }
    }

    // Cholesky, L^-1 and K^-1 = L^-T L^-1 on the padded layout of a likelihood evaluation.
    const Eigen::Index n4 = factor.n4;
    const Eigen::Index ld = (n4 + 15) / 16 * 16;
    const Eigen::MatrixXd inverse = spd.llt().solve(Eigen::MatrixXd::Identity(n, n));
    for (const int level : runnable_simd_levels()) {
      CAPTURE(level);
      Eigen::MatrixXd m = Eigen::MatrixXd::Zero(ld, n4);
      Eigen::MatrixXd xt = Eigen::MatrixXd::Zero(ld, n4);
      m.topLeftCorner(n, n) = spd;
      m.diagonal().segment(n, n4 - n).setOnes();
      REQUIRE(GP_AT_LEVEL(level, gp_cholesky, m.data(), n4, ld));
      const Eigen::MatrixXd lm = m.topLeftCorner(n, n).triangularView<Eigen::Lower>();
      CHECK((lm - l).cwiseAbs().maxCoeff() < 1e-13 * l.cwiseAbs().maxCoeff());
      GP_AT_LEVEL(level, gp_invert_lower, m.data(), xt.data(), n4, ld);
      GP_AT_LEVEL(level, gp_gram, xt.data(), m.data(), n4, ld);
      const Eigen::MatrixXd got = m.topLeftCorner(n, n).triangularView<Eigen::Lower>();
      const Eigen::MatrixXd want = inverse.triangularView<Eigen::Lower>();
      CHECK((got - want).cwiseAbs().maxCoeff() < 1e-13 * want.cwiseAbs().maxCoeff());
    }
    // A matrix that is not positive definite is reported, not factorised.
    Eigen::MatrixXd bad = Eigen::MatrixXd::Zero(ld, n4);
    bad.diagonal().setOnes();
    bad(n - 1, n - 1) = -1.0;
    CHECK_FALSE(adaptseg::detail::gp_cholesky(bad.data(), n4, ld));
  }
}

TEST_CASE("likelihood: dispatched kernels and the Eigen path on both sides of the size limit") {
  const Eigen::Index limit = adaptseg::detail::gp_dense_kernel_limit();
  for (const Eigen::Index n : {limit, limit + 1}) {
    CAPTURE(n);
    const Eigen::MatrixXd x = random_inputs(n, 1, 21, 0.0, 50.0);
    const Eigen::VectorXd y = smooth_targets(x, 22);
    const SquaredExponentialKernel kernel(0.5, 1.0, 0.1);
    GaussianProcess<SquaredExponentialKernel> gp(kernel);
    gp.fit(x, y, {.optimize = false});
    Eigen::VectorXd grad;
    const double lml = gp.log_marginal_likelihood(kernel.log_parameters(), &grad);
    // The fitted model and the optimiser's objective share the factorisation: equal bits.
    CHECK(lml == gp.log_marginal_likelihood());

    Eigen::MatrixXd k = kernel.cross_covariance(x, x);
    k.diagonal().array() += kernel.noise_variance();
    const Eigen::LLT<Eigen::MatrixXd> llt(k);
    const Eigen::VectorXd alpha = llt.solve(y);
    const Eigen::MatrixXd l = llt.matrixL();
    const double lml_ref = -0.5 * y.dot(alpha) - l.diagonal().array().log().sum() -
                           0.5 * static_cast<double>(n) * std::log(2.0 * std::numbers::pi);
    const Eigen::MatrixXd w = alpha * alpha.transpose() - llt.solve(Eigen::MatrixXd::Identity(n, n));
    const Eigen::VectorXd grad_ref = 0.5 * kernel.contract_gradient(x, w);
    CHECK(lml == doctest::Approx(lml_ref).epsilon(1e-10));
    CHECK(scaled_error(grad, grad_ref, std::max(1.0, grad_ref.cwiseAbs().maxCoeff())) < 1e-8);
  }
}

// ============================================================================================
// Agreement with scikit-learn 1.2.1 (fixtures)
// ============================================================================================

TEST_CASE("sklearn: log marginal likelihood and gradient at given hyperparameters") {
  for (const auto& name : fixture_names()) {
    CAPTURE(name);
    const Fixture f = load_fixture(name);
    with_fixture_model(f, [&](const auto& gp) {
      Eigen::VectorXd grad;
      const double lml = gp.log_marginal_likelihood(f.eval_theta, &grad);
      CHECK(std::abs(lml - f.lml) <= 1e-8 * std::abs(f.lml));
      // Componentwise relative error; every reference component is well away from zero.
      CHECK(relative_error(grad, f.lml_gradient) < 1e-8);
      const double lml_no_grad = gp.log_marginal_likelihood(f.eval_theta);
      CHECK(lml_no_grad == lml);
    });
  }
}

TEST_CASE("sklearn: posterior mean, latent and noisy variance, latent covariance") {
  for (const auto& name : fixture_names()) {
    CAPTURE(name);
    const Fixture f = load_fixture(name);
    with_fixture_model(f, [&](auto& gp) {
      auto kernel = gp.kernel();
      kernel.set_log_parameters(f.eval_theta);
      gp.set_kernel(kernel);
      const auto latent = gp.predict(f.xt, PredictiveVariance::kLatent);
      const auto noisy = gp.predict(f.xt, PredictiveVariance::kNoisy);
      // Means relative to the largest |mean|; variances relative to the prior variance of y
      // (sf2 * std^2), the scale of the two terms whose difference a variance is.
      const double mean_scale = f.mean.cwiseAbs().maxCoeff();
      const double var_scale = kernel.signal_variance() * gp.y_std() * gp.y_std();
      CHECK(scaled_error(latent.mean, f.mean, mean_scale) < 1e-8);
      CHECK(scaled_error(noisy.mean, f.mean, mean_scale) < 1e-8);
      CHECK(scaled_error(latent.variance, f.latent_var, var_scale) < 1e-8);
      CHECK(scaled_error(noisy.variance, f.noisy_var, var_scale) < 1e-8);
      CHECK(scaled_error(gp.predict_mean(f.xt), f.mean, mean_scale) < 1e-8);

      const Eigen::Index m = f.latent_cov.rows();
      const auto cov = gp.predict_covariance(f.xt.topRows(m));
      const Eigen::MatrixXd diff = cov.covariance - f.latent_cov;
      CHECK(diff.cwiseAbs().maxCoeff() / var_scale < 1e-8);
      CHECK(scaled_error(cov.mean, f.mean.head(m), mean_scale) < 1e-8);
      const auto cov_noisy = gp.predict_covariance(f.xt.topRows(m), PredictiveVariance::kNoisy);
      CHECK(scaled_error(cov_noisy.covariance.diagonal(), f.noisy_var.head(m), var_scale) < 1e-8);
    });
  }
}

TEST_CASE("sklearn: fitted log marginal likelihood at least scikit-learn's from the same bounds") {
  for (const auto& name : fixture_names()) {
    CAPTURE(name);
    const Fixture f = load_fixture(name);
    with_fixture_model(f, [&](auto& gp) {
      const auto summary = gp.fit(f.x, f.y, {.restarts = f.restarts, .seed = 0});
      CAPTURE(summary.log_parameters.transpose());
      CAPTURE(f.fitted_theta.transpose());
      CAPTURE(f.fitted_lml);
      CHECK(summary.log_marginal_likelihood >= f.fitted_lml - 1e-6);
      CHECK(summary.starts.size() == static_cast<std::size_t>(f.restarts + 1));
      CHECK(summary.status != FitStatus::kNumericalFailure);
      CHECK(summary.log_marginal_likelihood == gp.log_marginal_likelihood());
      CHECK(gp.log_marginal_likelihood(gp.kernel().log_parameters()) ==
            doctest::Approx(summary.log_marginal_likelihood).epsilon(1e-12));
      const auto lower = gp.kernel().log_lower_bounds();
      const auto upper = gp.kernel().log_upper_bounds();
      CHECK((summary.log_parameters.array() >= lower.array()).all());
      CHECK((summary.log_parameters.array() <= upper.array()).all());
    });
  }
}

// ============================================================================================
// Properties
// ============================================================================================

TEST_CASE_TEMPLATE("property: LML gradient matches central finite differences", K, SquaredExponentialKernel,
                   ArdSquaredExponentialKernel) {
  for (const bool normalize : {false, true}) {
    for (Eigen::Index dims : {1, 2}) {
      CAPTURE(normalize);
      CAPTURE(dims);
      const Eigen::MatrixXd x = random_inputs(30, dims, 11);
      const Eigen::VectorXd y = smooth_targets(x, 12);
      GaussianProcess<K> gp(conformance_kernel<K>(dims), {.normalize_y = normalize});
      gp.fit(x, y, {.optimize = false});
      Eigen::VectorXd theta = gp.kernel().log_parameters();
      theta(0) += 0.2;
      Eigen::VectorXd grad;
      const double lml = gp.log_marginal_likelihood(theta, &grad);
      CHECK(std::isfinite(lml));
      for (Eigen::Index p = 0; p < theta.size(); ++p) {
        const double h = 1e-5;
        Eigen::VectorXd tp = theta, tm = theta;
        tp(p) += h;
        tm(p) -= h;
        const double fd = (gp.log_marginal_likelihood(tp) - gp.log_marginal_likelihood(tm)) / (2.0 * h);
        CAPTURE(p);
        CHECK(std::abs(grad(p) - fd) <= 1e-6 * std::max(1.0, std::abs(fd)));
      }
    }
  }
}

TEST_CASE_TEMPLATE("property: incremental updates equal a batch refit", K, SquaredExponentialKernel,
                   ArdSquaredExponentialKernel) {
  for (const bool normalize : {false, true}) {
    CAPTURE(normalize);
    const Eigen::MatrixXd x = random_inputs(40, 2, 21);
    const Eigen::VectorXd y = smooth_targets(x, 22);
    GaussianProcess<K> online(conformance_kernel<K>(2), {.normalize_y = normalize});
    online.fit(x.topRows(25), y.head(25), {.optimize = false});  // the law holds for any hyperparameters
    const double mean0 = online.y_mean();
    const double std0 = online.y_std();
    const auto theta0 = online.kernel().log_parameters();
    for (Eigen::Index i = 25; i < 40; ++i) online.add_observation(x.row(i).transpose(), y(i));
    CHECK(online.size() == 40);
    // Frozen: hyperparameters and normalisation constants are those of the last fit.
    CHECK(online.kernel().log_parameters() == theta0);
    CHECK(online.y_mean() == mean0);
    CHECK(online.y_std() == std0);

    GaussianProcess<K> batch = online;  // same hyperparameters and frozen normalisation
    batch.condition(x, y);
    CHECK(online.log_marginal_likelihood() == doctest::Approx(batch.log_marginal_likelihood()).epsilon(1e-10));
    const Eigen::MatrixXd xq = random_inputs(50, 2, 23, -1.0, 6.0);
    const auto a = online.predict(xq);
    const auto b = batch.predict(xq);
    CHECK(scaled_error(a.mean, b.mean, b.mean.cwiseAbs().maxCoeff()) < 1e-10);
    CHECK(scaled_error(a.variance, b.variance, online.kernel().signal_variance() * std0 * std0) < 1e-10);
    // predict_mean after online updates (stale alpha path) and after refactorisation.
    CHECK(scaled_error(online.predict_mean(xq), b.mean, b.mean.cwiseAbs().maxCoeff()) < 1e-10);
    CHECK(scaled_error(batch.predict_mean(xq), b.mean, b.mean.cwiseAbs().maxCoeff()) < 1e-12);
    CHECK(online.training_inputs() == x);
    CHECK(online.training_targets() == y);

    // Re-optimisation only when asked: refit recomputes the normalisation from all data.
    const auto s = online.refit({.restarts = 0});
    CHECK(s.starts.size() == 1);
    if (normalize) CHECK(online.y_mean() == doctest::Approx(y.mean()));
  }
}

TEST_CASE("property: online model from scratch equals batch conditioning") {
  GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(0.8, 1.2, 0.05));
  const Eigen::MatrixXd x = random_inputs(12, 1, 31);
  const Eigen::VectorXd y = smooth_targets(x, 32);
  const auto prior = gp.predict(x.topRows(2));
  CHECK(prior.mean.cwiseAbs().maxCoeff() == 0.0);
  CHECK(prior.variance(0) == doctest::Approx(1.2));
  for (Eigen::Index i = 0; i < x.rows(); ++i) gp.add_observation(x.row(i).transpose(), y(i));
  auto batch = gp;
  batch.condition(x, y);
  CHECK(gp.log_marginal_likelihood() == doctest::Approx(batch.log_marginal_likelihood()).epsilon(1e-12));
  CHECK(scaled_error(gp.predict(x).mean, batch.predict(x).mean, 1.0) < 1e-12);
}

TEST_CASE("predictive variance semantics: latent, noisy, covariance, prior") {
  const Eigen::MatrixXd x = random_inputs(15, 1, 41);
  const Eigen::VectorXd y = 100.0 * smooth_targets(x, 42);
  GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(1.0, 1.0, 0.01), {.normalize_y = true});
  gp.fit(x, y, {.optimize = false});
  const Eigen::MatrixXd xq = random_inputs(9, 1, 43, -2.0, 7.0);
  const auto latent = gp.predict(xq);
  const auto noisy = gp.predict(xq, PredictiveVariance::kNoisy);
  const double sn2_y = gp.kernel().noise_variance() * gp.y_std() * gp.y_std();
  CHECK(((noisy.variance - latent.variance).array() - sn2_y).abs().maxCoeff() < 1e-9 * sn2_y);
  CHECK((latent.variance.array() >= 0.0).all());
  const auto cov = gp.predict_covariance(xq);
  CHECK(scaled_error(cov.covariance.diagonal(), latent.variance, gp.y_std() * gp.y_std()) < 1e-12);
  CHECK((cov.covariance - cov.covariance.transpose()).cwiseAbs().maxCoeff() < 1e-9);
  // Far from the data: back to the prior (mean = frozen target mean, variance = sf2 std^2).
  Eigen::MatrixXd far(1, 1);
  far << 1e3;
  const auto p = gp.predict(far);
  CHECK(p.mean(0) == doctest::Approx(gp.y_mean()));
  CHECK(p.variance(0) == doctest::Approx(gp.y_std() * gp.y_std()));
}

TEST_CASE("fit: deterministic restarts and summary") {
  const Eigen::MatrixXd x = random_inputs(15, 2, 51);
  const Eigen::VectorXd y = smooth_targets(x, 52);
  GaussianProcess<ArdSquaredExponentialKernel> a(conformance_kernel<ArdSquaredExponentialKernel>(2));
  auto b = a;
  const auto sa = a.fit(x, y, {.restarts = 2, .seed = 7});
  const auto sb = b.fit(x, y, {.restarts = 2, .seed = 7});
  REQUIRE(sa.starts.size() == 3);
  CHECK(sa.log_parameters == sb.log_parameters);
  CHECK(sa.starts[1].initial_log_parameters == sb.starts[1].initial_log_parameters);
  CHECK(sa.starts[0].initial_log_parameters == conformance_kernel<ArdSquaredExponentialKernel>(2).log_parameters());
  CHECK(sa.starts[1].initial_log_parameters != sa.starts[2].initial_log_parameters);
  CHECK(sa.evaluations > 0);
  for (const auto& s : sa.starts) CHECK(s.log_marginal_likelihood <= sa.log_marginal_likelihood);
  CHECK(sa.log_marginal_likelihood == sa.starts[sa.best_start].log_marginal_likelihood);

  // A tiny iteration budget is reported as a status, not an exception.
  auto c = a;
  const auto sc = c.fit(x, y, {.restarts = 0, .max_iterations = 1});
  CHECK(sc.status == FitStatus::kMaxIterations);
  CHECK(adaptseg::to_string(sc.status) == "max_iterations");
  CHECK(adaptseg::to_string(static_cast<FitStatus>(99)) == "unknown");

  auto d = a;
  const auto sd = d.fit(x, y, {.optimize = false});
  CHECK(sd.status == FitStatus::kNotOptimized);
  CHECK(sd.starts.empty());
  // `a` was fitted, so `d` (a copy) starts from a's fitted hyperparameters and keeps them.
  CHECK(d.kernel().log_parameters() == a.kernel().log_parameters());
}

// ============================================================================================
// Degenerate data and errors
// ============================================================================================

TEST_CASE("degenerate: repeated and nearly repeated inputs") {
  Eigen::MatrixXd x(6, 1);
  x << 0.5, 0.5, 0.5, 1.0, 1.0 + 1e-12, 2.0;
  Eigen::VectorXd y(6);
  y << 1.0, 1.1, 0.9, 2.0, 2.0, 0.5;
  SquaredExponentialKernel::Bounds bounds;
  bounds.noise_variance = {1e-20, 1.0};
  GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(1.0, 1.0, 1e-20, bounds));
  gp.fit(x, y, {.optimize = false});  // K_XX is singular to working precision: jitter
  CHECK(gp.jitter() > 0.0);
  CHECK(std::isfinite(gp.log_marginal_likelihood()));
  const auto p = gp.predict(x);
  CHECK(p.mean.allFinite());
  CHECK(p.variance.allFinite());
  const auto s = gp.fit(x, y, {.restarts = 2});
  CHECK(std::isfinite(s.log_marginal_likelihood));
  // A repeated input online: the O(n^2) extension may not be positive: refactorisation.
  GaussianProcess<SquaredExponentialKernel> online(SquaredExponentialKernel(1.0, 1.0, 1e-20, bounds));
  for (Eigen::Index i = 0; i < x.rows(); ++i) online.add_observation(x.row(i).transpose(), y(i));
  CHECK(online.size() == 6);
  CHECK(online.predict(x).mean.allFinite());
}

TEST_CASE("degenerate: single sample and constant targets") {
  Eigen::MatrixXd x1(1, 2);
  x1 << 0.3, 0.4;
  Eigen::VectorXd y1(1);
  y1 << 7.0;
  for (const bool normalize : {false, true}) {
    CAPTURE(normalize);
    GaussianProcess<SquaredExponentialKernel> gp(SquaredExponentialKernel(), {.normalize_y = normalize});
    const auto s = gp.fit(x1, y1, {.restarts = 2});
    CHECK(std::isfinite(s.log_marginal_likelihood));
    const auto p = gp.predict(x1);
    CHECK(p.mean.allFinite());
    if (normalize) CHECK(gp.y_std() == 1.0);  // std of one sample is 0: taken as 1

    const Eigen::MatrixXd x = random_inputs(10, 2, 61);
    const Eigen::VectorXd y = Eigen::VectorXd::Constant(10, 1234.5);
    const auto sc = gp.fit(x, y, {.restarts = 2});
    CHECK(std::isfinite(sc.log_marginal_likelihood));
    const auto pc = gp.predict(random_inputs(5, 2, 62));
    CHECK(pc.mean.allFinite());
    if (normalize) {
      CHECK(gp.y_std() == 1.0);
      CHECK(scaled_error(pc.mean, Eigen::VectorXd::Constant(5, 1234.5), 1234.5) < 1e-12);
    }
  }
}

TEST_CASE("errors: non-finite input, shapes, options, numerical failure") {
  const Eigen::MatrixXd x = random_inputs(5, 1, 71);
  const Eigen::VectorXd y = smooth_targets(x, 72);
  GaussianProcess<SquaredExponentialKernel> gp{SquaredExponentialKernel()};
  Eigen::MatrixXd xn = x;
  xn(2, 0) = std::nan("");
  CHECK_THROWS_WITH_AS(gp.fit(xn, y), doctest::Contains("x must be finite"), std::invalid_argument);
  Eigen::VectorXd yn = y;
  yn(1) = std::numeric_limits<double>::infinity();
  CHECK_THROWS_WITH_AS(gp.fit(x, yn), doctest::Contains("y must be finite"), std::invalid_argument);
  CHECK_THROWS_AS(gp.fit(x, y.head(4)), std::invalid_argument);
  CHECK_THROWS_AS(gp.fit(Eigen::MatrixXd(0, 1), Eigen::VectorXd(0)), std::invalid_argument);
  CHECK_THROWS_AS(gp.refit(), std::invalid_argument);
  gp.fit(x, y, {.optimize = false});
  CHECK_THROWS_AS(gp.add_observation(Eigen::VectorXd::Constant(1, std::nan("")), 1.0), std::invalid_argument);
  CHECK_THROWS_AS(gp.add_observation(Eigen::VectorXd::Constant(1, 0.0), std::nan("")), std::invalid_argument);
  CHECK_THROWS_AS(gp.add_observation(Eigen::VectorXd::Zero(2), 1.0), std::invalid_argument);
  CHECK_THROWS_AS((void)gp.predict(Eigen::MatrixXd::Constant(2, 1, std::nan(""))), std::invalid_argument);
  CHECK_THROWS_AS((void)gp.predict(Eigen::MatrixXd::Zero(2, 2)), std::invalid_argument);
  CHECK_THROWS_AS((void)gp.log_marginal_likelihood(Eigen::VectorXd::Zero(2)), std::invalid_argument);
  CHECK(gp.size() == 5);  // failed calls left the model unchanged
  ArdSquaredExponentialKernel ard(Eigen::VectorXd::Ones(2));
  GaussianProcess<ArdSquaredExponentialKernel> gp_ard(ard);
  CHECK_THROWS_AS(gp_ard.fit(x, y), std::invalid_argument);  // 1 column for a 2-D ARD kernel

  using Gp = GaussianProcess<SquaredExponentialKernel>;
  CHECK_THROWS_WITH_AS(Gp(SquaredExponentialKernel(), {.initial_jitter = 0.0}), doctest::Contains("initial_jitter"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(Gp(SquaredExponentialKernel(), {.max_jitter_attempts = -1}),
                       doctest::Contains("max_jitter_attempts"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(gp.fit(x, y, {.restarts = -1}), doctest::Contains("FitOptions::restarts"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(gp.fit(x, y, {.max_iterations = 0}), doctest::Contains("FitOptions::max_iterations"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS(gp.fit(x, y, {.gradient_tolerance = -1.0}), doctest::Contains("FitOptions::gradient_tolerance"),
                       std::invalid_argument);

  // Exactly repeated inputs, negligible noise and no jitter retries allowed: NumericalError.
  Eigen::MatrixXd xd(3, 1);
  xd << 1.0, 1.0, 1.0;
  SquaredExponentialKernel::Bounds bounds;
  bounds.noise_variance = {1e-30, 1.0};
  Gp strict(SquaredExponentialKernel(1.0, 1.0, 1e-30, bounds), {.max_jitter_attempts = 0});
  CHECK_THROWS_WITH_AS(strict.fit(xd, Eigen::Vector3d(1.0, 2.0, 3.0), {.optimize = false}),
                       doctest::Contains("not positive definite"), adaptseg::NumericalError);
  Gp lenient(SquaredExponentialKernel(1.0, 1.0, 1e-30, bounds));
  CHECK_NOTHROW(lenient.fit(xd, Eigen::Vector3d(1.0, 2.0, 3.0), {.optimize = false}));
}

// Persistence (the model's State as a YAML file): tests/test_gp_io.cpp.
