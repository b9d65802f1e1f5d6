#include "test_support.hpp"

#include <adaptseg/oracle_segmenter.hpp>
#include <adaptseg/semantic_map.hpp>
#include <adaptseg/simulated_sensor.hpp>

#include <doctest/doctest.h>

using namespace adaptseg;
namespace t = adaptseg::test;

namespace {
Image image_at(cv::Rect fp, double gsd, int w = 4, int h = 3) {
  Image img;
  img.footprint_px = fp;
  img.gsd_cm = gsd;
  img.width_px = w;
  img.height_px = h;
  return img;
}
}  // namespace

TEST_CASE("map: the finest GSD wins, whatever the order") {
  SemanticMap map(cv::Size(8, 6));
  const cv::Mat coarse(3, 4, CV_8UC1, cv::Scalar(1));
  const cv::Mat fine(3, 4, CV_8UC1, cv::Scalar(2));
  map.fuse(image_at({0, 0, 8, 6}, 2.0), coarse);  // one camera pixel = 2x2 map pixels
  CHECK(cv::countNonZero(map.labels() == 1) == 48);
  map.fuse(image_at({0, 0, 4, 3}, 1.0), fine);  // finer: overwrites its quarter
  CHECK(cv::countNonZero(map.labels() == 2) == 12);
  map.fuse(image_at({0, 0, 8, 6}, 2.0), coarse);  // coarser again: the fine part stays
  CHECK(cv::countNonZero(map.labels() == 2) == 12);
  CHECK(map.gsd_cm().at<float>(0, 0) == 1.0f);
  CHECK(map.gsd_cm().at<float>(5, 7) == 2.0f);
}

TEST_CASE("map: ignore pixels write nothing and parts outside the map are dropped") {
  SemanticMap map(cv::Size(4, 3), 255);
  cv::Mat labels(3, 4, CV_8UC1, cv::Scalar(1));
  labels.at<std::uint8_t>(0, 0) = 255;
  map.fuse(image_at({-2, -1, 4, 3}, 1.0), labels);  // shifted: only the lower-right 2x2 lands
  CHECK(cv::countNonZero(map.labels() == 1) == 4);
  CHECK(map.labels().at<std::uint8_t>(0, 0) == 1);   // camera (1, 2) lands at map (0, 0)
  CHECK(map.labels().at<std::uint8_t>(2, 3) == 255); // never observed
  CHECK(std::isinf(map.gsd_cm().at<float>(2, 3)));
  CHECK_THROWS_AS(map.fuse(image_at({0, 0, 4, 3}, 1.0), cv::Mat(2, 2, CV_8UC1)), std::invalid_argument);
}

TEST_CASE("map: a lawnmower at the orthomosaic's GSD reproduces the ground truth exactly") {
  const Field f = t::blob_field(1300, 900, 1.0, 3, 20);
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(f.num_classes());
  SemanticMap map(f.labels().size(), f.ignore_label());
  for (const auto& w : LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0)) {
    const Image img = sensor.capture(w);
    map.fuse(img, oracle.segment(img));
  }
  CHECK(cv::countNonZero(map.labels() != f.labels()) == 0);
}
