#pragma once
// Running any strategy by name, and parsing field specifications, for the example programs.

#include "cli.hpp"

#include <adaptseg/adaptive_mission.hpp>
#include <adaptseg/decision_model.hpp>
#include <adaptseg/linear_decision.hpp>
#ifdef ADAPTSEG_HAVE_GDAL
#include <adaptseg/gdal_io.hpp>
#endif

#include <array>
#include <cmath>
#include <filesystem>
#include <locale>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace adaptseg::examples {

/// lawnmower: one fixed GSD; adaptive / nonadaptive: the decision model with online updates on /
/// off, descents flown at once (the paper); tour: adaptive, but the whole top level first and the
/// chosen descents after it as one low-altitude tour where that is cheaper (DescentSchedule::tour);
/// row: the same per lawnmower row, staying low between a row's inspections
/// (DescentSchedule::row); linear: the conference version's rule.
inline const std::vector<std::string> kStrategies{"lawnmower", "adaptive", "nonadaptive", "tour", "row", "linear"};

/// When a model-based strategy flies its descents: tour and row defer where cheaper, the others
/// descend at once.
inline DescentSchedule schedule_of(const std::string& strategy) {
  if (strategy == "tour") return DescentSchedule::tour;
  if (strategy == "row") return DescentSchedule::row;
  return DescentSchedule::immediate;
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
      throw std::invalid_argument("field '" + f.name() + "' is georeferenced by its rasters; --geo-origin cannot replace that");
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
        throw std::invalid_argument("field '" + spec + "': the region has no valid pixel (all of it is the ignore label)");
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
                                "--model-file)");
}

/// One flown strategy: the mission, and the decisions for the model-based ones.
struct StrategyRun {
  MissionResult mission;
  std::optional<std::vector<DecisionRecord>> decisions;
  std::vector<RealisedDescent> realised{};  ///< simulation: what each descent gained
};

/// Flies `strategy` over `field`. Lawnmower: at `gsd_cm`, with `overlap`. Others: from
/// `model`'s top GSD with its candidates, camera and timing (the mission options' camera and
/// timing are replaced by the model's), within `budget_s` if set.
template <SegmentationBackend Backend>
StrategyRun run_strategy(const Field& field, Backend& backend, const std::string& strategy, double gsd_cm,
                         const DecisionModel* model, MissionOptions options, std::optional<double> budget_s,
                         LawnmowerOverlap overlap = {}) {
  if (strategy == "lawnmower") {
    if (gsd_cm == 0.0) throw std::invalid_argument("--strategy lawnmower needs --gsd (a positive GSD in cm/px)");
    if (!(gsd_cm > 0.0) || !std::isfinite(gsd_cm))
      throw std::invalid_argument("--gsd must be a finite positive GSD in cm/px (got " + fmt(gsd_cm, 3) + ")");
    if (gsd_cm < field.gsd_cm() * (1.0 - 1e-9))
      throw std::invalid_argument("--gsd " + std::to_string(gsd_cm) + " cm/px is finer than field '" +
                                  field.name() + "' (" + std::to_string(field.gsd_cm()) + " cm/px)");
    return {run_lawnmower_mission(field, gsd_cm, backend, options, overlap), std::nullopt};
  }
  if (overlap != LawnmowerOverlap{})
    throw std::invalid_argument("--overlap applies to --strategy lawnmower only (the decision function's regions "
                                "are the paper's non-overlapping top-level footprints)");
  if (model == nullptr) throw std::invalid_argument("--strategy " + strategy + " needs --model (from adaptseg_calibrate)");
  check_segmenter(*model, backend.name());
  // Without --interest, the model's labels of interest (its GPs were fitted for them).
  model->check_classes(field);
  if (options.interest.empty()) options.interest = field.class_indices(model->interest);
  model->check_compatible(field, options.interest);
  AdaptiveOptions ao = model->adaptive_options(std::move(options), budget_s);
  if (strategy == "linear") {
    LinearDecision policy(model->linear);
    auto r = run_adaptive_mission(field, backend, policy, ao, policy.name());
    return {std::move(r.mission), std::move(r.decisions), std::move(r.realised)};
  }
  if (strategy != "adaptive" && strategy != "nonadaptive" && strategy != "tour" && strategy != "row")
    throw std::invalid_argument("unknown strategy '" + strategy + "'");
  DecisionFunction df = model->decision_function;
  df.set_online(strategy != "nonadaptive");
  ao.schedule = schedule_of(strategy);
  auto r = run_adaptive_mission(field, backend, df, ao, strategy);
  return {std::move(r.mission), std::move(r.decisions), std::move(r.realised)};
}

}  // namespace adaptseg::examples
