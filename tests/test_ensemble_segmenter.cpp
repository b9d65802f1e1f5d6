// Tests of the ensemble backend (include/adaptseg/erfnet/ensemble_segmenter.hpp) with the bundled
// ensemble examples/models/ensemble-dubai (MobileNetV2 + ERFNet) and member lists made here:
// the mean is the weighted mean of what each member gives alone, disagreement and class splits
// follow the members' labels, the contract holds, the mean maps the held-out tile better than
// either member, and bad member lists are refused with one line naming the problem.

#include "backend_conformance.hpp"
#include "test_support.hpp"

#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/erfnet/ensemble_segmenter.hpp>
#include <adaptseg/vision/image_summary.hpp>
#include <adaptseg/vision/metrics.hpp>

#include <doctest/doctest.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <string>
#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;
namespace fs = std::filesystem;

static_assert(SegmentationBackend<EnsembleSegmenter>);
static_assert(SegmentsWithProbabilities<EnsembleSegmenter>);
static_assert(!std::is_copy_constructible_v<EnsembleSegmenter>);
static_assert(std::is_move_constructible_v<EnsembleSegmenter>);

namespace {

fs::path models() { return fs::path(ADAPTSEG_EXAMPLES_DIR) / "models"; }
fs::path mnv2() { return models() / "mobilenetv2-dubai"; }
fs::path erfnet() { return models() / "erfnet-dubai"; }

/// An image of held-out tile 6 at 2x its GSD, with a black (no-data) corner.
Image tile6_image() {
  const Field f = Field::load(t::example_field("dubai-tile-6"));
  const CameraModel camera;
  const auto plan = LawnmowerPlanner(camera).plan(f.area(), 2.0 * f.gsd_cm());
  REQUIRE(plan.size() > 4);
  Image img = SimulatedSensor(f, camera).capture(plan[4]);
  img.bgr(cv::Rect(0, 0, 40, 30)).setTo(cv::Scalar(0, 0, 0));
  return img;
}

const OnnxParams kParams{.camera_width_px = 480, .camera_height_px = 360, .resize_to_network = true, .num_threads = 2};

}  // namespace

TEST_CASE("ensemble: the mean, its labels, disagreement and class splits follow the members") {
  const Image img = tile6_image();
  EnsembleSegmenter ens({{mnv2(), 3.0}, {erfnet(), 1.0}}, kParams);
  REQUIRE(ens.size() == 2);
  CHECK(ens.name() == "ensemble");
  CHECK(ens.weight(0) == doctest::Approx(0.75));
  CHECK(ens.weight(1) == doctest::Approx(0.25));
  OnnxSegmenter a(mnv2(), kParams), b(erfnet(), kParams);
  const Segmentation sa = a.segment_with_probabilities(img), sb = b.segment_with_probabilities(img);
  const EnsembleSegmentation e = ens.segment_with_disagreement(img);
  const int nc = ens.num_classes();
  REQUIRE(e.mean.probabilities.size() == static_cast<std::size_t>(nc));
  REQUIRE(e.mean.member_votes.size() == static_cast<std::size_t>(nc));
  // The votes keep the probabilities' contract (what the planner and calibration check).
  check_probabilities(e.mean.member_votes, e.mean.labels, img, nc, "votes");
  CHECK(cv::countNonZero(e.mean.labels != ens.segment(img)) == 0);
  int bad_mean = 0, bad_label = 0, bad_dis = 0, bad_split = 0, bad_vote = 0, no_data = 0, disagreeing = 0;
  for (int r = 0; r < img.height_px; ++r)
    for (int x = 0; x < img.width_px; ++x) {
      const int la = sa.labels.at<std::uint8_t>(r, x), lb = sb.labels.at<std::uint8_t>(r, x);
      const int le = e.mean.labels.at<std::uint8_t>(r, x);
      const float dis = e.disagreement.at<float>(r, x);
      if (r < 30 && x < 40) {  // no RGB content: ignore label, zero probabilities and disagreement
        no_data += (le == img.ignore_label && dis == 0.0f) ? 1 : 0;
        for (int c = 0; c < nc; ++c) {
          bad_mean += e.mean.probabilities[static_cast<std::size_t>(c)].at<float>(r, x) != 0.0f;
          bad_vote += e.mean.member_votes[static_cast<std::size_t>(c)].at<float>(r, x) != 0.0f;
        }
        continue;
      }
      int best = 0;
      for (int c = 0; c < nc; ++c) {
        const auto k = static_cast<std::size_t>(c);
        const float want = 0.75f * sa.probabilities[k].at<float>(r, x) + 0.25f * sb.probabilities[k].at<float>(r, x);
        bad_mean += std::abs(e.mean.probabilities[k].at<float>(r, x) - want) > 1e-6f ? 1 : 0;
        if (e.mean.probabilities[k].at<float>(r, x) >
            e.mean.probabilities[static_cast<std::size_t>(best)].at<float>(r, x))
          best = c;
        const bool split = (la == c) != (lb == c);
        bad_split += (e.class_split[k].at<std::uint8_t>(r, x) == 255) != split ? 1 : 0;
        const float want_vote = (la == c ? 0.75f : 0.0f) + (lb == c ? 0.25f : 0.0f);
        bad_vote += std::abs(e.mean.member_votes[k].at<float>(r, x) - want_vote) > 1e-6f ? 1 : 0;
      }
      bad_label += best != le ? 1 : 0;
      const float want_dis = (la != le ? 0.75f : 0.0f) + (lb != le ? 0.25f : 0.0f);
      bad_dis += std::abs(dis - want_dis) > 1e-6f ? 1 : 0;
      disagreeing += la != lb ? 1 : 0;
    }
  CHECK(no_data == 30 * 40);
  CHECK(bad_mean == 0);
  CHECK(bad_label == 0);
  CHECK(bad_dis == 0);
  CHECK(bad_split == 0);
  CHECK(bad_vote == 0);
  // Two networks trained apart do disagree on real ground, and not everywhere.
  CAPTURE(disagreeing);
  CHECK(disagreeing > 500);
  CHECK(disagreeing < img.width_px * img.height_px / 2);
  // Decision input `split` (image_summary.hpp) from the ensemble's segmentation: for L = {water},
  // 1 exactly where the members split on water; a single network's segmentation leaves it unknown.
  const int water = 4;
  const std::vector<int> l{water};
  const std::vector<cv::Mat> planes = pixel_inputs(e.mean, l, img.ignore_label);
  const cv::Mat& split_plane = planes[index_of(DecisionInput::split)];
  int bad_split_input = 0;
  for (int r = 30; r < img.height_px; ++r)
    for (int x = 0; x < img.width_px; ++x)
      bad_split_input +=
          split_plane.at<float>(r, x) !=
          ((sa.labels.at<std::uint8_t>(r, x) == water) != (sb.labels.at<std::uint8_t>(r, x) == water) ? 1.0f : 0.0f);
  CHECK(bad_split_input == 0);
  CHECK(cv::countNonZero(pixel_inputs(sa, l, img.ignore_label)[index_of(DecisionInput::split)] ==
                         pixel_inputs(sa, l, img.ignore_label)[index_of(DecisionInput::split)]) == 0);  // all NaN
  // A one-member ensemble is that network: same labels and probabilities, no disagreement.
  EnsembleSegmenter one(std::vector<EnsembleMember>{{mnv2(), 2.0}}, kParams);
  const EnsembleSegmentation o = one.segment_with_disagreement(img);
  CHECK(cv::countNonZero(o.mean.labels != sa.labels) == 0);
  for (int c = 0; c < nc; ++c)
    CHECK(cv::norm(o.mean.probabilities[static_cast<std::size_t>(c)], sa.probabilities[static_cast<std::size_t>(c)],
                   cv::NORM_INF) < 1e-6);
  CHECK(cv::countNonZero(o.disagreement) == 0);
}

TEST_CASE("test-time mirror: a network's probabilities are the mean over the image and its mirror") {
  // OnnxParams::test_time_mirror, on MobileNetV2: the mean of the plain probabilities of the
  // image and of its left-right mirror (flipped back), labels its argmax, no-data kept; and an
  // ensemble member with `mirror` contributes exactly that.
  const Image img = tile6_image();
  Image mirrored = img;
  mirrored.bgr = cv::Mat();
  cv::flip(img.bgr, mirrored.bgr, 1);
  OnnxSegmenter plain(mnv2(), kParams);
  OnnxParams pm = kParams;
  pm.test_time_mirror = true;
  OnnxSegmenter both(mnv2(), pm);
  const Segmentation s = plain.segment_with_probabilities(img), f = plain.segment_with_probabilities(mirrored);
  const Segmentation m = both.segment_with_probabilities(img);
  CHECK(cv::countNonZero(m.labels != both.segment(img)) == 0);
  check_probabilities(m.probabilities, m.labels, img, plain.num_classes(), "mirror");
  const int nc = plain.num_classes();
  int bad_mean = 0, bad_label = 0, changed = 0;
  for (int r = 0; r < img.height_px; ++r)
    for (int x = 0; x < img.width_px; ++x) {
      const bool no_data = r < 30 && x < 40;
      int best = 0;
      for (int c = 0; c < nc; ++c) {
        const auto k = static_cast<std::size_t>(c);
        const float want =
            no_data
                ? 0.0f
                : 0.5f * (s.probabilities[k].at<float>(r, x) + f.probabilities[k].at<float>(r, img.width_px - 1 - x));
        bad_mean += std::abs(m.probabilities[k].at<float>(r, x) - want) > 1e-6f ? 1 : 0;
        if (m.probabilities[k].at<float>(r, x) > m.probabilities[static_cast<std::size_t>(best)].at<float>(r, x))
          best = c;
      }
      const int got = m.labels.at<std::uint8_t>(r, x);
      bad_label += got != (no_data ? img.ignore_label : best) ? 1 : 0;
      changed += got != s.labels.at<std::uint8_t>(r, x) ? 1 : 0;
    }
  CHECK(bad_mean == 0);
  CHECK(bad_label == 0);
  // The network does not answer the mirror exactly as the image: some labels change, few.
  CAPTURE(changed);
  CHECK(changed > 50);
  CHECK(changed < img.width_px * img.height_px / 10);
  // An ensemble member with `mirror: true` (the file's key) is that segmenter.
  t::TempDir tmp;
  t::write_file(tmp.path() / "ensemble.yaml", "members:\n  - model: " + mnv2().string() +
                                                  "\n    mirror: true\n  - model: " + erfnet().string() +
                                                  "\n    mirror: false\n");
  const auto list = read_ensemble_file(tmp.path());
  REQUIRE(list.size() == 2);
  CHECK(list[0].mirror);
  CHECK_FALSE(list[1].mirror);
  // The bundled variant examples/models/ensemble-dubai-mirror is that ensemble.
  const auto bundled = read_ensemble_file(models() / "ensemble-dubai-mirror");
  REQUIRE(bundled.size() == 2);
  CHECK((bundled[0].mirror && fs::equivalent(bundled[0].model_dir, mnv2())));
  CHECK((!bundled[1].mirror && fs::equivalent(bundled[1].model_dir, erfnet())));
  EnsembleSegmenter ens(tmp.path(), kParams);
  OnnxSegmenter erf(erfnet(), kParams);
  const Segmentation e = ens.segment_with_probabilities(img), b = erf.segment_with_probabilities(img);
  double worst = 0.0;
  for (std::size_t k = 0; k < static_cast<std::size_t>(nc); ++k) {
    cv::Mat want;
    cv::addWeighted(m.probabilities[k], 0.5, b.probabilities[k], 0.5, 0.0, want);
    worst = std::max(worst, cv::norm(e.probabilities[k], want, cv::NORM_INF));
  }
  CHECK(worst < 1e-6);
}

TEST_CASE("test-time coarser look: which images get a second pass, and its probabilities keep the contract") {
  // OnnxParams::test_time_coarse_gsd_cm: a pass at min(G, 2 x the image's GSD) where that is at
  // least 10 % coarser; the image of tile 6 at 10 cm/px gets one at 15 with G = 15 and none
  // with G = 10, where the result is the plain segmenter's byte for byte.
  const Image img = tile6_image();
  REQUIRE(img.gsd_cm == doctest::Approx(10.0));
  OnnxSegmenter plain(mnv2(), kParams);
  OnnxParams p10 = kParams, p15 = kParams;
  p10.test_time_coarse_gsd_cm = 10.0;
  p15.test_time_coarse_gsd_cm = 15.0;
  OnnxSegmenter c10(mnv2(), p10), c15(mnv2(), p15);
  Image at = img;
  const auto coarse = [&](OnnxSegmenter& s, double gsd) {
    at.gsd_cm = gsd;
    return s.coarse_gsd_cm(at);
  };
  CHECK(coarse(plain, 5.0) == 0.0);
  CHECK(coarse(c10, 5.0) == 10.0);
  CHECK(coarse(c10, 7.5) == 10.0);
  CHECK(coarse(c10, 9.5) == 0.0);  // 10 is less than 10 % coarser
  CHECK(coarse(c10, 2.0) == 4.0);  // at most twice the image's GSD
  CHECK(coarse(c15, 10.0) == 15.0);
  const Segmentation s = plain.segment_with_probabilities(img), same = c10.segment_with_probabilities(img);
  CHECK(cv::countNonZero(same.labels != s.labels) == 0);
  for (std::size_t c = 0; c < s.probabilities.size(); ++c)
    CHECK(cv::norm(same.probabilities[c], s.probabilities[c], cv::NORM_INF) == 0.0);
  const Segmentation m = c15.segment_with_probabilities(img);
  CHECK(cv::countNonZero(m.labels != c15.segment(img)) == 0);
  check_probabilities(m.probabilities, m.labels, img, plain.num_classes(), "coarse");  // no-data corner kept
  const int changed = cv::countNonZero(m.labels != s.labels);
  CAPTURE(changed);
  CHECK(changed > 50);
  CHECK(changed < img.width_px * img.height_px / 4);
  // ERFNet takes the smaller input too; an ensemble member's own `coarse_gsd_cm` is that segmenter.
  CHECK_NOTHROW(OnnxSegmenter(erfnet(), p15));
  t::TempDir tmp;
  t::write_file(tmp.path() / "ensemble.yaml", "members:\n  - model: " + mnv2().string() + "\n    coarse_gsd_cm: 15\n");
  REQUIRE(read_ensemble_file(tmp.path()).at(0).coarse_gsd_cm == 15.0);
  EnsembleSegmenter one(tmp.path(), kParams);
  const Segmentation e = one.segment_with_probabilities(img);
  for (std::size_t c = 0; c < m.probabilities.size(); ++c)
    CHECK(cv::norm(e.probabilities[c], m.probabilities[c], cv::NORM_INF) < 1e-6);
  // Refused: a negative GSD, and an image without one when the look is on.
  OnnxParams bad = kParams;
  bad.test_time_coarse_gsd_cm = -1.0;
  CHECK_THROWS_WITH_AS(OnnxSegmenter(mnv2(), bad), doctest::Contains("test_time_coarse_gsd_cm must be 0 (off)"),
                       std::invalid_argument);
  Image no_gsd = img;
  no_gsd.gsd_cm = 0.0;
  CHECK_THROWS_WITH_AS((void)c15.segment(no_gsd), doctest::Contains("needs the image's GSD"), std::invalid_argument);
  CHECK_NOTHROW((void)plain.segment(no_gsd));
}

TEST_CASE("test-time coarser look: tile 5 at 5 cm/px, by the network that never saw it, maps better") {
  // What the look is for (docs/journal/2026-12-coarse.md): held-out tile 5
  // at its own GSD by examples/models/mobilenetv2-dubai-loto/tile-5, every other image of the
  // lawnmower (eval_ensemble over all of them: field mIoU 0.506 plain, 0.533 with coarse 10).
  // A coarse pass that is lost, misplaced (planes not resampled to the image) or not averaged
  // falls to the plain number or below it.
  const Field f = Field::load(t::example_field("dubai-tile-5"));
  const CameraModel camera;
  const SimulatedSensor sensor(f, camera);
  const auto plan = LawnmowerPlanner(camera).plan(f.area(), f.gsd_cm());
  const OnnxParams p{.resize_to_network = true, .num_threads = 2};
  OnnxParams pc = p;
  pc.test_time_coarse_gsd_cm = 10.0;
  const fs::path net = models() / "mobilenetv2-dubai-loto" / "tile-5";
  OnnxSegmenter plain(net, f, camera, p), coarse(net, f, camera, pc);
  ConfusionMatrix cp(f.num_classes()), cc(f.num_classes());
  for (std::size_t k = 0; k < plan.size(); k += 2) {
    const Image img = sensor.capture(plan[k]);
    cp += image_confusion(img, plain.segment(img), f.num_classes());
    cc += image_confusion(img, coarse.segment(img), f.num_classes());
  }
  const double mp = cp.miou_all().value(), mc = cc.miou_all().value();
  CAPTURE(mp);
  CAPTURE(mc);
  CHECK(mc > mp + 0.01);
}

TEST_CASE("ensemble: the bundled ensemble passes the backend conformance suite on held-out tile 6") {
  const Field f = Field::load(t::example_field("dubai-tile-6"));
  const CameraModel camera;
  EnsembleSegmenter ens(models() / "ensemble-dubai", f, camera,
                        OnnxParams{.resize_to_network = true, .num_threads = 2});
  REQUIRE(ens.size() == 2);
  CHECK(ens.member(0).model_info().output_stride == 4);  // MobileNetV2 at 512 x 384
  CHECK(ens.member(1).model_info().output_stride == 1);  // ERFNet at 480 x 360
  t::check_backend_conformance(ens, SimulatedSensor(f, camera), f.num_classes());
}

TEST_CASE("ensemble: the bundled ensemble maps held-out tile 6 at 15 cm/px better than either member") {
  // The whole of tile 6 at 3x its GSD (eval_ensemble.py measures 0.601 for the ensemble, 0.571
  // and 0.562 for MobileNetV2 and ERFNet, docs/results.md "The ensemble"): what the ensemble is
  // for. A broken mean (one member only, weights swapped for labels) falls to a member's number.
  const Field f = Field::load(t::example_field("dubai-tile-6"));
  const CameraModel camera;
  const SimulatedSensor sensor(f, camera);
  const auto plan = LawnmowerPlanner(camera).plan(f.area(), 3.0 * f.gsd_cm());
  const OnnxParams p{.resize_to_network = true, .num_threads = 2};
  EnsembleSegmenter ens(models() / "ensemble-dubai", f, camera, p);
  OnnxSegmenter a(mnv2(), f, camera, p), b(erfnet(), f, camera, p);
  ConfusionMatrix ce(f.num_classes()), ca(f.num_classes()), cb(f.num_classes());
  for (const auto& w : plan) {
    const Image img = sensor.capture(w);
    ce += image_confusion(img, ens.segment(img), f.num_classes());
    ca += image_confusion(img, a.segment(img), f.num_classes());
    cb += image_confusion(img, b.segment(img), f.num_classes());
  }
  const double me = ce.miou_all().value(), ma = ca.miou_all().value(), mb = cb.miou_all().value();
  CAPTURE(me);
  CAPTURE(ma);
  CAPTURE(mb);
  CHECK(me > std::max(ma, mb) + 0.015);
}

TEST_CASE("ensemble: bad member lists are refused with one line naming the problem") {
  const auto refused = [](auto&& make, const char* what) {
    CAPTURE(what);
    CHECK_THROWS_WITH_AS(make(), doctest::Contains(what), std::invalid_argument);
  };
  refused([] { return EnsembleSegmenter(std::vector<EnsembleMember>{}); }, "no members");
  refused([] { return EnsembleSegmenter({{mnv2(), 0.0}, {erfnet(), 1.0}}); }, "member 1 (");
  refused([] { return EnsembleSegmenter({{mnv2(), 1.0}, {erfnet(), -1.0}}); }, "weight must be a finite number > 0");
  refused(
      [] {
        return EnsembleSegmenter(std::vector<EnsembleMember>{{mnv2(), std::numeric_limits<double>::quiet_NaN()}});
      },
      "weight must be");
  refused(
      [] {
        return EnsembleSegmenter({{mnv2(), 1.0}, {models() / ".." / "models" / "mobilenetv2-dubai", 1.0}});
      },
      "is listed twice (also member 1)");
  refused([] { return EnsembleSegmenter({{mnv2(), 1.0}, {models() / "none", 1.0}}); }, "member 2 (");
  refused([] { return EnsembleSegmenter({{mnv2(), 1.0}, {models() / "none", 1.0}}); }, "model directory not found");
  // Members of another class set than the field's, or than each other.
  refused(
      [] {
        return EnsembleSegmenter(std::vector<EnsembleMember>{{mnv2(), 1.0}},
                                 OnnxParams{.expected_classes = {"soil", "crop", "weed"}});
      },
      "differ from the 3 expected classes");
  t::TempDir tmp;
  const fs::path other = tmp.path() / "renamed";
  fs::create_directories(other);
  fs::copy_file(erfnet() / "model.onnx", other / "model.onnx");
  std::string yaml = t::read_file(erfnet() / "model.yaml");
  yaml.replace(yaml.find("[building,"), 10, "[house,");
  t::write_file(other / "model.yaml", yaml);
  refused(
      [&] {
        return EnsembleSegmenter({{mnv2(), 1.0}, {other, 1.0}}, kParams);
      },
      "members must share one class set");
  // Ensemble directories: the file, its keys, its members.
  const fs::path dir = tmp.path() / "ens";
  fs::create_directories(dir);
  refused([&] { return EnsembleSegmenter(tmp.path() / "nope"); }, "ensemble directory not found");
  refused([&] { return EnsembleSegmenter(dir); }, "ensemble.yaml: file not found");
  const auto with = [&](const std::string& text) {
    t::write_file(dir / "ensemble.yaml", text);
    return [&] { return EnsembleSegmenter(dir, kParams); };
  };
  refused(with("members: [\n"), "YAML error");
  refused(with("members: []\n"), "'members' must be a non-empty list");
  refused(with("models:\n  - model: x\n"), "unknown key 'models' (known: members, description)");
  refused(with("description: x\n"), "missing key 'members'");
  refused(with("members:\n  - path: x\n"),
          "unknown key 'members[0].path' (known: model, weight, mirror, coarse_gsd_cm)");
  refused(with("members:\n  - model: x\n    mirror: yes please\n"),
          "'members[0].mirror' must be true or false (got 'yes please')");
  refused(with("members:\n  - weight: 2\n"), "missing key 'members[0].model'");
  refused(with("members:\n  - x\n"), "'members[0]' must be a mapping");
  refused(with("members:\n  - model: x\n    wieght: 2\n"), "unknown key 'members[0].wieght'");
  refused(with("members:\n  - model: x\n    weight: heavy\n"),
          "'members[0].weight' must be a finite number (got 'heavy')");
  refused(with("members:\n  - model: " + mnv2().string() + "\n  - model: ../none\n"), "member 2 (");
  // Relative member paths are resolved against the ensemble directory.
  t::write_file(dir / "ensemble.yaml", "members:\n  - model: ../renamed\n    weight: 2\n");
  const EnsembleSegmenter single(dir, kParams);
  CHECK(single.size() == 1);
  CHECK(single.classes().at(0) == "house");
  CHECK(EnsembleSegmenter::is_ensemble_dir(dir));
  CHECK_FALSE(EnsembleSegmenter::is_ensemble_dir(mnv2()));
}
