#pragma once
/// @file
/// GIS rasters in through GDAL: fields whose orthomosaic and labels are GeoTIFFs (or any raster
/// GDAL reads) in a projected CRS (docs/data_format.md, "GeoTIFF fields"); the fused map written
/// back as a GeoTIFF in the field's CRS is map_geotiff.hpp's, which this header includes.
/// CMake target adaptseg::gdal (GDAL >= 3.1, plus adaptseg::geo); the core, adaptseg::vision
/// and adaptseg::geo do not need GDAL.
///
/// What is supported, and what is refused with one clear error each:
/// - grids: north-up geotransforms (no rotation or shear terms), square pixels, in a projected
///   CRS whose linear unit is the metre. Rotated grids, geographic CRSs (degrees), other units
///   and non-square pixels are refused (reproject with `gdalwarp`);
/// - the orthomosaic: 8-bit, at least 3 bands read as red, green, blue (a 4th band is ignored);
/// - labels: 8-bit, either one band of class indices or 3-4 bands of the classes' colours of
///   field.yaml (a 4th band is alpha: 0 = unlabelled). Nodata (and alpha 0) becomes the field's
///   ignore label; a value that is neither a class nor nodata is an error that names it;
/// - image and labels on the same grid and CRS.
///
/// One geo-reference model: the raster's CRS is turned, once at load, into the same
/// `FieldGeo` (anchor, heading, scale) a `geo:` section gives, so the exports go through
/// `GeoReference` whatever georeferenced the field; load_field checks at the field's corners
/// that this model agrees with GDAL's own transformation of the CRS to within 5 cm.

#include <adaptseg/core/error.hpp>
#include <adaptseg/gdal/detail/dataset.hpp>
#include <adaptseg/gdal/map_geotiff.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/vision/field.hpp>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <iomanip>
#include <limits>
#include <locale>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::gdal {

/// A raster's grid: its size, north-up geotransform and projected CRS in metres.
struct RasterGrid {
  int width_px = 0;
  int height_px = 0;
  /// GDAL's geotransform: easting = gt[0] + col * gt[1], northing = gt[3] + row * gt[5] at a
  /// pixel's top-left corner (gt[2] = gt[4] = 0: north-up).
  std::array<double, 6> geotransform{};
  std::string crs_wkt;  ///< the CRS as WKT2

  /// Pixel size [m] (square pixels).
  [[nodiscard]] double pixel_size_m() const noexcept { return geotransform[1]; }
};

namespace detail {

inline RasterGrid grid_of(GDALDataset& d, const std::filesystem::path& file) {
  RasterGrid g;
  g.width_px = d.GetRasterXSize();
  g.height_px = d.GetRasterYSize();
  {
    const QuietErrors quiet;
    if (d.GetGeoTransform(g.geotransform.data()) != CE_None)
      fail(file,
           "the raster has no geotransform (georeference it, e.g. gdal_translate -a_srs -a_ullr, "
           "or give gsd_cm in field.yaml and use a plain image)");
  }
  const OGRSpatialReference* srs = d.GetSpatialRef();
  if (srs == nullptr || srs->IsEmpty()) fail(file, "the raster has no coordinate reference system");
  if (srs->IsGeographic()) {
    // The UTM zone of the raster's centre (geotransform in degrees: longitude, latitude).
    const double lon = g.geotransform[0] + 0.5 * g.width_px * g.geotransform[1];
    const double lat = g.geotransform[3] + 0.5 * g.height_px * g.geotransform[5];
    const int zone = std::clamp(static_cast<int>(std::floor((lon + 180.0) / 6.0)) + 1, 1, 60);
    const int epsg = (lat >= 0.0 ? 32600 : 32700) + zone;
    fail(file,
         "geographic CRS (coordinates in degrees): reproject to a projected CRS in metres, "
         "e.g. gdalwarp -t_srs EPSG:" +
             std::to_string(epsg) + " (UTM zone " + std::to_string(zone) + (lat >= 0.0 ? "N" : "S") + ", the field's)");
  }
  if (!srs->IsProjected()) fail(file, "the CRS is not a projected one (need easting and northing in metres)");
  const char* unit = nullptr;
  const double to_metre = srs->GetLinearUnits(&unit);
  if (std::abs(to_metre - 1.0) > 1e-12)
    fail(file, std::string("the CRS's linear unit is '") + (unit ? unit : "?") +
                   "', not metre: reproject to a CRS in metres");
  const auto& gt = g.geotransform;
  for (double v : gt)
    if (!std::isfinite(v)) fail(file, "the geotransform is not finite");
  if (gt[2] != 0.0 || gt[4] != 0.0)
    fail(file, "rotated or sheared geotransform (terms " + num(gt[2]) + ", " + num(gt[4]) +
                   "): only north-up rasters are supported (resample with gdalwarp)");
  if (!(gt[1] > 0.0) || !(gt[5] < 0.0))
    fail(file, "the geotransform must have columns eastwards and rows southwards (pixel size " + num(gt[1]) + " x " +
                   num(gt[5]) + ")");
  if (std::abs(gt[1] + gt[5]) > 1e-6 * gt[1])
    fail(file, "non-square pixels (" + num(gt[1]) + " x " + num(-gt[5]) +
                   " m): resample to square pixels, e.g. gdalwarp -tr " + num(gt[1]) + " " + num(gt[1]));
  char* wkt = nullptr;
  const char* const options[] = {"FORMAT=WKT2_2019", nullptr};
  if (srs->exportToWkt(&wkt, options) != OGRERR_NONE || wkt == nullptr) {
    CPLFree(wkt);
    fail(file, "cannot export the CRS as WKT");
  }
  g.crs_wkt = wkt;
  CPLFree(wkt);
  return g;
}

/// Reads bands `band_map` (1-based) of an 8-bit raster into one interleaved CV_8UC(n) matrix:
/// GDAL writes straight into the matrix (no per-band copy), in strips of ~64 MiB whose cached
/// blocks are dropped after each strip, so GDAL's block cache (5 % of RAM by default) does not
/// hold a second copy of a large raster (20000 x 20000 RGB: peak 2.0 GiB instead of 2.8).
inline cv::Mat read_interleaved(GDALDataset& d, const std::filesystem::path& file, std::vector<int> band_map,
                                std::size_t strip_bytes = std::size_t{64} << 20) {
  const int n = static_cast<int>(band_map.size());
  for (int b : band_map)
    if (d.GetRasterBand(b)->GetRasterDataType() != GDT_Byte)
      fail(file, "band " + std::to_string(b) + " is " + GDALGetDataTypeName(d.GetRasterBand(b)->GetRasterDataType()) +
                     ", need 8-bit (Byte)");
  cv::Mat m(d.GetRasterYSize(), d.GetRasterXSize(), CV_8UC(n));
  const std::size_t row_bytes = m.step[0];
  const int strip = strip_rows(*d.GetRasterBand(band_map.front()), row_bytes, strip_bytes);
  const QuietErrors quiet;
  CPLErrorReset();
  for (int r0 = 0; r0 < m.rows; r0 += strip) {
    const int rows = std::min(strip, m.rows - r0);
    const CPLErr err = d.RasterIO(GF_Read, 0, r0, m.cols, rows, m.ptr(r0), m.cols, rows, GDT_Byte, n, band_map.data(),
                                  n, static_cast<GSpacing>(row_bytes), 1, nullptr);
    if (err != CE_None) fail(file, "cannot read the pixels (" + last_error() + ")");
    for (int b : band_map) d.GetRasterBand(b)->FlushCache(false);
  }
  return m;
}

/// The nodata value of band `b` as a byte, if it has one.
inline std::optional<int> nodata_byte(GDALDataset& d, int b, const std::filesystem::path& file) {
  int has = 0;
  const double v = d.GetRasterBand(b)->GetNoDataValue(&has);
  if (!has) return std::nullopt;
  if (!(v >= 0.0 && v <= 255.0) || v != std::floor(v))
    fail(file, "band " + std::to_string(b) + "'s nodata value " + num(v) + " is not a byte");
  return static_cast<int>(v);
}

inline std::string pixel_at(int r, int c) { return "row " + std::to_string(r) + ", col " + std::to_string(c); }

/// Labels as class indices (1 band) or class colours (3 bands, optional alpha) -> CV_8UC1 with
/// `ignore` where unlabelled.
inline cv::Mat read_labels(GDALDataset& d, const std::filesystem::path& file, const std::vector<ClassInfo>& classes,
                           int ignore) {
  const int bands = d.GetRasterCount();
  const int k = static_cast<int>(classes.size());
  const std::string fix = " (declare unlabelled pixels as nodata, e.g. gdal_edit.py -a_nodata " +
                          std::to_string(ignore) + ", or use field.yaml's ignore_label)";
  if (bands == 1) {
    cv::Mat labels = read_interleaved(d, file, {1});
    const std::optional<int> nodata = nodata_byte(d, 1, file);
    for (int r = 0; r < labels.rows; ++r) {
      auto* row = labels.ptr<std::uint8_t>(r);
      for (int c = 0; c < labels.cols; ++c) {
        const int v = row[c];
        if (nodata && v == *nodata) {
          row[c] = static_cast<std::uint8_t>(ignore);
        } else if (v >= k && v != ignore) {
          fail(file,
               "value " + std::to_string(v) + " at " + pixel_at(r, c) + " is no class index (0.." +
                   std::to_string(k - 1) + "), not the ignore label " + std::to_string(ignore) +
                   (nodata ? ", not nodata " + std::to_string(*nodata) : ", and the band has no nodata value" + fix));
        }
      }
    }
    return labels;
  }
  if (bands != 3 && bands != 4)
    fail(file, std::to_string(bands) + " bands: labels need 1 band (class indices) or 3-4 (class colours, alpha)");
  cv::Mat rgb = read_interleaved(d, file, bands == 4 ? std::vector<int>{1, 2, 3, 4} : std::vector<int>{1, 2, 3});
  std::array<std::optional<int>, 3> nodata{nodata_byte(d, 1, file), nodata_byte(d, 2, file), nodata_byte(d, 3, file)};
  const bool has_nodata = nodata[0] && nodata[1] && nodata[2];
  // Colour -> class through a table of all 2^24 colours (32 MB; one lookup per pixel).
  constexpr std::int16_t kNone = -1;
  std::vector<std::int16_t> table(std::size_t{1} << 24, kNone);
  const auto key = [](int r, int g, int b) {
    return (static_cast<std::size_t>(r) << 16) | (static_cast<std::size_t>(g) << 8) | static_cast<std::size_t>(b);
  };
  for (int i = k - 1; i >= 0; --i) {
    const auto& col = classes[static_cast<std::size_t>(i)].color_rgb;
    table[key(col[0], col[1], col[2])] = static_cast<std::int16_t>(i);
  }
  cv::Mat labels(rgb.rows, rgb.cols, CV_8UC1);
  const int n = rgb.channels();
  for (int r = 0; r < rgb.rows; ++r) {
    const std::uint8_t* in = rgb.ptr<std::uint8_t>(r);
    auto* out = labels.ptr<std::uint8_t>(r);
    for (int c = 0; c < rgb.cols; ++c, in += n) {
      if ((n == 4 && in[3] == 0) || (has_nodata && in[0] == *nodata[0] && in[1] == *nodata[1] && in[2] == *nodata[2])) {
        out[c] = static_cast<std::uint8_t>(ignore);
        continue;
      }
      const std::int16_t cls = table[key(in[0], in[1], in[2])];
      if (cls == kNone)
        fail(file,
             "colour (" + std::to_string(in[0]) + ", " + std::to_string(in[1]) + ", " + std::to_string(in[2]) +
                 ") at " + pixel_at(r, c) + " is no class colour of field.yaml" +
                 (has_nodata || n == 4 ? std::string() : std::string(", and the raster has no nodata value") + fix));
      out[c] = static_cast<std::uint8_t>(cls);
    }
  }
  return labels;
}

/// Easting, northing -> WGS84 through GDAL/PROJ (the reference the field's model is checked against).
class CrsToWgs84 {
 public:
  CrsToWgs84(const std::string& wkt, const std::filesystem::path& file) {
    if (src_.importFromWkt(wkt.c_str()) != OGRERR_NONE) fail(file, "cannot parse the CRS");
    src_.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    dst_.SetWellKnownGeogCS("WGS84");
    dst_.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    const QuietErrors quiet;
    ct_.reset(OGRCreateCoordinateTransformation(&src_, &dst_));
    if (!ct_) fail(file, "no transformation from the raster's CRS to WGS84 (" + last_error() + ")");
  }
  /// (easting, northing) [m] -> (latitude, longitude) [deg].
  [[nodiscard]] std::pair<double, double> operator()(double e, double n) const {
    double x = e, y = n;
    if (!ct_->Transform(1, &x, &y))
      throw std::invalid_argument("the CRS cannot transform easting " + std::to_string(e));
    return {y, x};
  }

 private:
  struct CtDeleter {
    void operator()(OGRCoordinateTransformation* t) const noexcept { OGRCoordinateTransformation::DestroyCT(t); }
  };
  OGRSpatialReference src_;
  OGRSpatialReference dst_;
  std::unique_ptr<OGRCoordinateTransformation, CtDeleter> ct_;
};

/// The FieldGeo of a north-up grid: anchored at the field's centre, heading and scale of the
/// grid there (from GDAL's transformation of points 50 m either side); checked at the corners.
inline FieldGeo field_geo_of(const RasterGrid& g, const std::filesystem::path& file, double altitude_m) {
  const CrsToWgs84 to_wgs84(g.crs_wkt, file);
  const double px = g.pixel_size_m();
  const double w = g.width_px * px, h = g.height_px * px;
  const double e0 = g.geotransform[0], n0 = g.geotransform[3] - h;  // field origin: bottom-left corner
  const auto& geod = GeographicLib::Geodesic::WGS84();
  const double ec = e0 + w / 2, nc = n0 + h / 2, d = 50.0;
  const auto [lat_c, lon_c] = to_wgs84(ec, nc);
  const auto [lat_s, lon_s] = to_wgs84(ec, nc - d);
  const auto [lat_n, lon_n] = to_wgs84(ec, nc + d);
  const auto [lat_w, lon_w] = to_wgs84(ec - d, nc);
  const auto [lat_e, lon_e] = to_wgs84(ec + d, nc);
  // Distances and bearings in the tangent plane itself (at the field plane's height, as
  // GeoReference uses it): at 1000 m above the ellipsoid its metres are 1.6e-4 longer than the
  // ellipsoid's, 8 cm over 500 m.
  const GeographicLib::LocalCartesian plane(lat_c, lon_c, altitude_m);
  const auto in_plane = [&](double lat, double lon) {
    double x = 0, y = 0, z = 0;
    plane.Forward(lat, lon, altitude_m, x, y, z);
    return std::pair{x, y};
  };
  const auto bearing_and_length = [&](std::pair<double, double> a, std::pair<double, double> b) {
    const double de = b.first - a.first, dn = b.second - a.second;
    return std::pair{std::atan2(de, dn) * 180.0 / std::numbers::pi, std::hypot(de, dn)};
  };
  const auto [az_ns, s_ns] = bearing_and_length(in_plane(lat_s, lon_s), in_plane(lat_n, lon_n));
  const auto [az_we, s_we] = bearing_and_length(in_plane(lat_w, lon_w), in_plane(lat_e, lon_e));
  FieldGeo geo{lat_c, lon_c, altitude_m, az_ns + 90.0, w / 2, h / 2, (2 * d) / s_ns};
  // A conformal grid: the same scale both ways and +x at right angles to +y.
  const double skew = std::remainder(az_we - (az_ns + 90.0), 360.0);
  if (std::abs(s_ns - s_we) > 1e-5 * s_ns || std::abs(skew) > 1e-3)
    fail(file, "the CRS is not conformal here (scale " + num(2 * d / s_ns) + " north-south vs " + num(2 * d / s_we) +
                   " east-west): use a conformal projection such as UTM");
  const GeoReference model(geo);
  double worst = 0.0;
  for (const auto& [x, y] : {std::pair{0.0, 0.0}, std::pair{w, 0.0}, std::pair{0.0, h}, std::pair{w, h}}) {
    const auto [lat, lon] = to_wgs84(e0 + x, n0 + y);
    const GeoPoint p = model.to_wgs84({x, y, 0.0});
    double s = 0, a1 = 0, a2 = 0;
    geod.Inverse(lat, lon, p.latitude_deg, p.longitude_deg, s, a1, a2);
    worst = std::max(worst, s);
  }
  if (worst > 0.05)
    fail(file, "the field is too large for one tangent plane in this CRS: " + num(worst) +
                   " m off at a corner (split it into regions)");
  return geo;
}

/// load_field's orthomosaic of the field `y` in `dir`: on the labels' grid `grid` and CRS,
/// red, green and blue read as BGR. No data in it (a 4th band's alpha 0, as OpenDroneMap writes
/// outside the flown area, or the bands' nodata values) is not the field: black there, as the
/// simulator fills ground outside the orthomosaic (a network backend leaves it unlabelled), and
/// the ignore label in `labels`, so that nothing is segmented, fused or scored there.
[[nodiscard]] inline cv::Mat read_field_image(const std::filesystem::path& dir, const adaptseg::detail::FieldYaml& y,
                                              const RasterGrid& grid, cv::Mat& labels) {
  using adaptseg::detail::field_error;
  const std::filesystem::path image_file = dir / *y.image_file;
  const Dataset id = open(image_file);
  if (!has_geotransform(*id))
    field_error(y.yaml, "'" + *y.image_file + "' has no georeference but '" + y.labels_file + "' has one");
  const RasterGrid ig = grid_of(*id, image_file);
  OGRSpatialReference a, b;
  a.importFromWkt(grid.crs_wkt.c_str());
  b.importFromWkt(ig.crs_wkt.c_str());
  const double tol = 1e-6 * grid.pixel_size_m();
  bool same = ig.width_px == grid.width_px && ig.height_px == grid.height_px;
  for (std::size_t i = 0; i < 6; ++i) same = same && std::abs(ig.geotransform[i] - grid.geotransform[i]) <= tol;
  if (!same)
    field_error(y.yaml, "'" + *y.image_file + "' and '" + y.labels_file + "' are not on the same grid (" +
                            std::to_string(ig.width_px) + "x" + std::to_string(ig.height_px) + " px from (" +
                            num(ig.geotransform[0]) + ", " + num(ig.geotransform[3]) + ") vs " +
                            std::to_string(grid.width_px) + "x" + std::to_string(grid.height_px) + " px from (" +
                            num(grid.geotransform[0]) + ", " + num(grid.geotransform[3]) +
                            "); align them with gdalwarp -te -tr)");
  if (!a.IsSame(&b)) field_error(y.yaml, "'" + *y.image_file + "' and '" + y.labels_file + "' differ in CRS");
  if (id->GetRasterCount() < 3)
    fail(image_file, std::to_string(id->GetRasterCount()) + " band(s): the image needs red, green, blue");
  cv::Mat image = read_interleaved(*id, image_file, {3, 2, 1});  // BGR, as OpenCV
  cv::Mat no_data(image.size(), CV_8UC1, cv::Scalar(0));
  if (id->GetRasterCount() >= 4 && id->GetRasterBand(4)->GetColorInterpretation() == GCI_AlphaBand)
    no_data = read_interleaved(*id, image_file, {4}) == 0;
  const std::array<std::optional<int>, 3> nodata{nodata_byte(*id, 1, image_file), nodata_byte(*id, 2, image_file),
                                                 nodata_byte(*id, 3, image_file)};
  if (nodata[0] && nodata[1] && nodata[2]) {
    cv::Mat is_nodata;
    cv::inRange(image, cv::Scalar(*nodata[2], *nodata[1], *nodata[0]), cv::Scalar(*nodata[2], *nodata[1], *nodata[0]),
                is_nodata);  // BGR order
    no_data |= is_nodata;
  }
  image.setTo(cv::Scalar(0, 0, 0), no_data);
  labels.setTo(cv::Scalar(y.ignore_label), no_data);
  return image;
}

/// load_field's check of the field's `geo:` section against the raster's georeference `geo`:
/// the section anchors the frame origin (0, 0), compared there (1 m, 0.1 degree of heading).
inline void check_field_geo(const adaptseg::detail::FieldYaml& y, const FieldGeo& geo) {
  const GeoPoint origin = GeoReference(geo).to_wgs84({0.0, 0.0, 0.0});
  double s = 0, a1 = 0, a2 = 0;
  GeographicLib::Geodesic::WGS84().Inverse(origin.latitude_deg, origin.longitude_deg, y.geo->latitude_deg,
                                           y.geo->longitude_deg, s, a1, a2);
  const double dh = std::remainder(y.geo->heading_deg - geo.heading_deg, 360.0);
  if (s > 1.0 || std::abs(dh) > 0.1)
    adaptseg::detail::field_error(y.yaml, "geo: disagrees with '" + y.labels_file + "' (field origin " + num(s) +
                                              " m apart, heading " + num(dh) +
                                              " degrees apart); omit geo: or correct it");
}

}  // namespace detail

/// The grid of a raster file.
/// @throws std::invalid_argument naming the file: unreadable, no geotransform, rotated or
///         sheared, non-square pixels, no CRS, a geographic CRS, a linear unit other than metre.
[[nodiscard]] inline RasterGrid read_grid(const std::filesystem::path& file) {
  const detail::Dataset d = detail::open(file);
  return detail::grid_of(*d, file);
}

/// Loads a field directory like Field::load, reading rasters that carry a georeference with GDAL:
/// `gsd_cm` and `geo:` may then be omitted (and must agree with the labels raster if given:
/// GSD to 1e-6, position of the field origin to 1 m, heading to 0.1 degree; `geo:`'s
/// `altitude_m` is the field plane's height, 0 without it). The field's crs() is the raster's,
/// its geo() the same grid as anchor, heading and scale (see the file comment). A labels file
/// without a geotransform (a plain PNG) loads exactly as Field::load.
/// @throws std::invalid_argument naming the file and the problem.
[[nodiscard]] inline Field load_field(const std::filesystem::path& dir) {
  using adaptseg::detail::field_error;
  const adaptseg::detail::FieldYaml y = adaptseg::detail::read_field_yaml(dir);
  const std::filesystem::path labels_file = dir / y.labels_file;
  const detail::Dataset ld = detail::open(labels_file);
  if (!detail::has_geotransform(*ld)) return Field::load(dir);
  const RasterGrid grid = detail::grid_of(*ld, labels_file);
  cv::Mat labels = detail::read_labels(*ld, labels_file, y.classes, y.ignore_label);
  cv::Mat image;
  if (y.image_file) image = detail::read_field_image(dir, y, grid, labels);
  const double gsd_cm = 100.0 * grid.pixel_size_m();
  if (y.gsd_cm && std::abs(*y.gsd_cm - gsd_cm) > 1e-6 * gsd_cm)
    field_error(y.yaml, "gsd_cm " + detail::num(*y.gsd_cm) + " disagrees with '" + y.labels_file +
                            "', whose pixels are " + detail::num(gsd_cm) + " cm");
  FieldGeo geo = [&] {
    try {
      return detail::field_geo_of(grid, labels_file, y.geo ? y.geo->altitude_m : 0.0);
    } catch (const std::invalid_argument& e) {
      field_error(y.yaml, e.what());
    }
  }();
  if (y.geo) detail::check_field_geo(y, geo);
  adaptseg::detail::FieldYaml with_geo = y;
  with_geo.geo = geo;
  return adaptseg::detail::field_from_yaml(with_geo, gsd_cm, std::move(labels), std::move(image))
      .with_crs(
          FieldCrs{grid.crs_wkt, grid.geotransform[0], grid.geotransform[3] + grid.height_px * grid.geotransform[5]});
}

}  // namespace adaptseg::gdal
