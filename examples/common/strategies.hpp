#pragma once
// Field specifications, regions and overlaps as the programs read them, and the programs' one
// instantiation of run_strategy() (the strategies themselves: <adaptseg/sim/strategy.hpp>).

#include "cli.hpp"

#include <adaptseg/sim/strategy.hpp>
#include <adaptseg/vision/any_backend.hpp>
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

}  // namespace adaptseg::examples

/// run_strategy() for the programs' one backend type, compiled once, in strategies.cpp (the
/// adaptseg_examples_common library): a program that includes this header does not instantiate
/// the planner and its policies again.
extern template adaptseg::StrategyRun adaptseg::run_strategy<adaptseg::AnyBackend>(
    const adaptseg::Field&, adaptseg::AnyBackend&, const std::string&, double, const adaptseg::DecisionModel*,
    adaptseg::MissionOptions, std::optional<double>, adaptseg::LawnmowerOverlap);
