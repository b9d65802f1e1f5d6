// The Eigen-only core (<adaptseg/core.hpp>, CMake target adaptseg::adaptseg) without OpenCV,
// yaml-cpp, json or GeographicLib: a Gaussian process, and a decision function (gain model fitted
// on region samples, the paper's utility rule) deciding a descent.
#include <adaptseg/core.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdio>
#include <vector>

int main() {
  Eigen::MatrixXd x(20, 1);
  Eigen::VectorXd y(20);
  for (int i = 0; i < 20; ++i) {
    x(i, 0) = 0.3 * i;
    y(i) = std::sin(x(i, 0));
  }
  adaptseg::GaussianProcess<adaptseg::SquaredExponentialKernel> gp(adaptseg::SquaredExponentialKernel(1.0));
  gp.fit(x, y);
  Eigen::MatrixXd q(1, 1);
  q(0, 0) = 1.5;
  const double mean = gp.predict(q).mean(0);
  std::printf("core consumer: GP fitted on %d points, f(1.5) = %.3f (sin: %.3f)\n", 20, mean, std::sin(1.5));
  if (std::abs(mean - std::sin(1.5)) >= 0.05) return 1;

  // Region samples where a larger altitude drop removes more of sigma and gains more mIoU.
  std::vector<adaptseg::RegionSample> samples;
  for (double dh : {2.75, 5.5, 8.25, 11.0})
    for (double sigma : {0.02, 0.05, 0.1, 0.2, 0.3}) {
      adaptseg::RegionSample s;
      s.top_gsd_cm = 3.0;
      s.delta_h_m = dh;
      s.sigma_top = sigma;
      s.sigma_sub = sigma + 0.02 * dh * sigma;
      s.miou_top = 0.7;
      s.miou_sub = 0.7 + 0.025 * dh;
      samples.push_back(s);
    }
  adaptseg::DecisionFunction decision(adaptseg::UtilityPolicy(adaptseg::GainModel::fit(samples), {}));
  const std::vector<adaptseg::Candidate> candidates{{1.0, 5.5, 9, 40.0}, {2.0, 11.0, 4, 20.0}};
  decision.begin_mission();
  const adaptseg::Decision d = decision.decide(
      {.sigma = 0.2, .valid_fraction = 1.0, .top_gsd_cm = 3.0, .top_altitude_m = 16.5, .candidates = candidates});
  std::printf("core consumer: decision function %s (%.1f cm/px)\n", d.descend ? "descends" : "stays", d.gsd_cm);
  return d.descend && d.scores.size() == candidates.size() ? 0 : 1;
}
