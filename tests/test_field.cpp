#include "test_support.hpp"

#include <adaptseg/vision/field.hpp>

#include <doctest/doctest.h>

#include <stdexcept>

using adaptseg::Field;
using adaptseg::FieldRegion;
namespace t = adaptseg::test;

namespace {
cv::Mat tiny_labels() {
  cv::Mat m(4, 6, CV_8UC1, cv::Scalar(0));
  m.at<std::uint8_t>(1, 1) = 1;
  m.at<std::uint8_t>(2, 3) = 2;
  m.at<std::uint8_t>(0, 0) = 255;
  return m;
}
}  // namespace

TEST_CASE("field: loads the documented format, block and flow YAML alike") {
  t::TempDir tmp;
  t::write_field(tmp.path() / "a", tiny_labels(), t::kWeedYaml);
  const Field f = Field::load(tmp.path() / "a");
  CHECK(f.name() == "tiny");
  CHECK(f.gsd_cm() == 1.0);
  CHECK(f.num_classes() == 3);
  CHECK(f.classes()[1].name == "crop");
  CHECK(f.classes()[2].color_rgb == std::array<std::uint8_t, 3>{255, 0, 0});
  CHECK(f.interest() == std::vector<int>{1, 2});
  CHECK(f.width_px() == 6);
  CHECK(f.height_px() == 4);
  CHECK(cv::countNonZero(f.valid_mask()) == 23);
  CHECK_FALSE(f.has_image());
  CHECK(f.area().x_max_m == doctest::Approx(0.06));

  // The same schema in flow style, quoted strings, other key order, comments.
  t::write_field(tmp.path() / "b", tiny_labels(),
                 "# a field\n{classes: [{color: [0,0,0], name: 'soil'}, {name: \"crop\", color: [0, 255, 0]},"
                 " {name: weed, color: [255,0,0]}], interest: [weed], labels: \"labels.png\", gsd_cm: 2,"
                 " name: flow}\n");
  const Field g = Field::load(tmp.path() / "b");
  CHECK(g.name() == "flow");
  CHECK(g.gsd_cm() == 2.0);
  CHECK(g.ignore_label() == 255);  // default
  CHECK(g.interest() == std::vector<int>{2});
}

TEST_CASE("field: loads an RGB image of the same size") {
  t::TempDir tmp;
  t::write_field(tmp.path(), tiny_labels(), std::string(t::kWeedYaml) + "image: image.png\n");
  cv::imwrite((tmp.path() / "image.png").string(), cv::Mat(4, 6, CV_8UC3, cv::Scalar(10, 20, 30)));
  const Field f = Field::load(tmp.path());
  REQUIRE(f.has_image());
  CHECK(f.image().at<cv::Vec3b>(0, 0) == cv::Vec3b(10, 20, 30));
}

TEST_CASE("field: bad field directories give clear errors") {
  t::TempDir tmp;
  const auto expect_error = [&](const std::string& yaml, const std::string& fragment,
                                const cv::Mat& labels = tiny_labels()) {
    const auto dir = tmp.path() / std::to_string(std::hash<std::string>{}(yaml + fragment));
    t::write_field(dir, labels, yaml);
    CAPTURE(yaml);
    CHECK_THROWS_WITH_AS(Field::load(dir), doctest::Contains(fragment.c_str()), std::invalid_argument);
  };
  const std::string ok = t::kWeedYaml;
  CHECK_THROWS_WITH_AS(Field::load(tmp.path() / "nope"), doctest::Contains("not found"), std::invalid_argument);
  std::filesystem::create_directories(tmp.path() / "empty");
  CHECK_THROWS_WITH_AS(Field::load(tmp.path() / "empty"), doctest::Contains("field.yaml"), std::invalid_argument);
  expect_error("name: [unclosed\n", "YAML error");
  expect_error("- just\n- a list\n", "mapping");
  expect_error(ok + "colour_map: x\n", "unknown key 'colour_map'");
  expect_error("gsd_cm: 1\nlabels: labels.png\nclasses: [{name: a, color: [0,0,0]}]\n", "missing key 'name'");
  expect_error("name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: [{name: a, colour: [0,0,0]}]\n",
               "unknown key 'classes[0].colour' (known: name, color)");
  expect_error("name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: [a, b]\n", "'classes[0]' must be a mapping");
  expect_error("name: x\ngsd_cm: -1\nlabels: labels.png\nclasses: [{name: a, color: [0,0,0]}]\n", "gsd_cm");
  expect_error("name: x\ngsd_cm: fast\nlabels: labels.png\nclasses: [{name: a, color: [0,0,0]}]\n",
               "'gsd_cm' must be a finite number (got 'fast')");
  expect_error("name: x\ngsd_cm: 1\nlabels: missing.png\nclasses: [{name: a, color: [0,0,0]}]\n", "file not found");
  expect_error("name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: []\n", "non-empty list");
  expect_error("name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: [{name: a, color: [0,0]}]\n", "3 integers");
  expect_error("name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: [{name: a, color: [0,0,300]}]\n",
               "'classes[0].color[2]' must be an integer in [0, 255] (got '300')");
  expect_error("name: x\ngsd_cm: 1\nlabels: labels.png\nclasses: [{name: a}]\n", "missing key 'classes[0].color'");
  expect_error(
      std::string(t::kWeedYaml).replace(std::string(t::kWeedYaml).find("ignore_label: 255"), 17, "ignore_label: 1"),
      "ignore_label must not be a class index");
  expect_error(std::string(t::kWeedYaml).replace(std::string(t::kWeedYaml).find("[crop, weed]"), 12, "[crop, tree]"),
               "unknown class 'tree'");
  expect_error(std::string(t::kWeedYaml).replace(std::string(t::kWeedYaml).find("name: weed"), 10, "name: crop"),
               "listed twice");
  cv::Mat bad = tiny_labels();
  bad.at<std::uint8_t>(3, 5) = 7;
  expect_error(ok, "label value 7 at row 3, col 5", bad);
  expect_error(ok, "single-channel", cv::Mat(4, 6, CV_8UC3, cv::Scalar(0, 0, 0)));
  expect_error(ok + "image: image.png\n", "file not found");
  {
    const auto dir = tmp.path() / "mismatch";
    t::write_field(dir, tiny_labels(), ok + "image: image.png\n");
    cv::imwrite((dir / "image.png").string(), cv::Mat(5, 6, CV_8UC3, cv::Scalar(0, 0, 0)));
    CHECK_THROWS_WITH_AS(Field::load(dir), doctest::Contains("differ in size"), std::invalid_argument);
    t::write_file(dir / "image.png", "not a png");
    CHECK_THROWS_WITH_AS(Field::load(dir), doctest::Contains("cannot decode"), std::invalid_argument);
  }
}

TEST_CASE("field: frame, pixel rectangles and validity") {
  const Field f("f", 2.0, tiny_labels(), t::soil_crop_weed(), {1});
  // Pixel (row 0, col 0) is the top-left: x in [0, 2) cm, y in [6, 8) cm.
  CHECK(f.pixel_rect({0.0, 0.06, 0.02, 0.08}) == cv::Rect(0, 0, 1, 1));
  CHECK(f.pixel_rect({0.0, 0.0, 0.12, 0.08}) == cv::Rect(0, 0, 6, 4));
  CHECK_FALSE(f.has_valid({0.0, 0.06, 0.02, 0.08}));  // the single ignore pixel
  CHECK(f.has_valid({0.0, 0.0, 0.02, 0.02}));
  CHECK_FALSE(f.has_valid({1.0, 1.0, 2.0, 2.0}));  // entirely outside
  CHECK(f.class_index("weed") == 2);
  CHECK_FALSE(f.class_index("tree").has_value());
  CHECK_THROWS_WITH_AS((void)f.class_indices({"crop", "tree"}), doctest::Contains("soil, crop, weed"),
                       std::invalid_argument);
}

TEST_CASE("field: sub-fields split along the image axes") {
  const Field f("f", 1.0, tiny_labels(), t::soil_crop_weed(), {1, 2});
  const Field left = f.sub_field({0.0, 0.0, 0.5, 1.0});
  CHECK(left.width_px() == 3);
  CHECK(left.height_px() == 4);
  CHECK(left.labels().at<std::uint8_t>(1, 1) == 1);
  const Field right = f.sub_field({0.5, 0.0, 1.0, 1.0});
  CHECK(right.labels().at<std::uint8_t>(2, 0) == 2);
  CHECK(right.name() == "f[0.5,0,1,1]");
  CHECK_THROWS_AS((void)f.sub_field({0.5, 0.0, 0.5, 1.0}), std::invalid_argument);
  CHECK_THROWS_AS((void)f.sub_field({-0.1, 0.0, 0.5, 1.0}), std::invalid_argument);
  CHECK_THROWS_AS((void)f.sub_field({0.0, 0.0, 0.01, 1.0}), std::invalid_argument);  // no pixel
}

TEST_CASE("field: direct construction validates its data") {
  CHECK_THROWS_WITH_AS(Field("x", 0.0, tiny_labels(), t::soil_crop_weed(), {}), doctest::Contains("gsd_cm"),
                       std::invalid_argument);
  CHECK_THROWS_AS(Field("x", 1.0, cv::Mat(), t::soil_crop_weed(), {}), std::invalid_argument);
  CHECK_THROWS_AS(Field("x", 1.0, tiny_labels(), {}, {}), std::invalid_argument);
  CHECK_THROWS_AS(Field("x", 1.0, tiny_labels(), t::soil_crop_weed(), {3}), std::invalid_argument);
  CHECK_THROWS_AS(Field("x", 1.0, tiny_labels(), t::soil_crop_weed(), {}, 2), std::invalid_argument);
}
