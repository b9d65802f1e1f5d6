// Times adaptseg::GaussianProcess on a data set written by benchmarks/bench_gaussian_process.py
// (which times scikit-learn on the same data and prints the comparison table).
//
// Usage: bench_gaussian_process <data-file>
// Data file (text): "n D m reps restarts normalize" / "bounds sf_lo sf_hi ls_lo ls_hi sn_lo sn_hi" /
// "init sf2 ls sn2" / n training rows "x_1..x_D y" / m query rows "x_1..x_D" / one row "x_1..x_D y"
// (the online observation). Prints one line of JSON: median times [s], LML and hyperparameters.
// D = 1 uses the isotropic kernel, D > 1 the ARD kernel (scikit-learn: RBF with a vector length scale).
#include <adaptseg/core/gaussian_process.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>
#include <string>
#include <vector>

namespace {

struct Data {
  Eigen::Index n = 0, d = 0, m = 0;
  int reps = 1, restarts = 0;
  bool normalize = true;
  double bounds[6] = {};
  double sf2 = 1, ls = 1, sn2 = 1;
  Eigen::MatrixXd x, xq;
  Eigen::VectorXd y, x_new;
  double y_new = 0;
};

Data read_data(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw std::invalid_argument("cannot open data file " + path);
  Data data;
  std::string tag;
  int normalize = 1;
  in >> data.n >> data.d >> data.m >> data.reps >> data.restarts >> normalize;
  data.normalize = normalize != 0;
  in >> tag;
  for (double& b : data.bounds) in >> b;
  in >> tag >> data.sf2 >> data.ls >> data.sn2;
  data.x.resize(data.n, data.d);
  data.y.resize(data.n);
  for (Eigen::Index i = 0; i < data.n; ++i) {
    for (Eigen::Index j = 0; j < data.d; ++j) in >> data.x(i, j);
    in >> data.y(i);
  }
  data.xq.resize(data.m, data.d);
  for (Eigen::Index i = 0; i < data.m; ++i)
    for (Eigen::Index j = 0; j < data.d; ++j) in >> data.xq(i, j);
  data.x_new.resize(data.d);
  for (Eigen::Index j = 0; j < data.d; ++j) in >> data.x_new(j);
  in >> data.y_new;
  if (!in) throw std::invalid_argument("truncated data file " + path);
  return data;
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  const std::size_t k = v.size() / 2;
  return v.size() % 2 == 1 ? v[k] : 0.5 * (v[k - 1] + v[k]);
}

template <typename F>
double seconds(F&& f) {
  const auto t0 = std::chrono::steady_clock::now();
  f();
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

template <typename K>
int run(const Data& data, K kernel) {
  using Gp = adaptseg::GaussianProcess<K>;
  typename Gp::Options options;
  options.normalize_y = data.normalize;
  const typename Gp::FitOptions fit_options{.restarts = data.restarts, .seed = 0};

  std::vector<double> fit_times, predict_times, update_times;
  Gp fitted(kernel, options);
  typename Gp::FitSummary summary;
  for (int r = 0; r < data.reps; ++r) {
    Gp gp(kernel, options);
    fit_times.push_back(seconds([&] { summary = gp.fit(data.x, data.y, fit_options); }));
    fitted = gp;
  }
  double checksum = 0.0;
  for (int r = 0; r < data.reps; ++r) {
    predict_times.push_back(seconds([&] {
      const auto p = fitted.predict(data.xq, adaptseg::PredictiveVariance::kNoisy);
      checksum += p.mean.sum() + p.variance.sum();
    }));
  }
  const int update_reps = std::max(data.reps, 5);
  for (int r = 0; r < update_reps; ++r) {
    Gp gp = fitted;  // copy outside the timed region
    update_times.push_back(seconds([&] { gp.add_observation(data.x_new, data.y_new); }));
    checksum += gp.log_marginal_likelihood();
  }
  std::printf(
      "{\"fit_s\": %.9g, \"predict_s\": %.9g, \"update_s\": %.9g, \"lml\": %.17g, \"status\": \"%s\", "
      "\"evaluations\": %d, \"jitter\": %.3g, \"checksum\": %.6g, \"theta\": [",
      median(fit_times), median(predict_times), median(update_times), summary.log_marginal_likelihood,
      std::string(adaptseg::to_string(summary.status)).c_str(), summary.evaluations, fitted.jitter(), checksum);
  for (Eigen::Index i = 0; i < summary.log_parameters.size(); ++i) {
    std::printf("%s%.9g", i == 0 ? "" : ", ", summary.log_parameters(i));
  }
  std::printf("]}\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: " << argv[0] << " <data-file written by bench_gaussian_process.py>\n";
    return 2;
  }
  try {
    const Data data = read_data(argv[1]);
    if (data.d == 1) {
      adaptseg::SquaredExponentialKernel::Bounds b;
      b.signal_variance = {data.bounds[0], data.bounds[1]};
      b.length_scale = {data.bounds[2], data.bounds[3]};
      b.noise_variance = {data.bounds[4], data.bounds[5]};
      return run(data, adaptseg::SquaredExponentialKernel(data.ls, data.sf2, data.sn2, b));
    }
    adaptseg::ArdSquaredExponentialKernel::Bounds b;
    b.signal_variance = {data.bounds[0], data.bounds[1]};
    b.length_scale = {data.bounds[2], data.bounds[3]};
    b.noise_variance = {data.bounds[4], data.bounds[5]};
    return run(
        data, adaptseg::ArdSquaredExponentialKernel(Eigen::VectorXd::Constant(data.d, data.ls), data.sf2, data.sn2, b));
  } catch (const std::exception& e) {
    std::cerr << "bench_gaussian_process: " << e.what() << "\n";
    return 1;
  }
}
