#pragma once
/// @file
/// The fused map written as a GeoTIFF in the field's CRS (or, for a field georeferenced by a
/// `geo:` section, a transverse Mercator on its anchor), with the classes' colours and names, and
/// the GSD each pixel was observed at, for QGIS and the like (docs/data_format.md, "GeoTIFF
/// fields"). CMake target adaptseg::gdal.

#include <adaptseg/core/error.hpp>
#include <adaptseg/gdal/detail/dataset.hpp>
#include <adaptseg/vision/field.hpp>

#include <GeographicLib/Math.hpp>
#include <cpl_conv.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg::gdal {

/// The grid of a map to write as a GeoTIFF: its size, GSD, georeference, classes. A field's
/// (MapGrid::of), or a live mission's, whose map covers a SurveyArea with a geo-reference.
struct MapGrid {
  std::string name;  ///< for messages
  int width_px = 0;
  int height_px = 0;
  double gsd_cm = 0.0;          ///< square pixels [cm/px]; the raster's bottom-left corner is the frame origin
  std::optional<FieldCrs> crs;  ///< a projected CRS (a GeoTIFF field's), used when present
  std::optional<FieldGeo> geo;  ///< otherwise the frame's WGS84 geo-reference
  std::vector<ClassInfo> classes;
  int ignore_label = 255;

  /// The grid of `field`'s orthomosaic.
  [[nodiscard]] static MapGrid of(const Field& field) {
    return {field.name(), field.width_px(), field.height_px(), field.gsd_cm(),
            field.crs(),  field.geo(),      field.classes(),   field.ignore_label()};
  }
};

namespace detail {

/// A GeoTIFF of the map grid in its CRS: the raster's own for a GeoTIFF field; for a
/// field georeferenced by `geo:`, a transverse Mercator centred on the anchor (the tangent
/// plane to < 0.1 mm over a kilometre) with the field's heading as a rotated geotransform.
inline Dataset create_on_field_grid(const std::filesystem::path& file, const MapGrid& grid, GDALDataType type,
                                    const std::vector<std::string>& creation_options) {
  register_drivers();
  std::string wkt;
  std::array<double, 6> gt{};
  const double g = grid.gsd_cm / 100.0;
  if (grid.crs) {
    wkt = grid.crs->wkt;
    gt = {grid.crs->origin_easting_m, g, 0.0, grid.crs->origin_northing_m + grid.height_px * g, 0.0, -g};
  } else if (grid.geo) {
    const FieldGeo& geo = *grid.geo;
    OGRSpatialReference srs;
    srs.SetWellKnownGeogCS("WGS84");
    srs.SetTM(geo.latitude_deg, geo.longitude_deg, 1.0, 0.0, 0.0);
    char* text = nullptr;
    const char* const options[] = {"FORMAT=WKT2_2019", nullptr};
    srs.exportToWkt(&text, options);
    wkt = text ? text : "";
    CPLFree(text);
    double sh = 1.0, ch = 0.0;
    GeographicLib::Math::sincosd(geo.heading_deg, sh, ch);  // exact at multiples of 90 degrees, as GeoReference
    const double k = geo.scale;
    const double ax = geo.anchor_x_m, ay = geo.anchor_y_m, top = grid.height_px * g;
    // Pixel corner (col, row) is field point (col g, top - row g); east/north as in GeoReference.
    gt = {(-ax * sh - (top - ay) * ch) / k, g * sh / k, g * ch / k,
          (-ax * ch + (top - ay) * sh) / k, g * ch / k, -g * sh / k};
  } else {
    throw std::invalid_argument("'" + grid.name + "' has no georeference (a GeoTIFF field or a geo: section)");
  }
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName("GTiff");
  if (driver == nullptr) throw std::runtime_error("GDAL has no GTiff driver");
  CPLStringList options;
  for (const auto& o : creation_options) options.AddString(o.c_str());
  const QuietErrors quiet;
  CPLErrorReset();
  Dataset d(driver->Create(file.c_str(), grid.width_px, grid.height_px, 1, type, options.List()));
  if (!d) throw std::runtime_error(file.string() + ": cannot create (" + last_error() + ")");
  if (d->SetGeoTransform(gt.data()) != CE_None || d->SetProjection(wkt.c_str()) != CE_None)
    throw std::runtime_error(file.string() + ": cannot write the georeference (" + last_error() + ")");
  return d;
}

/// Writes `m` into band 1 in strips of ~64 MiB, each flushed to the file before the next (as
/// read_interleaved: GDAL's block cache holds no second copy of a large map).
inline void write_band(GDALDataset& d, const cv::Mat& m, GDALDataType type, const std::filesystem::path& file) {
  GDALRasterBand* band = d.GetRasterBand(1);
  const std::size_t row_bytes = m.step[0];
  const int strip = strip_rows(*band, row_bytes, std::size_t{64} << 20);
  const QuietErrors quiet;
  CPLErrorReset();
  for (int r0 = 0; r0 < m.rows; r0 += strip) {
    const int rows = std::min(strip, m.rows - r0);
    if (band->RasterIO(GF_Write, 0, r0, m.cols, rows, const_cast<std::uint8_t*>(m.ptr(r0)), m.cols, rows, type, 0,
                       static_cast<GSpacing>(row_bytes), nullptr) != CE_None ||
        band->FlushCache(false) != CE_None)
      throw std::runtime_error(file.string() + ": cannot write the pixels (" + last_error() + ")");
  }
}

}  // namespace detail

/// Writes `labels` (class indices of `grid`'s classes, CV_8UC1 of its size; the ignore label
/// where unobserved) as a GeoTIFF on the grid (see detail::create_on_field_grid): one Byte band,
/// DEFLATE-compressed, nodata = the ignore label, a colour table with the classes' colours and
/// their names as category names (QGIS shows it as the PNG map).
/// @throws std::invalid_argument for a mistyped map or a grid without georeference;
///         std::runtime_error if the file cannot be written.
inline void write_map_geotiff(const std::filesystem::path& file, const MapGrid& grid, const cv::Mat& labels) {
  adaptseg::detail::require(labels.type() == CV_8UC1 && labels.size() == cv::Size(grid.width_px, grid.height_px),
                            "write_map_geotiff: labels must be CV_8UC1 of the map grid's size",
                            std::to_string(labels.cols) + "x" + std::to_string(labels.rows));
  detail::Dataset d = detail::create_on_field_grid(file, grid, GDT_Byte, {"COMPRESS=DEFLATE", "TILED=YES"});
  GDALRasterBand* band = d->GetRasterBand(1);
  band->SetDescription("class");
  band->SetNoDataValue(grid.ignore_label);
  GDALColorTable colors;  // the classes only: the ignore label is nodata
  CPLStringList names;
  for (const ClassInfo& c : grid.classes) {
    const GDALColorEntry e{c.color_rgb[0], c.color_rgb[1], c.color_rgb[2], 255};
    colors.SetColorEntry(colors.GetColorEntryCount(), &e);
    names.AddString(c.name.c_str());
  }
  band->SetColorTable(&colors);
  band->SetCategoryNames(names.List());
  detail::write_band(*d, labels, GDT_Byte, file);
  d.reset();  // flush and close
}

/// write_map_geotiff on `field`'s grid.
inline void write_map_geotiff(const std::filesystem::path& file, const Field& field, const cv::Mat& labels) {
  write_map_geotiff(file, MapGrid::of(field), labels);
}

/// Writes the GSD [cm/px] each pixel of a fused map was observed at (SemanticMap::gsd_cm(),
/// CV_32F of the grid's size, +inf where unobserved) as a Float32 GeoTIFF on the grid, nodata 0
/// where unobserved.
/// @throws as write_map_geotiff.
inline void write_gsd_geotiff(const std::filesystem::path& file, const MapGrid& grid, const cv::Mat& gsd_cm) {
  adaptseg::detail::require(gsd_cm.type() == CV_32F && gsd_cm.size() == cv::Size(grid.width_px, grid.height_px),
                            "write_gsd_geotiff: gsd_cm must be CV_32F of the map grid's size",
                            std::to_string(gsd_cm.cols) + "x" + std::to_string(gsd_cm.rows));
  cv::Mat out = gsd_cm.clone();
  out.setTo(0.0, out == std::numeric_limits<double>::infinity());
  detail::Dataset d = detail::create_on_field_grid(file, grid, GDT_Float32, {"COMPRESS=DEFLATE", "TILED=YES"});
  d->GetRasterBand(1)->SetDescription("gsd_cm");
  d->GetRasterBand(1)->SetNoDataValue(0.0);
  detail::write_band(*d, out, GDT_Float32, file);
  d.reset();
}

/// write_gsd_geotiff on `field`'s grid.
inline void write_gsd_geotiff(const std::filesystem::path& file, const Field& field, const cv::Mat& gsd_cm) {
  write_gsd_geotiff(file, MapGrid::of(field), gsd_cm);
}

}  // namespace adaptseg::gdal
