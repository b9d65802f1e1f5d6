#include "comma_locale.hpp"
#include "test_support.hpp"

#include <adaptseg/sim/cached_backend.hpp>
#include <adaptseg/sim/decision_table.hpp>
#include <adaptseg/sim/strategy.hpp>
#include <adaptseg/vision/any_backend.hpp>
#include <adaptseg/vision/oracle_segmenter.hpp>
#include <adaptseg/vision/simulated_sensor.hpp>

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

using namespace adaptseg;
namespace t = adaptseg::test;
using doctest::Contains;

namespace {
MissionOptions deterministic() { return t::deterministic_options(); }

/// An oracle under another name: what a model calibrated with the oracle must refuse.
struct RenamedOracle {
  OracleSegmenter oracle;
  [[nodiscard]] std::string name() const { return "erfnet:another"; }
  [[nodiscard]] cv::Mat segment(const Image& image) { return oracle.segment(image); }
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) {
    return oracle.segment_with_probabilities(image);
  }
};

/// The oracle, counting what it is asked: what CachedBackend must spare.
struct CountingOracle {
  OracleSegmenter oracle;
  int labels = 0, with_probabilities = 0;
  [[nodiscard]] std::string name() const { return oracle.name(); }
  [[nodiscard]] cv::Mat segment(const Image& image) {
    ++labels;
    return oracle.segment(image);
  }
  [[nodiscard]] Segmentation segment_with_probabilities(const Image& image) {
    ++with_probabilities;
    return oracle.segment_with_probabilities(image);
  }
};

bool same(const cv::Mat& a, const cv::Mat& b) {
  return a.size() == b.size() && a.type() == b.type() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}
}  // namespace

TEST_CASE("CachedBackend: each image segmented once, in memory and on disk, probabilities kept once asked twice") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  const SimulatedSensor sensor(f, CameraModel{});
  const auto plan = LawnmowerPlanner(sensor.camera()).plan(f.area(), 3.0 * f.gsd_cm());
  REQUIRE(plan.size() >= 2);
  const Image a = sensor.capture(plan[0]), b = sensor.capture(plan[1]);
  t::TempDir dir;
  CountingOracle inner{OracleSegmenter(f.num_classes())};
  CachedBackend<CountingOracle> cached(inner, dir.path() / "oracle");
  CHECK(cached.name() == inner.name());
  const cv::Mat la = cached.segment(a);
  CHECK(same(la, inner.oracle.segment(a)));
  CHECK(same(cached.segment(a), la));
  CHECK(inner.labels == 1);  // the second from memory
  (void)cached.segment(b);
  CHECK(inner.labels == 2);  // another footprint, another image
  // Probabilities: computed when asked, kept (memory and disk) from the second ask on.
  const Segmentation pa = cached.segment_with_probabilities(a);
  CHECK(same(pa.labels, la));
  REQUIRE(pa.probabilities.size() == static_cast<std::size_t>(f.num_classes()));
  (void)cached.segment_with_probabilities(a);
  const Segmentation third = cached.segment_with_probabilities(a);
  CHECK(inner.with_probabilities == 2);
  for (std::size_t c = 0; c < pa.probabilities.size(); ++c) CHECK(same(third.probabilities[c], pa.probabilities[c]));
  // A copy each time: changing what it returned changes nothing kept.
  cv::Mat changed = cached.segment(a);
  changed.setTo(0);
  CHECK(same(cached.segment(a), la));

  // Another run over the same folder: nothing segmented again, labels and probabilities as kept.
  CountingOracle second{OracleSegmenter(f.num_classes())};
  CachedBackend<CountingOracle> again(second, dir.path() / "oracle");
  CHECK(same(again.segment(a), la));
  CHECK(same(again.segment(b), inner.oracle.segment(b)));
  const Segmentation from_disk = again.segment_with_probabilities(a);
  CHECK(second.labels + second.with_probabilities == 0);
  for (std::size_t c = 0; c < pa.probabilities.size(); ++c)
    CHECK(same(from_disk.probabilities[c], pa.probabilities[c]));
  // A file cut short is not read: the image is segmented again.
  for (const auto& file : std::filesystem::directory_iterator(dir.path() / "oracle"))
    std::filesystem::resize_file(file.path(), 10);
  CountingOracle third_run{OracleSegmenter(f.num_classes())};
  CachedBackend<CountingOracle> cut(third_run, dir.path() / "oracle");
  CHECK(same(cut.segment(a), la));
  CHECK(third_run.labels == 1);
}

TEST_CASE("strategy table: one row per strategy, the lawnmower first, unknown names refused") {
  const std::vector<std::string> all = strategy_names();
  REQUIRE(all.size() == kStrategyTable.size());
  CHECK(all.front() == std::string(kLawnmowerStrategy));
  const std::vector<std::string> model_based = strategy_names(true);
  CHECK(model_based.size() == all.size() - 1);
  for (const std::string& name : model_based) CHECK(strategy_info(name).flies_model());
  CHECK_FALSE(strategy_info(kLawnmowerStrategy).flies_model());
  CHECK(strategy_info("adaptive").online);
  CHECK_FALSE(strategy_info("nonadaptive").online);
  CHECK(strategy_info("tour").schedule == DescentSchedule::tour);
  CHECK(strategy_info("linear").policy == StrategyPolicy::linear);
  CHECK_THROWS_WITH_AS((void)strategy_info("adaptiv"), Contains("strategy must be 'lawnmower', 'nonadaptive'"),
                       std::invalid_argument);
  // strategies.csv: the header and one line per row, policy and schedule by name.
  std::istringstream csv(strategies_csv());
  std::string line;
  std::vector<std::string> lines;
  while (std::getline(csv, line)) lines.push_back(line);
  REQUIRE(lines.size() == kStrategyTable.size() + 1);
  CHECK(lines[0] == "name,policy,schedule,online,label");
  CHECK(lines[1] == "lawnmower,lawnmower,immediate,false,\"lawnmower (fixed altitude)\"");
  CHECK(lines[4] == "tour,decision_function,tour,true,\"tour (at once or after the survey)\"");
}

TEST_CASE("run_strategy: the lawnmower flies as run_lawnmower_mission, and bad settings are refused") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  OracleSegmenter oracle(f.num_classes());
  AnyBackend any(oracle);
  const StrategyRun run = run_strategy(f, any, kLawnmowerStrategy, 3.0, nullptr, deterministic(), std::nullopt);
  const MissionResult direct = run_lawnmower_mission(f, 3.0, oracle, deterministic());
  CHECK_FALSE(run.decisions.has_value());
  CHECK(run.mission.waypoints.size() == direct.waypoints.size());
  CHECK(run.mission.total_s() == direct.total_s());
  CHECK(run.mission.miou_interest().value() == direct.miou_interest().value());
  CHECK(run.mission.segmenter == "oracle");
  const auto fly = [&](const std::string& strategy, double gsd, const DecisionModel* model, LawnmowerOverlap o = {}) {
    return run_strategy(f, any, strategy, gsd, model, deterministic(), std::nullopt, o);
  };
  CHECK_THROWS_WITH_AS((void)fly("lawnmower", 0.0, nullptr), Contains("needs --gsd"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)fly("lawnmower", NAN, nullptr), Contains("(got nan)"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)fly("lawnmower", 0.5, nullptr),
                       Contains(("is finer than field '" + f.name() + "'").c_str()), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)fly("adaptive", 3.0, nullptr), Contains("--strategy adaptive needs --decision-model"),
                       std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)fly("adaptive", 3.0, nullptr, LawnmowerOverlap{0.2, 0.2}),
                       Contains("--overlap applies to --strategy lawnmower only"), std::invalid_argument);
  CHECK_THROWS_WITH_AS((void)fly("bogus", 3.0, nullptr), Contains("strategy must be"), std::invalid_argument);
}

TEST_CASE("run_strategy: a decision model flies with its backend only, online or frozen as its row says") {
  const Field f = Field::load(t::example_field("weedmap-000"));
  const DecisionModel model =
      DecisionModel::load(std::string(ADAPTSEG_TEST_DATA_DIR) + "/decision_model/weedmap_utility.yaml");
  OracleSegmenter oracle(f.num_classes());
  AnyBackend any(oracle);
  const StrategyRun adaptive = run_strategy(f, any, "adaptive", 0.0, &model, deterministic(), std::nullopt);
  const StrategyRun frozen = run_strategy(f, any, "nonadaptive", 0.0, &model, deterministic(), std::nullopt);
  REQUIRE(adaptive.decisions.has_value());
  REQUIRE(frozen.decisions.has_value());
  CHECK_FALSE(adaptive.decisions->empty());
  CHECK(adaptive.mission.strategy == "adaptive");
  CHECK(frozen.mission.strategy == "nonadaptive");
  // The model's top level, not the GSD passed (that is the lawnmower's).
  CHECK(adaptive.mission.waypoints.front().waypoint.gsd_cm == doctest::Approx(model.top_gsd_cm));
  CHECK(adaptive.realised.size() ==
        static_cast<std::size_t>(std::count_if(adaptive.decisions->begin(), adaptive.decisions->end(),
                                               [](const DecisionRecord& d) { return d.decision.descend; })));
  RenamedOracle renamed{OracleSegmenter(f.num_classes())};
  AnyBackend other(renamed);
  CHECK_THROWS_WITH_AS((void)run_strategy(f, other, "adaptive", 0.0, &model, deterministic(), std::nullopt),
                       Contains("calibrated with segmenter 'oracle' but the mission uses 'erfnet:another'"),
                       std::invalid_argument);
}

TEST_CASE("decisions.csv: one column table for the header and every row, in any locale") {
  const std::string header = decisions_csv_header();
  CHECK(header.rfind("field,strategy,decision,image,sigma,action,gsd_cm,images,extra_time_s,", 0) == 0);
  CHECK(header.find(",realised_field_gain,flown,") != std::string::npos);
  CHECK(header.find(",realised_delta_fn,forecast_curve_rise,forecast_end_s,realised_field_gain_region\n") !=
        std::string::npos);
  const auto columns = [](const std::string& line) { return std::count(line.begin(), line.end(), ',') + 1; };
  CHECK(columns(header.substr(0, header.size() - 1)) == static_cast<long>(kDecisionColumns.size()));

  const Field f = Field::load(t::example_field("dubai-tile-1"));
  const DecisionModel model =
      DecisionModel::load(std::string(ADAPTSEG_TEST_DATA_DIR) + "/decision_model/dubai_road_front_aware.yaml");
  OracleSegmenter oracle(f.num_classes());
  AnyBackend any(oracle);
  const StrategyRun run = run_strategy(f, any, "adaptive", 0.0, &model, deterministic(), std::nullopt);
  REQUIRE(run.decisions.has_value());
  REQUIRE_FALSE(run.realised.empty());  // at least one descent, to see its realised columns
  const std::vector<DecisionRow> rows = decision_rows("a field, quoted", "adaptive", *run.decisions, run.realised);
  REQUIRE(rows.size() == run.decisions->size());
  std::ostringstream os;
  {
    const t::CommaLocale comma;  // a global locale with a decimal comma must not reach the file
    write_decisions_csv(os, "a field, quoted", "adaptive", *run.decisions, run.realised);
  }
  std::istringstream in(os.str());
  std::string line;
  std::size_t k = 0, descents = 0;
  while (std::getline(in, line)) {
    REQUIRE(k < rows.size());
    std::string start = "\"a field, quoted\",adaptive,";
    start += std::to_string(k);
    start += ',';
    CHECK(line.rfind(start, 0) == 0);
    CHECK(columns(line) == static_cast<long>(kDecisionColumns.size()) + 1);  // the quoted comma
    const DecisionRow& r = rows[k];
    CHECK(line.find(r.record->decision.descend ? ",descend," : ",continue,") != std::string::npos);
    if (r.record->decision.descend) {
      ++descents;
      REQUIRE(r.realised != nullptr);
      REQUIRE(r.candidate.has_value());
      CHECK(r.chosen()->gsd_cm == doctest::Approx(r.record->decision.gsd_cm));
      // Every column of a descent in simulation has a value but those the rule does not forecast.
      for (const DecisionColumn& c : kDecisionColumns)
        if (std::string(c.name).rfind("forecast_", 0) != 0 && std::string(c.name).rfind("observed_", 0) != 0)
          CHECK_MESSAGE(!c.value(r).empty(), c.name);
      CHECK(kDecisionColumns[19].value(r) == adaptseg::detail::format_fixed(r.realised->field_gain, 6));
      // The front-aware rule's curve: a rise over the descent's time, from the mission's forecast end.
      const CandidateScore& score = *r.score();
      CHECK(score.predicted_curve_rise >= 0.0);
      CHECK(score.predicted_end_s >= r.chosen()->extra_time_s);
      CHECK(score.predicted_field_gain > score.predicted_curve_rise);  // z >= 0: the descent beat the rise
    } else {
      CHECK(r.realised == nullptr);
      CHECK(kDecisionColumns[23].value(r).empty());  // realised_delta_tp
    }
    CHECK(line.find(".") != std::string::npos);  // numbers with a decimal point, not a comma
    ++k;
  }
  CHECK(k == rows.size());
  CHECK(descents == run.realised.size());
  CHECK(std::string(kDecisionColumns[19].name) == "realised_field_gain");
  CHECK(std::string(kDecisionColumns[23].name) == "realised_delta_tp");
  CHECK(adaptseg::detail::format_fixed(-0.5, 3) == "-0.500");
  CHECK(adaptseg::detail::format_fixed(1234567.0, 1) == "1234567.0");
}

TEST_CASE("realised descents: the field gain inside the region apart from where the images overhang it") {
  // 8 x 4 px, the class of interest (weed, 2) in columns 2-3 (inside the descent's region,
  // columns 0-3) and 5-6 (beyond it, where the descent's images overhang). The top level saw
  // none of it; the descent's finer images, over both halves, all of it.
  cv::Mat truth(4, 8, CV_8UC1, cv::Scalar(0));
  truth.colRange(2, 4).setTo(2);
  truth.colRange(5, 7).setTo(2);
  const Field f("overhang", 1.0, truth, t::soil_crop_weed(), {2});
  const auto image_at = [](cv::Rect fp, double gsd) {
    Image img;
    img.footprint_px = fp;
    img.gsd_cm = gsd;
    img.width_px = fp.width;
    img.height_px = fp.height;
    return img;
  };
  SemanticMap top_only(truth.size());
  top_only.fuse(image_at({0, 0, 8, 4}, 2.0), cv::Mat(4, 8, CV_8UC1, cv::Scalar(0)));
  SemanticMap map(truth.size());
  map.fuse(image_at({0, 0, 8, 4}, 2.0), cv::Mat(4, 8, CV_8UC1, cv::Scalar(0)));
  const cv::Rect region(0, 0, 4, 4);
  detail::PendingDescent d{0, region, map.labels()(region).clone(), cv::Rect(0, 0, 8, 4), 1.0};
  map.fuse(image_at({0, 0, 8, 4}, 1.0), truth);
  MissionResult mission;
  mission.interest = {2};
  mission.fused_labels = map.labels();
  mission.confusion = ConfusionMatrix(f.num_classes());
  mission.confusion.add(truth, map.labels(), f.ignore_label());
  const std::vector<RealisedDescent> r =
      detail::realised_descents(f, {d}, top_only, cv::Mat(4, 8, CV_32F, cv::Scalar(1.0f)), mission);
  REQUIRE(r.size() == 1);
  CHECK(r[0].field_gain == doctest::Approx(1.0));         // weed IoU 0 -> 1
  CHECK(r[0].field_gain_region == doctest::Approx(0.5));  // its 8 pixels inside alone: 0.5
  CHECK(r[0].delta_tp == 16);
  CHECK(r[0].region_delta_miou() == doctest::Approx(-1.0));
}
