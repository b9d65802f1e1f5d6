// The Eigen-only core fits a Gaussian process: no OpenCV, yaml-cpp, json or GeographicLib.
#include <adaptseg/gaussian_process.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdio>

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
  return std::abs(mean - std::sin(1.5)) < 0.05 ? 0 : 1;
}
