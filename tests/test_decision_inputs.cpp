#include <adaptseg/core/decision_inputs.hpp>
#include <adaptseg/vision/grid_inputs.hpp>
#include <adaptseg/vision/image_summary.hpp>

#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <limits>
#include <random>
#include <span>
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
  CHECK_THROWS_WITH_AS((void)parse_decision_input("error"),
                       doctest::Contains("decision input must be 'sigma', 'boundary', 'ambiguity'"),
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

TEST_CASE("GridInputs: every cell to the bit as cell_inputs of the planes on the grid, turned or not") {
  // Random segmentations with probabilities over footprints of non-integer size ratios, partly
  // outside the rect, some turned; random field masks; random cells (some outside the footprint).
  cv::RNG rng(7);
  const std::vector<int> interest{1, 3};
  int compared = 0;
  for (int trial = 0; trial < 40; ++trial) {
    Image img;
    img.width_px = 13 + rng.uniform(0, 20);
    img.height_px = 9 + rng.uniform(0, 15);
    img.ignore_label = 255;
    const double ratio = rng.uniform(0.6, 3.3);
    img.footprint_px = cv::Rect(rng.uniform(-10, 10), rng.uniform(-10, 10), static_cast<int>(img.width_px * ratio) + 1,
                                static_cast<int>(img.height_px * ratio) + 1);
    img.yaw_deg = trial % 3 == 0 ? rng.uniform(-180.0, 180.0) : (trial % 3 == 1 ? 90.0 * rng.uniform(0, 4) : 0.0);
    Segmentation s;
    s.labels = cv::Mat(img.height_px, img.width_px, CV_8UC1);
    rng.fill(s.labels, cv::RNG::UNIFORM, 0, 5);
    for (int k = 0; k < 6; ++k)
      s.labels.at<unsigned char>(rng.uniform(0, img.height_px), rng.uniform(0, img.width_px)) = 255;
    cv::Mat sum(s.labels.size(), CV_32F, cv::Scalar(0.0f));
    for (int c = 0; c < 5; ++c) {
      cv::Mat p(s.labels.size(), CV_32F);
      rng.fill(p, cv::RNG::UNIFORM, 0.0f, 1.0f);
      cv::pow(p, 3.0, p);  // small probabilities too
      s.probabilities.push_back(p);
      sum += p;
    }
    for (cv::Mat& p : s.probabilities) p /= sum;
    const cv::Rect rect(rng.uniform(-5, 15), rng.uniform(-5, 15), rng.uniform(10, 60), rng.uniform(10, 60));
    cv::Mat field(rect.size(), CV_8UC1);
    rng.fill(field, cv::RNG::UNIFORM, 0, 4);  // about a quarter not field
    if (trial % 2 == 1) field.setTo(255);     // all field: summed by camera pixel, weighted
    const auto grid = planes_on_grid(img, pixel_inputs(s, interest, 255), rect);
    for (const auto& row : kDecisionInputs) {
      const GridInputs fast(img, s, interest, 255, rect, std::array{row.input},
                            trial % 4 < 2 ? GridInputs::Cells::many : GridInputs::Cells::one);
      for (int c = 0; c < 6; ++c) {
        const cv::Rect cell(rng.uniform(-3, rect.width), rng.uniform(-3, rect.height), rng.uniform(1, 30),
                            rng.uniform(1, 30));
        const CellInputs want = cell_inputs(grid, field, cell);
        const CellInputs got = fast.cell(field, cell);
        CHECK(got.field_px == want.field_px);
        for (DecisionInput i : {DecisionInput::sigma, row.input}) {
          const double a = got.value(i), b = want.value(i);
          CHECK_MESSAGE(((std::isnan(a) && std::isnan(b)) || a == b), "input ", to_string(i), " trial ", trial);
        }
        if (row.input != DecisionInput::sigma && row.input != DecisionInput::boundary)
          CHECK(std::isnan(
              got.value(DecisionInput::entropy == row.input ? DecisionInput::ambiguity : DecisionInput::entropy)));
        compared += want.field_px > 0.0 ? 1 : 0;
      }
    }
  }
  CHECK(compared > 500);  // most cells saw something
}

namespace {
// The per-pixel formulas as adaptseg wrote them one pixel at a time until pixel_input_rows
// (adaptseg 0.2 before it): the reference the row kernel must equal to the bit.
std::array<float, kDecisionInputCount> reference_values(int label, std::span<const float> p,
                                                        const std::array<bool, 256>& in_interest,
                                                        std::span<const float> votes) {
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  std::array<float, kDecisionInputCount> v;
  v.fill(nan);
  const float in = label >= 0 && label < 256 && in_interest[static_cast<std::size_t>(label)] ? 1.0f : 0.0f;
  v[index_of(DecisionInput::sigma)] = in;
  v[index_of(DecisionInput::boundary)] = in;
  float vote_sum = 0.0f, split = 0.0f;
  for (std::size_t c = 0; c < votes.size() && c < 256; ++c) {
    vote_sum += votes[c];
    if (in_interest[c])
      split += (votes[c] > kVoteShareTolerance && votes[c] < 1.0f - kVoteShareTolerance) ? 1.0f : 0.0f;
  }
  if (vote_sum > 0.0f) v[index_of(DecisionInput::split)] = split;
  const std::size_t n = p.size();
  if (n == 0) return v;
  std::size_t first = 0, second = n > 1 ? 1 : 0;
  if (n > 1 && p[1] > p[0]) first = 1, second = 0;
  float sum = 0.0f, entropy = 0.0f;
  for (std::size_t c = 0; c < n; ++c) {
    sum += p[c];
    if (p[c] > 0.0f) entropy -= p[c] * std::log(p[c]);
    if (c < 2) continue;
    if (p[c] > p[first]) {
      second = first;
      first = c;
    } else if (p[c] > p[second]) {
      second = c;
    }
  }
  if (!(sum > 0.0f)) return v;
  float ambiguity = 0.0f, expected_error = 0.0f, second_choice = 0.0f;
  for (std::size_t c = 0; c < n && c < 256; ++c) {
    if (!in_interest[c]) continue;
    ambiguity += (p[c] > 0.2f && p[c] < 0.8f) ? 1.0f : 0.0f;
    expected_error += static_cast<std::size_t>(label) == c ? 1.0f - p[c] : p[c];
    second_choice += (c == second && c != first && p[c] > 0.2f) ? 1.0f : 0.0f;
  }
  v[index_of(DecisionInput::ambiguity)] = ambiguity;
  v[index_of(DecisionInput::expected_error)] = expected_error;
  v[index_of(DecisionInput::second_choice)] = second_choice;
  v[index_of(DecisionInput::low_confidence)] = p[first] < 0.6f ? 1.0f : 0.0f;
  v[index_of(DecisionInput::entropy)] = n > 1 ? entropy / std::log(static_cast<float>(n)) : 0.0f;
  return v;
}
}  // namespace

TEST_CASE("decision inputs: the row kernel equals the per-pixel formulas, every input alone or together") {
  // Random rows of 1..200 pixels over 1..6 classes (ties and zeros included), with and without
  // member votes, some pixels without probabilities; every input wanted, and each alone.
  std::mt19937 rng(17);
  std::uniform_real_distribution<float> u(0.0f, 1.0f);
  int compared = 0, differ = 0, touched = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const std::size_t classes = 1 + static_cast<std::size_t>(trial % 6), n = 1 + static_cast<std::size_t>(rng() % 200);
    const bool with_votes = trial % 3 == 0;
    std::vector<unsigned char> labels(n);
    std::vector<std::vector<float>> p(classes, std::vector<float>(n)),
        v(with_votes ? classes : 0, std::vector<float>(n));
    for (std::size_t x = 0; x < n; ++x) {
      labels[x] = static_cast<unsigned char>(rng() % classes);
      float total = 0.0f;
      for (std::size_t c = 0; c < classes; ++c)
        total += (p[c][x] = rng() % 5 == 0 ? 0.0f : (rng() % 7 == 0 ? 0.25f : u(rng)));
      const bool none = rng() % 10 == 0;  // a pixel without probabilities
      for (std::size_t c = 0; c < classes; ++c) p[c][x] = none || total == 0.0f ? 0.0f : p[c][x] / total;
      for (auto& vote : v) vote[x] = static_cast<float>(rng() % 3) / 2.0f;
    }
    std::array<bool, 256> in_l{};
    for (std::size_t c = 0; c < classes; ++c) in_l[c] = rng() % 2 == 0;
    std::vector<const float*> p_rows, v_rows;
    for (const auto& row : p) p_rows.push_back(row.data());
    for (const auto& row : v) v_rows.push_back(row.data());
    for (int alone = -1; alone < static_cast<int>(kDecisionInputCount); ++alone) {
      std::array<bool, kDecisionInputCount> wanted{};
      for (std::size_t k = 0; k < kDecisionInputCount; ++k) wanted[k] = alone < 0 || static_cast<int>(k) == alone;
      std::array<std::vector<float>, kDecisionInputCount> out;
      std::array<float*, kDecisionInputCount> out_rows{};
      for (std::size_t k = 0; k < kDecisionInputCount; ++k) {
        out[k].assign(n, -7.0f);
        out_rows[k] = out[k].data();
      }
      pixel_input_rows(n, labels.data(), p_rows, v_rows, in_l, wanted, out_rows);
      for (std::size_t x = 0; x < n; ++x) {
        std::vector<float> px(classes), vx(v.size());
        for (std::size_t c = 0; c < classes; ++c) px[c] = p[c][x];
        for (std::size_t c = 0; c < v.size(); ++c) vx[c] = v[c][x];
        const auto want = reference_values(labels[x], px, in_l, vx);
        for (std::size_t k = 0; k < kDecisionInputCount; ++k) {
          if (!wanted[k]) {
            touched += out[k][x] != -7.0f ? 1 : 0;
            continue;
          }
          const bool same = std::isnan(want[k]) ? std::isnan(out[k][x]) : out[k][x] == want[k];
          if (!same && ++differ <= 5)
            FAIL_CHECK("input " << to_string(kDecisionInputs[k].input) << " pixel " << x << " trial " << trial);
          ++compared;
        }
      }
    }
  }
  CHECK(compared > 100000);
  CHECK(differ == 0);
  CHECK(touched == 0);  // inputs not wanted are left as they were
}
