#pragma once
/// @file
/// A field to survey: the orthomosaic's label map (and RGB image, when there is one), its
/// GSD and class set, loaded from the project's field directory format (docs/data_format.md),
/// and where it lies on the Earth (FieldGeo, FieldCrs: field_geo.hpp).

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/vision/detail/yaml_io.hpp>
#include <adaptseg/vision/field_geo.hpp>
#include <adaptseg/vision/image.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <iterator>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace adaptseg {

/// One semantic class: its name and display colour (RGB).
struct ClassInfo {
  std::string name;
  std::array<std::uint8_t, 3> color_rgb{0, 0, 0};
};

/// Fraction rectangle of a field along the image axes: `x` along columns (left to right),
/// `y` along rows (top to bottom), each in [0, 1]. `{0, 0, 0.5, 1}` is the left half.
struct FieldRegion {
  double x0 = 0.0, y0 = 0.0, x1 = 1.0, y1 = 1.0;
};

/// An orthomosaic with class labels (docs/method.md, "Decisions where the paper is silent, and
/// departures"). The field frame has its origin at the
/// orthomosaic's bottom-left corner, x along the columns, y up the rows, in metres; pixel
/// (row r, col c) covers x in [c, c+1) * g0/100 and y in [H-r-1, H-r) * g0/100.
///
/// A Field is immutable; copies are cheap (the cv::Mat buffers are shared).
class Field {
 public:
  /// @param name field name (reports, figures).
  /// @param gsd_cm ground sampling distance of `labels` (and `image`) [cm/px], > 0.
  /// @param labels 8-bit single-channel class indices; `ignore_label` marks pixels outside
  ///        the field or unlabelled.
  /// @param classes the classes, index order (names unique and non-empty).
  /// @param interest class indices of the labels of interest L.
  /// @param ignore_label label value of "no class" (0..255, not a class index).
  /// @param image optional 8-bit 3-channel BGR image of the same size (empty if none).
  /// @throws std::invalid_argument for an empty/mistyped label map, a GSD that is not
  ///         positive, no classes, duplicate or empty class names, an ignore label that is
  ///         also a class index, labels of interest out of range, an image of another size,
  ///         or a label value that is neither a class index nor the ignore label.
  Field(std::string name, double gsd_cm, cv::Mat labels, std::vector<ClassInfo> classes, std::vector<int> interest,
        int ignore_label = 255, cv::Mat image = {})
      : name_(std::move(name)),
        gsd_cm_(gsd_cm),
        labels_(std::move(labels)),
        image_(std::move(image)),
        classes_(std::move(classes)),
        interest_(std::move(interest)),
        ignore_label_(ignore_label) {
    validate();
    valid_ = labels_ != ignore_label_;
  }

  /// Loads a field directory: `field.yaml`, the label PNG it names and the optional image.
  /// `gsd_cm` is required here; a field whose rasters carry their georeference (GeoTIFFs)
  /// loads with gdal::load_field (<adaptseg/gdal/gdal_io.hpp>), which may take it from them.
  /// @throws std::invalid_argument naming the file and the problem (missing file, YAML
  ///         syntax error, missing or mistyped key, unknown key, unknown class of interest,
  ///         wrong image type, size mismatch, out-of-range label value, a `geo:` section
  ///         with a missing, unknown, mistyped or out-of-range key).
  static Field load(const std::filesystem::path& dir);

  [[nodiscard]] const std::string& name() const noexcept { return name_; }
  /// Orthomosaic GSD g0 [cm/px].
  [[nodiscard]] double gsd_cm() const noexcept { return gsd_cm_; }
  /// Class indices, CV_8UC1.
  [[nodiscard]] const cv::Mat& labels() const noexcept { return labels_; }
  /// BGR image, CV_8UC3, or empty when the field has none.
  [[nodiscard]] const cv::Mat& image() const noexcept { return image_; }
  [[nodiscard]] bool has_image() const noexcept { return !image_.empty(); }
  /// 255 where the label is a class, 0 where it is the ignore label; CV_8UC1.
  [[nodiscard]] const cv::Mat& valid_mask() const noexcept { return valid_; }
  [[nodiscard]] const std::vector<ClassInfo>& classes() const noexcept { return classes_; }
  [[nodiscard]] int num_classes() const noexcept { return static_cast<int>(classes_.size()); }
  /// Default labels of interest L (class indices, ascending).
  [[nodiscard]] const std::vector<int>& interest() const noexcept { return interest_; }
  [[nodiscard]] int ignore_label() const noexcept { return ignore_label_; }
  /// Where the field lies on the Earth, if known (`geo:` in field.yaml, or with_geo()).
  [[nodiscard]] const std::optional<FieldGeo>& geo() const noexcept { return geo_; }
  /// A copy of this field with `geo` as its geo-reference (nullopt: none).
  /// @throws std::invalid_argument for a latitude outside [-90, 90], a longitude outside
  ///         [-180, 180], or a non-finite altitude, heading or anchor.
  [[nodiscard]] Field with_geo(std::optional<FieldGeo> geo) const {
    if (geo) detail::validate_field_geo(*geo, "Field '" + name_ + "': geo");
    Field out = *this;
    out.geo_ = std::move(geo);
    return out;
  }
  /// The projected CRS the field frame is a shifted copy of, for a field georeferenced by its
  /// raster (<adaptseg/gdal/gdal_io.hpp>); nullopt otherwise.
  [[nodiscard]] const std::optional<FieldCrs>& crs() const noexcept { return crs_; }
  /// A copy of this field whose frame is the grid of `crs` (nullopt: none).
  /// @throws std::invalid_argument for an empty WKT or a non-finite origin.
  [[nodiscard]] Field with_crs(std::optional<FieldCrs> crs) const {
    if (crs) {
      detail::require(!crs->wkt.empty(), "Field '" + name_ + "': crs.wkt must not be empty", "''");
      detail::require_finite(crs->origin_easting_m, "Field '" + name_ + "': crs.origin_easting_m");
      detail::require_finite(crs->origin_northing_m, "Field '" + name_ + "': crs.origin_northing_m");
    }
    Field out = *this;
    out.crs_ = std::move(crs);
    return out;
  }
  [[nodiscard]] int width_px() const noexcept { return labels_.cols; }
  [[nodiscard]] int height_px() const noexcept { return labels_.rows; }

  /// The whole orthomosaic in the field frame [m].
  [[nodiscard]] Area area() const noexcept {
    return {0.0, 0.0, width_px() * gsd_cm_ / 100.0, height_px() * gsd_cm_ / 100.0};
  }

  /// Orthomosaic pixels under `a` (raster_rect: edges on pixel boundaries, may extend beyond
  /// the orthomosaic, clamped against overflow).
  [[nodiscard]] cv::Rect pixel_rect(const Area& a) const { return raster_rect(a, gsd_cm_, height_px()); }

  /// Number of valid (non-ignore) pixels under `a` (the part of `a` outside the raster has none).
  [[nodiscard]] int valid_pixels(const Area& a) const {
    const cv::Rect r = pixel_rect(a) & cv::Rect(0, 0, width_px(), height_px());
    return r.area() > 0 ? cv::countNonZero(valid_(r)) : 0;
  }
  /// Number of valid (non-ignore) pixels of the whole field.
  [[nodiscard]] int valid_pixels() const { return cv::countNonZero(valid_); }

  /// True if any valid (non-ignore) pixel lies under `a`.
  [[nodiscard]] bool has_valid(const Area& a) const { return valid_pixels(a) > 0; }

  /// Index of the class called `class_name`, if any.
  [[nodiscard]] std::optional<int> class_index(std::string_view class_name) const {
    for (std::size_t i = 0; i < classes_.size(); ++i)
      if (classes_[i].name == class_name) return static_cast<int>(i);
    return std::nullopt;
  }

  /// Class indices of `names` (sorted, unique).
  /// @throws std::invalid_argument for an unknown class name, listing the known ones.
  [[nodiscard]] std::vector<int> class_indices(const std::vector<std::string>& names) const {
    std::set<int> out;
    for (const auto& n : names) {
      const auto i = class_index(n);
      if (!i) {
        std::string known;
        for (const auto& c : classes_) known += (known.empty() ? "" : ", ") + c.name;
        throw std::invalid_argument("unknown class '" + n + "' in field '" + name_ + "' (classes: " + known + ")");
      }
      out.insert(*i);
    }
    return {out.begin(), out.end()};
  }

  /// The part of the field inside `region` (fractions along the image axes) as a field of
  /// its own, named "<name>[x0,y0,x1,y1]"; pixel edges are rounded to the nearest pixel.
  /// Its frame origin is the region's bottom-left corner; a geo-reference is kept, its
  /// anchor (and a CRS origin) shifted into the new frame, so every ground point keeps its
  /// WGS84 position.
  /// @throws std::invalid_argument unless 0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1 and the
  ///         region holds at least one pixel.
  [[nodiscard]] Field sub_field(const FieldRegion& region) const {
    const auto in01 = [](double v) { return std::isfinite(v) && v >= 0.0 && v <= 1.0; };
    std::ostringstream desc;
    desc << region.x0 << ',' << region.y0 << ',' << region.x1 << ',' << region.y1;
    detail::require(in01(region.x0) && in01(region.x1) && in01(region.y0) && in01(region.y1) && region.x0 < region.x1 &&
                        region.y0 < region.y1,
                    "Field::sub_field: region must satisfy 0 <= x0 < x1 <= 1, 0 <= y0 < y1 <= 1", desc.str());
    const int c0 = static_cast<int>(std::lround(region.x0 * width_px()));
    const int c1 = static_cast<int>(std::lround(region.x1 * width_px()));
    const int r0 = static_cast<int>(std::lround(region.y0 * height_px()));
    const int r1 = static_cast<int>(std::lround(region.y1 * height_px()));
    detail::require(c1 > c0 && r1 > r0, "Field::sub_field: region holds no pixel", desc.str());
    const cv::Rect roi(c0, r0, c1 - c0, r1 - r0);
    Field out(name_ + "[" + desc.str() + "]", gsd_cm_, labels_(roi).clone(), classes_, interest_, ignore_label_,
              image_.empty() ? cv::Mat() : image_(roi).clone());
    if (geo_) {
      // The new origin, the region's bottom-left corner, lies at (c0, height - r1) pixels in this frame.
      out.geo_ = geo_;
      out.geo_->anchor_x_m -= c0 * gsd_cm_ / 100.0;
      out.geo_->anchor_y_m -= (height_px() - r1) * gsd_cm_ / 100.0;
    }
    if (crs_) {
      out.crs_ = crs_;
      out.crs_->origin_easting_m += c0 * gsd_cm_ / 100.0;
      out.crs_->origin_northing_m += (height_px() - r1) * gsd_cm_ / 100.0;
    }
    return out;
  }

 private:
  void validate() const {
    detail::require_positive(gsd_cm_, "Field '" + name_ + "': gsd_cm");
    detail::require(!labels_.empty(), "Field '" + name_ + "': the label map is empty", "0x0");
    detail::require(labels_.type() == CV_8UC1,
                    "Field '" + name_ + "': the label map must be 8-bit single channel (CV_8UC1)",
                    "channels=" + std::to_string(labels_.channels()) + " depth=" + std::to_string(labels_.depth()));
    detail::require(!classes_.empty(), "Field '" + name_ + "': at least one class is required", 0);
    detail::require(ignore_label_ >= 0 && ignore_label_ <= 255, "Field '" + name_ + "': ignore_label must be in 0..255",
                    ignore_label_);
    detail::require(ignore_label_ >= num_classes(),
                    "Field '" + name_ + "': ignore_label must not be a class index (there are " +
                        std::to_string(num_classes()) + " classes)",
                    ignore_label_);
    std::set<std::string> names;
    for (const auto& c : classes_) {
      detail::require(!c.name.empty(), "Field '" + name_ + "': a class has an empty name", "''");
      detail::require(names.insert(c.name).second, "Field '" + name_ + "': class name listed twice", c.name);
    }
    for (int i : interest_)
      detail::require(i >= 0 && i < num_classes(), "Field '" + name_ + "': label of interest out of range", i);
    if (!image_.empty()) {
      detail::require(image_.type() == CV_8UC3, "Field '" + name_ + "': the image must be 8-bit 3-channel",
                      "channels=" + std::to_string(image_.channels()));
      detail::require(image_.size() == labels_.size(), "Field '" + name_ + "': image and label map differ in size",
                      std::to_string(image_.cols) + "x" + std::to_string(image_.rows) + " vs " +
                          std::to_string(labels_.cols) + "x" + std::to_string(labels_.rows));
    }
    // Every pixel must be a class index or the ignore label.
    for (int r = 0; r < labels_.rows; ++r) {
      const auto* row = labels_.ptr<std::uint8_t>(r);
      for (int c = 0; c < labels_.cols; ++c) {
        const int v = row[c];
        if (v >= num_classes() && v != ignore_label_) {
          throw std::invalid_argument("Field '" + name_ + "': label value " + std::to_string(v) + " at row " +
                                      std::to_string(r) + ", col " + std::to_string(c) +
                                      " is neither a class index (0.." + std::to_string(num_classes() - 1) +
                                      ") nor the ignore label " + std::to_string(ignore_label_));
        }
      }
    }
  }

  std::string name_;
  double gsd_cm_;
  cv::Mat labels_;
  cv::Mat image_;
  std::vector<ClassInfo> classes_;
  std::vector<int> interest_;
  int ignore_label_;
  cv::Mat valid_;
  std::optional<FieldGeo> geo_;
  std::optional<FieldCrs> crs_;
};

namespace detail {

[[noreturn]] inline void field_error(const std::filesystem::path& file, const std::string& what) {
  throw std::invalid_argument(file.string() + ": " + what);
}

/// The `geo:` section of field.yaml (`geo`, a reader of its mapping): exactly latitude_deg,
/// longitude_deg, altitude_m and heading_deg (numbers); `anchored` (a live folder's area.yaml,
/// which --record-from writes for a region or a GeoTIFF field) also allows FieldGeo's
/// anchor_x_m, anchor_y_m (default 0) and scale (default 1).
/// @throws std::invalid_argument naming the file and the key.
inline FieldGeo field_read_geo(const YamlReader& geo, bool anchored = false) {
  if (anchored)
    geo.only_keys({"latitude_deg", "longitude_deg", "altitude_m", "heading_deg", "anchor_x_m", "anchor_y_m", "scale"});
  else
    geo.only_keys({"latitude_deg", "longitude_deg", "altitude_m", "heading_deg"});
  FieldGeo g{geo.number("latitude_deg"), geo.number("longitude_deg"), geo.number("altitude_m"),
             geo.number("heading_deg")};
  if (geo.has("anchor_x_m")) g.anchor_x_m = geo.number("anchor_x_m");
  if (geo.has("anchor_y_m")) g.anchor_y_m = geo.number("anchor_y_m");
  if (geo.has("scale")) g.scale = geo.number("scale");
  try {
    validate_field_geo(g, "geo");
  } catch (const std::invalid_argument& e) {
    yaml_error(geo.where(), e.what());
  }
  return g;
}

/// The `classes:` list of field.yaml (and of a live folder's area.yaml) from the reader `r` of
/// the file's mapping: a non-empty list of {name, color: [r, g, b]}, names unique.
/// @throws std::invalid_argument naming the file and the key.
inline std::vector<ClassInfo> field_read_classes(const YamlReader& r) {
  std::vector<ClassInfo> classes;
  for (const YamlReader& c : r.maps("classes")) {
    c.only_keys({"name", "color"});
    ClassInfo info;
    info.name = c.text("name");
    const std::vector<long long> rgb = c.integers("color", 0, 255);
    if (rgb.size() != 3) yaml_error(r.where(), "'" + c.path("color") + "' must be a list of 3 integers [r, g, b]");
    for (std::size_t k = 0; k < 3; ++k) info.color_rgb[k] = static_cast<std::uint8_t>(rgb[k]);
    for (const auto& earlier : classes)
      if (earlier.name == info.name)
        yaml_error(r.where(), "'" + c.path("name") + "': class name '" + info.name + "' listed twice");
    classes.push_back(std::move(info));
  }
  if (classes.empty()) yaml_error(r.where(), "'classes' must be a non-empty list");
  return classes;
}

inline cv::Mat field_read_image(const std::filesystem::path& file, int flags, const std::filesystem::path& yaml) {
  if (!std::filesystem::is_regular_file(file)) field_error(yaml, "file not found: " + file.string());
  cv::Mat m = cv::imread(file.string(), flags);
  if (m.empty()) field_error(yaml, "cannot decode image: " + file.string());
  return m;
}

/// field.yaml read and checked, the rasters not yet loaded (Field::load, gdal::load_field).
struct FieldYaml {
  std::filesystem::path yaml;  ///< the field.yaml file
  std::string name;
  std::optional<double> gsd_cm;           ///< absent: the rasters must carry it
  std::string labels_file;                ///< as written, relative to the directory
  std::optional<std::string> image_file;  ///< as written, relative to the directory
  int ignore_label = 255;
  std::vector<ClassInfo> classes;
  std::vector<int> interest;
  std::optional<FieldGeo> geo;
};

/// Reads `dir`/field.yaml (docs/data_format.md); `gsd_cm` may be absent (the caller decides).
/// @throws std::invalid_argument naming the file and the problem.
inline FieldYaml read_field_yaml(const std::filesystem::path& dir) {
  namespace fs = std::filesystem;
  if (!fs::is_directory(dir)) throw std::invalid_argument("field directory not found: " + dir.string());
  const fs::path yaml = dir / "field.yaml";
  if (!fs::is_regular_file(yaml)) throw std::invalid_argument("missing " + yaml.string());
  const YamlReader r(yaml_mapping(yaml.string(), "a field description", [&] { return YAML::LoadFile(yaml.string()); }),
                     yaml.string());
  r.only_keys({"name", "gsd_cm", "labels", "image", "ignore_label", "classes", "interest", "geo"});
  FieldYaml out;
  out.yaml = yaml;
  out.name = r.text("name");
  if (r.has("gsd_cm")) {
    out.gsd_cm = r.number("gsd_cm");
    if (!(*out.gsd_cm > 0.0)) field_error(yaml, "'gsd_cm' must be > 0 (got " + r.text("gsd_cm") + ")");
  }
  out.labels_file = r.text("labels");
  if (r.has("image")) out.image_file = r.text("image");
  if (r.has("ignore_label")) out.ignore_label = static_cast<int>(r.integer("ignore_label", 0, 255));
  std::vector<ClassInfo> classes = field_read_classes(r);

  std::vector<int> interest;
  for (const std::string& n : r.has("interest") ? r.texts("interest") : std::vector<std::string>{}) {
    const auto it = std::find_if(classes.begin(), classes.end(), [&](const ClassInfo& c) { return c.name == n; });
    if (it == classes.end()) field_error(yaml, "'interest' names unknown class '" + n + "'");
    interest.push_back(static_cast<int>(it - classes.begin()));
  }
  std::sort(interest.begin(), interest.end());
  interest.erase(std::unique(interest.begin(), interest.end()), interest.end());

  if (r.has("geo")) out.geo = field_read_geo(r.map("geo"));
  out.classes = std::move(classes);
  out.interest = std::move(interest);
  return out;
}

/// The label map as read from `file`: it must be 8-bit single channel.
inline cv::Mat field_check_labels(cv::Mat labels, const FieldYaml& y) {
  if (labels.type() != CV_8UC1)
    field_error(y.yaml, "'" + y.labels_file + "' must be an 8-bit single-channel PNG (got " +
                            std::to_string(labels.channels()) + " channels, depth " + std::to_string(labels.depth()) +
                            ")");
  return labels;
}

/// The Field of `y` with these rasters; a violation of Field's rules names field.yaml.
inline Field field_from_yaml(const FieldYaml& y, double gsd_cm, cv::Mat labels, cv::Mat image) {
  try {
    Field f = Field(y.name, gsd_cm, std::move(labels), y.classes, y.interest, y.ignore_label, std::move(image))
                  .with_geo(y.geo);
    // A field without a labelled pixel would fly no image and score NaN: say so instead.
    if (f.valid_pixels() == 0)
      throw std::invalid_argument("the field has no valid pixel: every label is the ignore label " +
                                  std::to_string(y.ignore_label) + " (or, in a GeoTIFF orthomosaic, transparent)");
    return f;
  } catch (const std::invalid_argument& e) {
    field_error(y.yaml, e.what());
  }
}

}  // namespace detail

inline Field Field::load(const std::filesystem::path& dir) {
  const detail::FieldYaml y = detail::read_field_yaml(dir);
  if (!y.gsd_cm)
    detail::field_error(y.yaml,
                        "missing key 'gsd_cm' (a field whose rasters carry their georeference, "
                        "e.g. GeoTIFFs, loads with adaptseg::gdal::load_field, <adaptseg/gdal/gdal_io.hpp>)");
  cv::Mat labels =
      detail::field_check_labels(detail::field_read_image(dir / y.labels_file, cv::IMREAD_UNCHANGED, y.yaml), y);
  cv::Mat image;
  if (y.image_file) image = detail::field_read_image(dir / *y.image_file, cv::IMREAD_COLOR, y.yaml);
  return detail::field_from_yaml(y, *y.gsd_cm, std::move(labels), std::move(image));
}

}  // namespace adaptseg
