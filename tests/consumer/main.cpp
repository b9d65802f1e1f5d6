// Uses the installed package: plan and fly a lawnmower over a synthetic field with the oracle,
// and write and read back a Gaussian process as a YAML file (the vision component's formats).
#include <adaptseg/planner.hpp>
#include <adaptseg/vision/gp_io.hpp>

#include <cstdio>
#include <sstream>

int main() {
  cv::Mat labels(600, 800, CV_8UC1, cv::Scalar(0));
  cv::rectangle(labels, cv::Rect(100, 100, 50, 50), cv::Scalar(1), cv::FILLED);
  const adaptseg::Field field("consumer", 1.0, labels, {{"soil", {0, 0, 0}}, {"crop", {0, 255, 0}}}, {1});
  adaptseg::OracleSegmenter oracle(field.num_classes());
  const auto result = adaptseg::run_lawnmower_mission(field, 1.0, oracle, {});
  std::printf("adaptseg %s consumer: %zu images, mIoU %.3f\n", adaptseg::kVersion, result.waypoints.size(),
              result.miou_all().value_or(-1.0));

  using Gp = adaptseg::GaussianProcess<adaptseg::SquaredExponentialKernel>;
  Eigen::MatrixXd x(3, 1);
  x << 0.0, 0.5, 1.0;
  Gp gp(adaptseg::SquaredExponentialKernel(0.5, 1.0, 0.01));
  gp.condition(x, Eigen::Vector3d(0.1, 0.5, 0.1));
  std::stringstream file;
  adaptseg::save_gaussian_process(gp, file);
  const Gp back = adaptseg::load_gaussian_process<adaptseg::SquaredExponentialKernel>(file);
  const bool same = back.predict(x).mean == Gp::from_state(gp.state()).predict(x).mean;
  std::printf("GP file round trip: %s\n", same ? "same predictions" : "DIFFERENT predictions");
  return result.miou_all().value_or(0.0) == 1.0 && same ? 0 : 1;
}
