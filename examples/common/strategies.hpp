#pragma once
// Running any strategy by name, and parsing field specifications, for the example programs.

#include "cli.hpp"

#include <adaptseg/core/linear_decision.hpp>
#include <adaptseg/vision/adaptive_mission.hpp>
#include <adaptseg/vision/decision_model.hpp>
#ifdef ADAPTSEG_HAVE_GDAL
#include <adaptseg/gdal/gdal_io.hpp>
#endif

#include <array>
#include <cmath>
#include <filesystem>
#include <locale>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace adaptseg::examples {

class AnyBackend;  // segmenters.hpp

/// What a strategy flies.
enum class StrategyPolicy {
  lawnmower,          ///< one fixed GSD (`--gsd`), no decision
  decision_function,  ///< the calibrated decision function of the model (paper §3.2)
  linear,             ///< the conference version's linear rule, from the model's σ range
};

/// One row of the table of strategies: everything a program or a figure needs to know about a
/// strategy. To add one, add its row here; adaptseg_mission, adaptseg_evaluate, adaptseg_live
/// and examples/tools/plot_evaluation.py (through the `strategies.csv` adaptseg_evaluate writes)
/// read it.
struct StrategyInfo {
  std::string_view name;  ///< on the command line and in results.csv
  StrategyPolicy policy;
  DescentSchedule schedule;  ///< when the chosen descents are flown (not lawnmower)
  bool online;               ///< decision_function: learns in flight (DecisionFunction::set_online)
  std::string_view label;    ///< in the figures' legends
};

/// Every strategy, in the order adaptseg_evaluate flies them on a test field (the lawnmowers
/// first). adaptive / nonadaptive: the decision model with online updates on / off, descents
/// flown at once (the paper); tour: adaptive, but the whole top level first and the chosen
/// descents after it as one low-altitude tour where that is cheaper; row: the same per
/// lawnmower row, staying low between a row's inspections.
inline constexpr std::array<StrategyInfo, 6> kStrategyTable{{
    {"lawnmower", StrategyPolicy::lawnmower, DescentSchedule::immediate, false, "lawnmower (fixed altitude)"},
    {"nonadaptive", StrategyPolicy::decision_function, DescentSchedule::immediate, false, "non-adaptive"},
    {"adaptive", StrategyPolicy::decision_function, DescentSchedule::immediate, true, "adaptive"},
    {"tour", StrategyPolicy::decision_function, DescentSchedule::tour, true, "tour (at once or after the survey)"},
    {"row", StrategyPolicy::decision_function, DescentSchedule::row, true, "row (at once or after each row)"},
    {"linear", StrategyPolicy::linear, DescentSchedule::immediate, false, "linear (ECMR 2021)"},
}};

/// The names of the strategies of `kStrategyTable` (all of them, or only those that fly a
/// calibrated model: every one but the lawnmower), in its order.
inline std::vector<std::string> strategy_names(bool model_based_only = false) {
  std::vector<std::string> names;
  for (const auto& s : kStrategyTable)
    if (!model_based_only || s.policy != StrategyPolicy::lawnmower) names.emplace_back(s.name);
  return names;
}

/// The row of strategy `name`.
/// @throws std::invalid_argument naming every strategy for an unknown name.
inline const StrategyInfo& strategy_info(std::string_view name) {
  for (const auto& s : kStrategyTable)
    if (s.name == name) return s;
  std::string known;
  for (const auto& s : kStrategyTable) known += (known.empty() ? "" : ", ") + std::string(s.name);
  throw std::invalid_argument("unknown strategy '" + std::string(name) + "' (one of: " + known + ")");
}

/// The table as CSV (`name,policy,schedule,online,label`), which adaptseg_evaluate writes beside
/// results.csv for the figures.
inline std::string strategies_csv() {
  std::string out = "name,policy,schedule,online,label\n";
  for (const auto& s : kStrategyTable) {
    const char* policy = s.policy == StrategyPolicy::lawnmower           ? "lawnmower"
                         : s.policy == StrategyPolicy::decision_function ? "decision_function"
                                                                         : "linear";
    out += std::string(s.name) + ',' + policy + ',' + to_string(s.schedule) + ',' + (s.online ? "true" : "false") +
           ",\"" + std::string(s.label) + "\"\n";
  }
  return out;
}

/// "a,b,c,d" -> four numbers; `what` describes the expected text in the error.
/// @throws std::invalid_argument for anything else.
inline std::array<double, 4> parse_four_numbers(const std::string& text, const std::string& what) {
  std::istringstream is(text);
  std::array<double, 4> v{};
  char comma = 0;
  bool ok = static_cast<bool>(is >> v[0]);
  for (std::size_t k = 1; k < 4 && ok; ++k) ok = (is >> comma) && comma == ',' && (is >> v[k]);
  ok = ok && (is >> std::ws).eof();
  if (!ok) throw std::invalid_argument("'" + text + "' is not " + what);
  return v;
}

/// "O" or "ALONG,ACROSS" -> LawnmowerOverlap (fractions in [0, 0.9]; one value: both).
/// @throws std::invalid_argument for anything else.
inline LawnmowerOverlap parse_overlap(const std::string& text) {
  std::istringstream is(text);
  is.imbue(std::locale::classic());
  LawnmowerOverlap o;
  char comma = 0;
  bool ok = static_cast<bool>(is >> o.along);
  o.across = o.along;
  if (ok && (is >> std::ws).peek() == ',') ok = (is >> comma) && static_cast<bool>(is >> o.across);
  ok = ok && (is >> std::ws).eof();
  const auto in_range = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 0.9; };
  if (!ok || !in_range(o.along) || !in_range(o.across))
    throw std::invalid_argument("--overlap '" + text + "' is not OVERLAP or ALONG,ACROSS with fractions in [0, 0.9]");
  return o;
}

/// "x0,y0,x1,y1" -> FieldRegion (fractions along the image axes).
/// @throws std::invalid_argument for anything else.
inline FieldRegion parse_region(const std::string& text) {
  const auto v = parse_four_numbers(text, "a region x0,y0,x1,y1 (fractions 0..1)");
  return {v[0], v[1], v[2], v[3]};
}

/// A field directory with an optional region: "DIR" or "DIR:x0,y0,x1,y1". `geo`, if set,
/// replaces the directory's geo-reference (before the region is cut out, so it refers to
/// the whole field's frame, like field.yaml's `geo:` section).
inline Field load_field_spec(const std::string& spec, const std::optional<FieldGeo>& geo = std::nullopt) {
  const auto load = [&](const std::string& dir) {
#ifdef ADAPTSEG_HAVE_GDAL
    const Field f = gdal::load_field(dir);  // GeoTIFF fields too; PNG fields as Field::load
#else
    const Field f = Field::load(dir);
#endif
    if (geo && f.crs())
      throw std::invalid_argument("field '" + f.name() +
                                  "' is georeferenced by its rasters; --geo-origin cannot replace that");
    return geo ? f.with_geo(geo) : f;
  };
  // "DIR:tail" where the tail looks like numbers is a region (a malformed one is an error that
  // says so), unless the whole spec is a directory.
  const auto colon = spec.rfind(':');
  if (colon != std::string::npos && colon + 1 < spec.size() && !std::filesystem::is_directory(spec)) {
    const std::string tail = spec.substr(colon + 1);
    const bool numeric = tail.find_first_not_of("0123456789.,+-eE ") == std::string::npos &&
                         tail.find_first_of("0123456789") != std::string::npos;
    if (numeric) {
      FieldRegion region{};
      try {
        region = parse_region(tail);
      } catch (const std::invalid_argument& e) {
        throw std::invalid_argument("field '" + spec + "': " + e.what() + "; write DIR:x0,y0,x1,y1");
      }
      Field part = load(spec.substr(0, colon)).sub_field(region);
      if (part.valid_pixels() == 0)
        throw std::invalid_argument("field '" + spec +
                                    "': the region has no valid pixel (all of it is the ignore label)");
      return part;
    }
  }
  return load(spec);
}

/// Writes `dir`/map.tif (class indices) and `dir`/map_gsd.tif (the GSD each pixel was mapped
/// at) in the field's CRS when the field is georeferenced (a GeoTIFF field or a geo: section)
/// and the program was built with GDAL; returns whether it did.
inline bool write_geo_maps(const Field& field, const cv::Mat& labels, const cv::Mat& gsd_cm,
                           const std::filesystem::path& dir) {
#ifdef ADAPTSEG_HAVE_GDAL
  if (!field.crs() && !field.geo()) return false;
  gdal::write_map_geotiff(dir / "map.tif", field, labels);
  gdal::write_gsd_geotiff(dir / "map_gsd.tif", field, gsd_cm);
  return true;
#else
  (void)field, (void)labels, (void)gsd_cm, (void)dir;
  return false;
#endif
}

/// Throws unless `model` was calibrated with the backend named `segmenter` (a network's name
/// holds its weights' identity: network_name()).
/// @throws std::invalid_argument naming both.
inline void check_segmenter(const DecisionModel& model, const std::string& segmenter) {
  if (model.segmenter != segmenter)
    throw std::invalid_argument("the decision model was calibrated with segmenter '" + model.segmenter +
                                "' but the mission uses '" + segmenter +
                                "': calibrate with the backend the mission flies (adaptseg_calibrate --segmenter, "
                                "--network)");
}

/// One flown strategy: the mission, and the decisions for the model-based ones.
struct StrategyRun {
  MissionResult mission;
  std::optional<std::vector<DecisionRecord>> decisions;
  std::vector<RealisedDescent> realised{};  ///< simulation: what each descent gained
};

/// Flies `strategy` over `field`. Lawnmower: at `gsd_cm`, with `overlap`. Others: from
/// `model`'s top GSD with its candidates, camera and timing (the mission options' camera and
/// timing are replaced by the model's), within `budget_s` if set. Compiled once, in
/// strategies.cpp (the adaptseg_examples_common library), for every program.
StrategyRun run_strategy(const Field& field, AnyBackend& backend, const std::string& strategy, double gsd_cm,
                         const DecisionModel* model, MissionOptions options, std::optional<double> budget_s,
                         LawnmowerOverlap overlap = {});

}  // namespace adaptseg::examples
