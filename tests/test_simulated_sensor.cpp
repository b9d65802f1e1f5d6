#include "test_support.hpp"

#include <adaptseg/vision/simulated_sensor.hpp>

#include <doctest/doctest.h>

#include <limits>

using namespace adaptseg;
namespace t = adaptseg::test;

TEST_CASE("sensor: at the orthomosaic's GSD the image is the orthomosaic crop") {
  const Field f = t::blob_field(1000, 800, 1.0);
  const SimulatedSensor sensor(f, CameraModel{});
  const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0);
  const Image img = sensor.capture(plan.front());
  CHECK(img.footprint_px == cv::Rect(0, 800 - 360, 480, 360));  // bottom-left corner
  CHECK(img.width_px == 480);
  CHECK(img.height_px == 360);
  CHECK(cv::countNonZero(img.ground_truth != f.labels()(img.footprint_px)) == 0);
  CHECK(img.bgr.empty());  // the field has no RGB
}

TEST_CASE("sensor: a turned camera cuts its footprint out in its own orientation") {
  cv::Mat rgb(900, 1300, CV_8UC3);
  cv::randu(rgb, 0, 256);
  const Field blobs = t::blob_field(1300, 900, 1.0);
  const Field f("turned", 1.0, blobs.labels(), t::soil_crop_weed(), {1}, 255, rgb);
  const SimulatedSensor sensor(f, CameraModel{});
  // Footprint (400, 200, 480, 360) on the map grid: x 4.0..8.8 m, y 3.4..7.0 m (rows run down).
  const Waypoint w{{6.4, 5.2, 10.0}, 1.0, {4.0, 3.4, 8.8, 7.0}};
  const Image upright = sensor.capture(w);
  REQUIRE(upright.footprint_px == cv::Rect(400, 200, 480, 360));
  // A half turn: the same pixels, upside down (labels and, at the orthomosaic's GSD, colour).
  const Image half = sensor.capture(w, 180.0);
  CHECK(half.yaw_deg == 180.0);
  CHECK(half.footprint_px == upright.footprint_px);
  cv::Mat flipped;
  cv::flip(upright.ground_truth, flipped, -1);
  CHECK(cv::countNonZero(half.ground_truth != flipped) == 0);
  cv::flip(upright.bgr, flipped, -1);
  CHECK(cv::norm(half.bgr, flipped, cv::NORM_INF) == 0.0);
  // A quarter turn counter-clockwise: the image's x axis runs up the map, its rows to the
  // right; camera pixel (c, r) sees map pixel (column 460 + r, row 619 - c).
  const Image quarter = sensor.capture(w, 90.0);
  REQUIRE(quarter.ground_truth.size() == cv::Size(480, 360));
  int differ = 0;
  for (int r = 0; r < 360; ++r)
    for (int c = 0; c < 480; ++c) {
      differ += quarter.ground_truth.at<std::uint8_t>(r, c) != f.labels().at<std::uint8_t>(619 - c, 460 + r);
      differ += quarter.bgr.at<cv::Vec3b>(r, c) != f.image().at<cv::Vec3b>(619 - c, 460 + r);
    }
  CHECK(differ == 0);
  CHECK_THROWS_WITH_AS((void)sensor.capture(w, std::numeric_limits<double>::infinity()),
                       doctest::Contains("yaw_deg must be finite"), std::invalid_argument);
}

TEST_CASE("sensor: footprints of a lawnmower tile the orthomosaic exactly, at any GSD") {
  const Field f = t::blob_field(997, 611, 1.0);
  const SimulatedSensor sensor(f, CameraModel{});
  for (double gsd : {1.0, 1.3, 1.5, 2.0, 2.7, 3.0}) {
    CAPTURE(gsd);
    cv::Mat hits(f.labels().size(), CV_8UC1, cv::Scalar(0));
    for (const auto& w : LawnmowerPlanner(sensor.camera()).plan(f.area(), gsd)) {
      const Image img = sensor.capture(w);
      const cv::Rect in = img.footprint_px & cv::Rect(0, 0, f.width_px(), f.height_px());
      hits(in) += 1;
    }
    double lo = 0, hi = 0;
    cv::minMaxLoc(hits, &lo, &hi);
    CHECK(lo == 1);  // no gap
    CHECK(hi == 1);  // no overlap
  }
}

TEST_CASE("sensor: outside the orthomosaic is ignore (labels) and black (RGB)") {
  cv::Mat labels(100, 100, CV_8UC1, cv::Scalar(1));
  cv::Mat rgb(100, 100, CV_8UC3, cv::Scalar(200, 100, 50));
  const Field f("small", 1.0, labels, t::soil_crop_weed(), {1}, 255, rgb);
  const SimulatedSensor sensor(f, CameraModel{});
  const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0);
  REQUIRE(plan.size() == 1);
  const Image img = sensor.capture(plan.front());
  CHECK(cv::countNonZero(img.ground_truth == 1) == 100 * 100);
  CHECK(cv::countNonZero(img.ground_truth == 255) == 480 * 360 - 100 * 100);
  REQUIRE(img.bgr.size() == cv::Size(480, 360));
  CHECK(img.bgr.at<cv::Vec3b>(359, 0) == cv::Vec3b(200, 100, 50));  // bottom-left is the field
  CHECK(img.bgr.at<cv::Vec3b>(0, 479) == cv::Vec3b(0, 0, 0));
}

TEST_CASE("sensor: RGB is area-averaged when flying higher") {
  cv::Mat rgb(720, 960, CV_8UC3);
  for (int r = 0; r < rgb.rows; ++r)
    for (int c = 0; c < rgb.cols; ++c)
      rgb.at<cv::Vec3b>(r, c) = ((r + c) % 2) ? cv::Vec3b(255, 255, 255) : cv::Vec3b(0, 0, 0);
  const Field f("checker", 1.0, cv::Mat(720, 960, CV_8UC1, cv::Scalar(0)), t::soil_crop_weed(), {1}, 255, rgb);
  const SimulatedSensor sensor(f, CameraModel{});
  const Image img = sensor.capture(LawnmowerPlanner(sensor.camera()).plan(f.area(), 2.0).front());
  REQUIRE(img.bgr.size() == cv::Size(480, 360));
  double lo = 0, hi = 0;
  cv::minMaxLoc(img.bgr.reshape(1), &lo, &hi);
  CHECK(lo >= 126);  // every 2x2 block averages to mid grey
  CHECK(hi <= 129);
}

TEST_CASE("sensor: a GSD finer than the orthomosaic is refused") {
  const Field f = t::blob_field(200, 200, 2.0);
  const SimulatedSensor sensor(f, CameraModel{});
  const auto w = LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0).front();
  CHECK_THROWS_WITH_AS((void)sensor.capture(w), doctest::Contains("finer than the field"), std::invalid_argument);
}
