#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/vision/image_summary.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <vector>

using namespace adaptseg;

namespace {
std::array<bool, 256> lut(std::initializer_list<int> classes) {
  std::array<bool, 256> l{};
  for (int c : classes) l[static_cast<std::size_t>(c)] = true;
  return l;
}
double at(const std::array<float, kDecisionInputCount>& v, DecisionInput i) { return v[index_of(i)]; }
}  // namespace

TEST_CASE("decision inputs: each per-pixel quantity on hand-computed pixels") {
  const auto in1 = lut({1});
  {  // labelled 1 (in L) with p = (0.1, 0.7, 0.2): sure enough, 0.3 expected error about L
    const std::vector<float> p{0.1f, 0.7f, 0.2f};
    const auto v = pixel_input_values(1, p, in1);
    CHECK(at(v, DecisionInput::sigma) == 1.0);
    CHECK(at(v, DecisionInput::ambiguity) == 1.0);  // 0.2 < 0.7 < 0.8
    CHECK(at(v, DecisionInput::expected_error) == doctest::Approx(0.3));
    CHECK(at(v, DecisionInput::second_choice) == 0.0);  // the runner-up is class 2, not in L
    CHECK(at(v, DecisionInput::low_confidence) == 0.0);
    const double h = -(0.1 * std::log(0.1) + 0.7 * std::log(0.7) + 0.2 * std::log(0.2)) / std::log(3.0);
    CHECK(at(v, DecisionInput::entropy) == doctest::Approx(h).epsilon(1e-5));
  }
  {  // labelled 0 with p = (0.5, 0.4, 0.1): class 1 of L is the runner-up, 0.4 expected error
    const std::vector<float> p{0.5f, 0.4f, 0.1f};
    const auto v = pixel_input_values(0, p, in1);
    CHECK(at(v, DecisionInput::sigma) == 0.0);
    CHECK(at(v, DecisionInput::ambiguity) == 1.0);
    CHECK(at(v, DecisionInput::expected_error) == doctest::Approx(0.4));
    CHECK(at(v, DecisionInput::second_choice) == 1.0);
    CHECK(at(v, DecisionInput::low_confidence) == 1.0);
  }
  {  // two classes of L: their errors add up
    const std::vector<float> p{0.2f, 0.5f, 0.3f};
    const auto v = pixel_input_values(1, p, lut({1, 2}));
    CHECK(at(v, DecisionInput::expected_error) == doctest::Approx(0.5 + 0.3));
    CHECK(at(v, DecisionInput::ambiguity) == 2.0);
  }
  {  // a labels-only backend: only what the labels say
    const auto v = pixel_input_values(1, {}, in1);
    CHECK(at(v, DecisionInput::sigma) == 1.0);
    CHECK(std::isnan(at(v, DecisionInput::expected_error)));
    CHECK(std::isnan(at(v, DecisionInput::entropy)));
    CHECK(std::isnan(at(v, DecisionInput::split)));  // no ensemble, no votes
  }
  {  // an ensemble's votes: members split on class 1 (0.6 / 0.4 with class 0), agree on class 2
    const std::vector<float> p{0.45f, 0.5f, 0.05f};
    const std::vector<float> split_votes{0.4f, 0.6f, 0.0f};
    CHECK(at(pixel_input_values(1, p, in1, split_votes), DecisionInput::split) == 1.0);
    CHECK(at(pixel_input_values(1, p, lut({1, 2}), split_votes), DecisionInput::split) == 1.0);  // class 2: nobody
    CHECK(at(pixel_input_values(1, p, lut({0, 1}), split_votes), DecisionInput::split) == 2.0);
    // All members label 1 (three thirds, summed in float): no split, whatever the probabilities say.
    const float third = 1.0f / 3.0f;
    const std::vector<float> agree{0.0f, third + third + third, 0.0f};
    CHECK(at(pixel_input_values(1, p, in1, agree), DecisionInput::split) == 0.0);
    CHECK(at(pixel_input_values(1, p, in1, agree), DecisionInput::ambiguity) == 1.0);
    // A pixel without votes (no RGB content) has no value.
    const std::vector<float> none{0.0f, 0.0f, 0.0f};
    CHECK(std::isnan(at(pixel_input_values(1, p, in1, none), DecisionInput::split)));
  }
  CHECK(parse_decision_input("expected_error") == DecisionInput::expected_error);
  CHECK_THROWS_WITH_AS((void)parse_decision_input("error"), doctest::Contains("one of sigma, boundary, ambiguity"),
                       std::invalid_argument);
  for (const auto& row : kDecisionInputs) CHECK(parse_decision_input(row.name) == row.input);
}

TEST_CASE("image summary: per-pixel planes onto the map grid, and a cell's means over its field") {
  // A 4 x 2 camera image over an 8 x 4 map-pixel footprint at (2, 1): each camera pixel covers 2 x 2.
  Image img;
  img.width_px = 4;
  img.height_px = 2;
  img.footprint_px = cv::Rect(2, 1, 8, 4);
  img.ignore_label = 255;
  Segmentation s;
  s.labels = (cv::Mat_<unsigned char>(2, 4) << 1, 0, 0, 255, 1, 1, 0, 0);
  cv::Mat p1(2, 4, CV_32F, cv::Scalar(0.9f));
  p1.at<float>(0, 1) = 0.3f;  // labelled 0, but 0.3 for class 1
  s.probabilities = {1.0f - p1, p1};
  s.probabilities[0].at<float>(0, 3) = 0.0f;  // the ignore pixel: no probability
  s.probabilities[1].at<float>(0, 3) = 0.0f;
  const std::vector<int> interest{1};
  const auto planes = pixel_inputs(s, interest, 255);
  REQUIRE(planes.size() == kDecisionInputCount);
  CHECK(std::isnan(planes[index_of(DecisionInput::sigma)].at<float>(0, 3)));
  CHECK(planes[index_of(DecisionInput::expected_error)].at<float>(0, 1) == doctest::Approx(0.3));
  // On a 12 x 6 map grid: NaN outside the footprint, 2 x 2 blocks inside.
  const auto grid = planes_on_grid(img, planes, cv::Rect(0, 0, 12, 6));
  const cv::Mat& sigma = grid[index_of(DecisionInput::sigma)];
  CHECK(std::isnan(sigma.at<float>(0, 0)));
  CHECK(sigma.at<float>(1, 2) == 1.0f);
  CHECK(sigma.at<float>(2, 3) == 1.0f);
  CHECK(sigma.at<float>(1, 4) == 0.0f);
  CHECK(std::isnan(sigma.at<float>(1, 8)));  // the ignore pixel
  // A cell over the footprint's left half; field everywhere but the top-left map pixel.
  cv::Mat field(6, 12, CV_8UC1, cv::Scalar(255));
  field.at<unsigned char>(1, 2) = 0;
  const CellInputs c = cell_inputs(grid, field, cv::Rect(2, 1, 4, 4));
  CHECK(c.field_px == 15.0);
  // σ over the 15 pixels: 3 of the first block (one is not field), 4 of the block below, 4 of
  // its neighbour: 11 in L.
  CHECK(c.value(DecisionInput::sigma) == doctest::Approx(11.0 / 15.0));
  CHECK(c.value(DecisionInput::boundary) == doctest::Approx(11.0 / 15.0 * 4.0 / 15.0));
  // Expected error: 0.1 on the 11 pixels of L, 0.3 on the 4 labelled 0 with p_1 = 0.3.
  CHECK(c.value(DecisionInput::expected_error) == doctest::Approx((11 * 0.1 + 4 * 0.3) / 15.0).epsilon(1e-6));
  CHECK(c.mass(DecisionInput::expected_error) == doctest::Approx(11 * 0.1 + 4 * 0.3).epsilon(1e-6));
  // A cell outside what the image saw: NaN values, no mass.
  const CellInputs none = cell_inputs(grid, field, cv::Rect(0, 0, 2, 2));
  CHECK(none.field_px == 0.0);
  CHECK(std::isnan(none.value(DecisionInput::sigma)));
  CHECK(none.mass(DecisionInput::sigma) == 0.0);
}
