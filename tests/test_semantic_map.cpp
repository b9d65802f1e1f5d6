#include "test_support.hpp"

#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/semantic_map.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <doctest/doctest.h>

#include <limits>

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
  CHECK(map.labels().at<std::uint8_t>(0, 0) == 1);    // camera (1, 2) lands at map (0, 0)
  CHECK(map.labels().at<std::uint8_t>(2, 3) == 255);  // never observed
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

TEST_CASE("map: a camera turned a quarter turn writes its pixels where the turn puts them") {
  // A 4 x 2 camera at 1 map px per camera px, footprint (1, 2, 4, 2), turned 90 deg
  // counter-clockwise seen from above: its x axis runs up the map (field +y), its rows to the
  // right (field +x). Camera pixel (u, v) lands on map column 2 + v, row 4 - u.
  SemanticMap map(cv::Size(6, 6), 255);
  cv::Mat labels(2, 4, CV_8UC1);
  for (int v = 0; v < 2; ++v)
    for (int u = 0; u < 4; ++u) labels.at<std::uint8_t>(v, u) = static_cast<std::uint8_t>(10 * v + u);
  Image img = image_at({1, 2, 4, 2}, 1.0, 4, 2);
  img.yaw_deg = 90.0;
  map.fuse(img, labels);
  for (int v = 0; v < 2; ++v)
    for (int u = 0; u < 4; ++u) CHECK(map.labels().at<std::uint8_t>(4 - u, 2 + v) == labels.at<std::uint8_t>(v, u));
  CHECK(cv::countNonZero(map.labels() != 255) == 8);  // nothing else written
  CHECK(cv::countNonZero(map.gsd_cm() == 1.0f) == 8);
  // -270 deg is the same turn.
  SemanticMap same(cv::Size(6, 6), 255);
  img.yaw_deg = -270.0;
  same.fuse(img, labels);
  CHECK(cv::countNonZero(same.labels() != map.labels()) == 0);
}

TEST_CASE("map: a camera turned half a turn sees its image upside down, and the map is the same") {
  const cv::Rect fp(3, 1, 12, 9);  // 3 map px per camera px
  cv::Mat labels(3, 4, CV_8UC1);
  cv::randu(labels, 0, 4);
  SemanticMap upright(cv::Size(20, 12)), turned(cv::Size(20, 12));
  upright.fuse(image_at(fp, 3.0), labels);
  Image img = image_at(fp, 3.0);
  img.yaw_deg = 180.0;
  cv::Mat flipped;
  cv::flip(labels, flipped, -1);
  turned.fuse(img, flipped);
  CHECK(cv::countNonZero(turned.labels() != upright.labels()) == 0);
  CHECK(cv::countNonZero(turned.labels() != 255) == 12 * 9);
}

TEST_CASE("map: turned images of the sensor at the orthomosaic's GSD reproduce the ground truth") {
  const Field f = t::blob_field(1300, 900, 1.0, 3, 20);
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(f.num_classes());
  const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), 1.0);
  for (double yaw : {180.0, 33.0, -120.0}) {
    CAPTURE(yaw);
    SemanticMap map(f.labels().size(), f.ignore_label());
    for (const auto& w : plan) {
      const Image img = sensor.capture(w, yaw);
      map.fuse(img, oracle.segment(img));
    }
    const cv::Mat observed = map.labels() != f.ignore_label();
    const cv::Mat wrong = (map.labels() != f.labels()) & observed;
    if (yaw == 180.0) {  // a half turn is exact: the lawnmower tiles the field as at yaw 0
      CHECK(cv::countNonZero(map.labels() != f.labels()) == 0);
    } else {  // nearest neighbour twice (cut, then fuse): a pixel off at some blob edges
      CHECK(cv::countNonZero(observed) > 0.7 * cv::countNonZero(f.labels() != f.ignore_label()));
      CHECK(cv::countNonZero(wrong) < 0.02 * cv::countNonZero(observed));
    }
  }
}

TEST_CASE("map: a yaw that is not finite is refused") {
  SemanticMap map(cv::Size(8, 6));
  Image img = image_at({0, 0, 4, 3}, 1.0);
  img.yaw_deg = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH_AS(map.fuse(img, cv::Mat(3, 4, CV_8UC1, cv::Scalar(1))),
                       doctest::Contains("yaw_deg must be finite"), std::invalid_argument);
  CHECK(cv::countNonZero(map.labels() != 255) == 0);
}

TEST_CASE("semantic map: fuse writes what resampling the labels onto the footprint and masking writes") {
  // The reference: the camera labels resampled onto the footprint (INTER_NEAREST_EXACT), written
  // where not ignored and the image is at least as fine as the pixel's last write. Random sizes,
  // footprints partly outside the map, non-integer ratios, GSDs in random order.
  cv::RNG rng(5);
  for (int trial = 0; trial < 30; ++trial) {
    const cv::Size size(rng.uniform(20, 120), rng.uniform(20, 120));
    SemanticMap map(size, 255);
    cv::Mat ref_labels(size, CV_8UC1, cv::Scalar(255)), ref_gsd(size, CV_32F, cv::Scalar(1e30f));
    for (int k = 0; k < 6; ++k) {
      Image img;
      img.width_px = rng.uniform(5, 40);
      img.height_px = rng.uniform(5, 30);
      img.ignore_label = 255;
      img.gsd_cm = rng.uniform(1, 5);
      const double ratio = rng.uniform(0.5, 3.5);
      img.footprint_px =
          cv::Rect(rng.uniform(-20, size.width), rng.uniform(-20, size.height),
                   static_cast<int>(img.width_px * ratio) + 1, static_cast<int>(img.height_px * ratio) + 1);
      cv::Mat labels(img.height_px, img.width_px, CV_8UC1);
      rng.fill(labels, cv::RNG::UNIFORM, 0, 4);
      labels.setTo(255, labels == 3);  // some ignored
      map.fuse(img, labels);
      const cv::Rect fp = img.footprint_px, inside = fp & cv::Rect(0, 0, size.width, size.height);
      if (inside.area() == 0) continue;
      cv::Mat up;
      cv::resize(labels, up, fp.size(), 0, 0, cv::INTER_NEAREST_EXACT);
      const cv::Mat up_in = up(inside - fp.tl());
      const cv::Mat write = (ref_gsd(inside) >= static_cast<float>(img.gsd_cm)) & (up_in != 255);
      up_in.copyTo(ref_labels(inside), write);
      ref_gsd(inside).setTo(static_cast<float>(img.gsd_cm), write);
    }
    CHECK(cv::countNonZero(map.labels() != ref_labels) == 0);
    ref_gsd.setTo(std::numeric_limits<float>::infinity(), ref_gsd == 1e30f);
    CHECK(cv::countNonZero(map.gsd_cm() != ref_gsd) == 0);
  }
}

namespace {
/// A segmentation of a w x h image: every pixel `label`, with probability `p` on it and the rest
/// spread evenly over the other classes.
Segmentation uniform_segmentation(int w, int h, int classes, int label, float p) {
  Segmentation s{cv::Mat(h, w, CV_8UC1, cv::Scalar(label)), {}};
  for (int c = 0; c < classes; ++c)
    s.probabilities.emplace_back(h, w, CV_32F,
                                 cv::Scalar(c == label ? p : (1.0f - p) / static_cast<float>(classes - 1)));
  return s;
}
}  // namespace

TEST_CASE("map, pooled: a sure coarse look keeps what an unsure finer look contradicts, a sure finer look wins") {
  // 3 classes. The coarse image (GSD 3) is sure of class 0; a finer image (GSD 1) says class 1.
  // Pooled sums: class 0: log(0.9) / 3 + log(q0) / 1; class 1: log(0.05) / 3 + log(p) / 1.
  SemanticMap map(cv::Size(8, 6), 255, MapFusion::pooled), unsure(cv::Size(8, 6), 255, MapFusion::pooled);
  CHECK(map.fusion() == MapFusion::pooled);
  map.fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.9f));
  unsure.fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.9f));
  CHECK(cv::countNonZero(map.labels() == 0) == 48);
  CHECK(map.gsd_cm().at<float>(0, 0) == 3.0f);
  // Unsure (0.4 against 0.3, 0.3): 0's sum log(0.9)/3 + log(0.3) = -1.239 > 1's log(0.05)/3 + log(0.4) = -1.915.
  unsure.fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.4f));
  CHECK(cv::countNonZero(unsure.labels() == 0) == 48);
  CHECK(unsure.gsd_cm().at<float>(0, 0) == 1.0f);  // the finest look is still recorded
  // Sure (0.95): 1's sum log(0.05)/3 + log(0.95) = -1.050 > 0's log(0.9)/3 + log(0.025) = -3.724.
  map.fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.95f));
  CHECK(cv::countNonZero(map.labels() == 1) == 12);
  CHECK(cv::countNonZero(map.labels() == 0) == 36);
  // Finest-wins maps the unsure look's quarter as class 1 all the same.
  SemanticMap finest(cv::Size(8, 6));
  finest.fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.9f));
  finest.fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.4f));
  CHECK(cv::countNonZero(finest.labels() == 1) == 12);
}

TEST_CASE("map, pooled-interest: a label of interest any look gave stays, whichever look pooling prefers") {
  // As the pooled case above: a coarse look (GSD 3) sure of class 0, a finer one (GSD 1) unsure of
  // class 1 over the upper-left quarter; pooling keeps 0 there, keeping class 1 of interest gives 1.
  SemanticMap pooled(cv::Size(8, 6), 255, MapFusion::pooled);
  SemanticMap kept(cv::Size(8, 6), 255, MapFusion::pooled_interest, {1});
  SemanticMap other(cv::Size(8, 6), 255, MapFusion::pooled_interest, {2});  // no look says 2
  for (SemanticMap* m : {&pooled, &kept, &other}) {
    m->fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.9f));
    m->fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.4f));
  }
  CHECK(kept.fusion() == MapFusion::pooled_interest);
  CHECK(cv::countNonZero(pooled.labels() == 0) == 48);
  CHECK(cv::countNonZero(kept.labels() == 1) == 12);
  CHECK(cv::countNonZero(kept.labels() == 0) == 36);
  CHECK(cv::countNonZero(other.labels() != pooled.labels()) == 0);
  CHECK(cv::countNonZero(kept.gsd_cm() != pooled.gsd_cm()) == 0);

  // A sure closer look does not remove a label of interest a coarse look gave: coarse says 1
  // (0.9), the closer look 0 (0.95) over the quarter. Pooled: 0 there; kept: 1 everywhere.
  SemanticMap removed(cv::Size(8, 6), 255, MapFusion::pooled),
      stays(cv::Size(8, 6), 255, MapFusion::pooled_interest, {1});
  for (SemanticMap* m : {&removed, &stays}) {
    m->fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 1, 0.9f));
    m->fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 0, 0.95f));
  }
  CHECK(cv::countNonZero(removed.labels() == 0) == 12);
  CHECK(cv::countNonZero(stays.labels() == 1) == 48);

  // Two labels of interest, both seen in the quarter: the one of the larger pooled sum. Coarse 0
  // (0.9); then 1 (0.4; 0 and 2 at 0.3); then 2 (0.5; 0 and 1 at 0.25). Sums: 0: ln 0.9 / 3 +
  // ln 0.3 + ln 0.25 = -2.625; 1: ln 0.05 / 3 + ln 0.4 + ln 0.25 = -3.301; 2: ln 0.05 / 3 +
  // ln 0.3 + ln 0.5 = -2.896. Pooled: 0; of interest {1, 2}: 2; of interest {1} alone: 1.
  SemanticMap both(cv::Size(8, 6), 255, MapFusion::pooled_interest, {1, 2});
  SemanticMap one(cv::Size(8, 6), 255, MapFusion::pooled_interest, {1});
  for (SemanticMap* m : {&both, &one}) {
    m->fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.9f));
    m->fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.4f));
    m->fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 2, 0.5f));
  }
  CHECK(cv::countNonZero(both.labels() == 2) == 12);
  CHECK(cv::countNonZero(one.labels() == 1) == 12);
  CHECK(cv::countNonZero(both.labels() == 0) == 36);

  // It needs one to eight labels of interest, each a label.
  CHECK_THROWS_WITH_AS(SemanticMap(cv::Size(8, 6), 255, MapFusion::pooled_interest),
                       doctest::Contains("needs one to eight labels of interest"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(SemanticMap(cv::Size(8, 6), 255, MapFusion::pooled_interest, {0, 1, 2, 3, 4, 5, 6, 7, 8}),
                       doctest::Contains("needs one to eight labels of interest"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(SemanticMap(cv::Size(8, 6), 255, MapFusion::pooled_interest, {255}),
                       doctest::Contains("a label of interest must be in 0..254"), std::invalid_argument);
  CHECK(to_string(MapFusion::pooled_interest) == std::string("pooled-interest"));
  CHECK(parse_map_fusion("pooled-interest") == MapFusion::pooled_interest);
  CHECK(pools_probabilities(MapFusion::pooled_interest));
  CHECK_FALSE(pools_probabilities(MapFusion::finest));
}

TEST_CASE("map, pooled-guarded: a closer look changes only what the coarsest look was unsure of") {
  // 3 classes. Coarse looks (GSD 3) over the whole map, a finer one (GSD 1, sure of class 1 at
  // 0.95) over the upper-left quarter. Pooled, the finer look wins there (the case above). The
  // coarse look's own probability of its class decides the guarded map: 0.9 > 0.75 keeps class 0,
  // 0.7 < 0.75 lets the finer look write class 1.
  for (const float coarse : {0.9f, 0.7f}) {
    CAPTURE(coarse);
    SemanticMap pooled(cv::Size(8, 6), 255, MapFusion::pooled), guarded(cv::Size(8, 6), 255, MapFusion::pooled_guarded);
    for (SemanticMap* m : {&pooled, &guarded}) {
      m->fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, coarse));
      m->fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.95f));
    }
    CHECK(guarded.fusion() == MapFusion::pooled_guarded);
    CHECK(cv::countNonZero(pooled.labels() == 1) == 12);
    CHECK(cv::countNonZero(guarded.labels() == 1) == (coarse > SemanticMap::kGuardConfidence ? 0 : 12));
    CHECK(cv::countNonZero(guarded.gsd_cm() != pooled.gsd_cm()) == 0);  // the finest look is recorded all the same
  }

  // Two coarse looks of one GSD pool: 0.7 twice over 3 classes (0.15 each for the others) gives
  // class 0 the probability 0.49 / (0.49 + 2 * 0.0225) = 0.916 > 0.75, which guards it; the order
  // of the looks does not matter, and a coarser look replaces what the finer ones pooled.
  SemanticMap twice(cv::Size(8, 6), 255, MapFusion::pooled_guarded),
      fine_first(cv::Size(8, 6), 255, MapFusion::pooled_guarded);
  twice.fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.7f));
  twice.fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.7f));
  twice.fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.95f));
  CHECK(cv::countNonZero(twice.labels() == 0) == 48);
  fine_first.fuse(image_at({0, 0, 4, 3}, 1.0), uniform_segmentation(4, 3, 3, 1, 0.95f));
  CHECK(cv::countNonZero(fine_first.labels() == 1) == 12);  // alone, the finer look is the coarsest
  fine_first.fuse(image_at({0, 0, 8, 6}, 3.0), uniform_segmentation(4, 3, 3, 0, 0.9f));
  CHECK(cv::countNonZero(fine_first.labels() == 0) == 48);

  // Where every look agrees, or only the coarse looks fell, the guarded map is the pooled one.
  const Field f = t::blob_field(1300, 900, 1.0, 3, 20);
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(f.num_classes());
  SemanticMap pooled(f.labels().size(), f.ignore_label(), MapFusion::pooled);
  SemanticMap guarded(f.labels().size(), f.ignore_label(), MapFusion::pooled_guarded);
  for (const auto& w : LawnmowerPlanner(sensor.camera()).plan(f.area(), 3.0)) {
    const Image img = sensor.capture(w);
    const Segmentation s = oracle.segment_with_probabilities(img);
    pooled.fuse(img, s);
    guarded.fuse(img, s);
  }
  CHECK(cv::countNonZero(guarded.labels() != pooled.labels()) == 0);
  CHECK(to_string(MapFusion::pooled_guarded) == std::string("pooled-guarded"));
  CHECK(parse_map_fusion("pooled-guarded") == MapFusion::pooled_guarded);
  CHECK(pools_probabilities(MapFusion::pooled_guarded));
}

TEST_CASE("map, pooled: one-hot looks give finest-wins, and the oracle's lawnmowers map the ground truth") {
  // A finer look's weight (1 / GSD) exceeds a coarser one's, so where every look is sure the
  // finest decides, as with MapFusion::finest.
  const Field f = t::blob_field(1300, 900, 1.0, 3, 20);
  const SimulatedSensor sensor(f, CameraModel{});
  OracleSegmenter oracle(f.num_classes());
  SemanticMap pooled(f.labels().size(), f.ignore_label(), MapFusion::pooled);
  SemanticMap finest(f.labels().size(), f.ignore_label());
  const LawnmowerPlanner planner(sensor.camera());
  for (double gsd : {3.0, 1.0})
    for (const auto& w : planner.plan(f.area(), gsd)) {
      const Image img = sensor.capture(w);
      const Segmentation s = oracle.segment_with_probabilities(img);
      pooled.fuse(img, s);
      finest.fuse(img, s.labels);
    }
  const cv::Mat truth = f.labels() != f.ignore_label();
  CHECK(cv::countNonZero((pooled.labels() != f.labels()) & truth) == 0);
  CHECK(cv::countNonZero(pooled.labels() != finest.labels()) == 0);
  CHECK(cv::countNonZero(pooled.gsd_cm() != finest.gsd_cm()) == 0);
}

TEST_CASE("map, pooled: labels alone, missing or mismatched probabilities are refused") {
  SemanticMap map(cv::Size(8, 6), 255, MapFusion::pooled);
  const Image img = image_at({0, 0, 4, 3}, 1.0);
  CHECK_THROWS_WITH_AS(map.fuse(img, cv::Mat(3, 4, CV_8UC1, cv::Scalar(1))),
                       doctest::Contains("a pooled map needs the class probabilities"), std::invalid_argument);
  CHECK_THROWS_WITH_AS(map.fuse(img, Segmentation{cv::Mat(3, 4, CV_8UC1, cv::Scalar(1)), {}}),
                       doctest::Contains("needs the class probabilities"), std::invalid_argument);
  Segmentation wrong_size = uniform_segmentation(4, 3, 3, 0, 0.9f);
  wrong_size.probabilities[1] = cv::Mat(2, 2, CV_32F, cv::Scalar(0.05f));
  CHECK_THROWS_WITH_AS(map.fuse(img, wrong_size), doctest::Contains("CV_32FC1 planes of the image's size"),
                       std::invalid_argument);
  map.fuse(img, uniform_segmentation(4, 3, 3, 0, 0.9f));
  CHECK_THROWS_WITH_AS(map.fuse(img, uniform_segmentation(4, 3, 4, 0, 0.9f)),
                       doctest::Contains("number of class planes changed"), std::invalid_argument);
  CHECK(to_string(MapFusion::pooled) == std::string("pooled"));
  CHECK(parse_map_fusion("finest") == MapFusion::finest);
  CHECK_THROWS_WITH_AS(
      static_cast<void>(parse_map_fusion("mean")),
      doctest::Contains("map fusion must be 'finest', 'pooled', 'pooled-interest' or 'pooled-guarded', not 'mean'"),
      std::invalid_argument);
}

TEST_CASE("map, pooled: a turned camera pools where fuse(labels) would write") {
  const cv::Rect fp(3, 1, 12, 9);
  Segmentation s = uniform_segmentation(4, 3, 3, 2, 0.8f);
  Image img = image_at(fp, 3.0);
  img.yaw_deg = 33.0;
  SemanticMap pooled(cv::Size(20, 14), 255, MapFusion::pooled), finest(cv::Size(20, 14));
  pooled.fuse(img, s);
  finest.fuse(img, s.labels);
  CHECK(cv::countNonZero(finest.labels() != 255) > 0);
  CHECK(cv::countNonZero(pooled.labels() != finest.labels()) == 0);
  CHECK(cv::countNonZero(pooled.gsd_cm() != finest.gsd_cm()) == 0);
}
