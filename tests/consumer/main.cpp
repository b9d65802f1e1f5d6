// Uses the installed package: plan and fly a lawnmower over a synthetic field with the oracle.
#include <adaptseg/planner.hpp>

#include <cstdio>

int main() {
  cv::Mat labels(600, 800, CV_8UC1, cv::Scalar(0));
  cv::rectangle(labels, cv::Rect(100, 100, 50, 50), cv::Scalar(1), cv::FILLED);
  const adaptseg::Field field("consumer", 1.0, labels, {{"soil", {0, 0, 0}}, {"crop", {0, 255, 0}}}, {1});
  adaptseg::OracleSegmenter oracle(field.num_classes());
  const auto result = adaptseg::run_lawnmower_mission(field, 1.0, oracle, {});
  std::printf("adaptseg %s consumer: %zu images, mIoU %.3f\n", adaptseg::kVersion, result.waypoints.size(),
              result.miou_all().value_or(-1.0));
  return result.miou_all().value_or(0.0) == 1.0 ? 0 : 1;
}
