#pragma once
/// @file
/// Terrain following from a digital elevation model (a DEM GeoTIFF, or any raster GDAL reads
/// with a geotransform and a CRS: SRTM or Copernicus tiles in degrees, a photogrammetric DSM in
/// UTM): each waypoint of a survey flown at the height above its own ground that keeps the GSD,
/// with its altitude given relative to home. CMake target adaptseg::gdal.
///
/// Why relative altitudes (MAV_FRAME_GLOBAL_RELATIVE_ALT, 3) and not the other frames: PX4's
/// mission parser accepts MAV_FRAME_GLOBAL(_INT) and MAV_FRAME_GLOBAL_RELATIVE_ALT(_INT) only
/// (src/modules/mavlink/mavlink_mission.cpp, parse_mavlink_mission_item), so the terrain frame
/// (MAV_FRAME_GLOBAL_TERRAIN_ALT, 10) is ArduPilot's alone, and there only with terrain data
/// loaded on the autopilot (AP_Mission.cpp: the frame needs AP_TERRAIN_AVAILABLE). Absolute
/// altitudes (MAV_FRAME_GLOBAL, AMSL) would need the DEM's vertical datum to match the
/// autopilot's idea of mean sea level, and its take-off altitude to be right to a metre; a
/// difference of two DEM heights, the waypoint's ground less home's, is free of both (the
/// datum's offset cancels, and the geoid changes by centimetres over a site). QGroundControl
/// shows such items as "Relative" altitude (AltitudeMode 1). The home point must therefore be
/// where the UAV really takes off: the altitudes are relative to the ground there.
///
/// @code
/// const adaptseg::ElevationModel dem("dem.tif");
/// const auto terrain = adaptseg::follow_terrain(path, adaptseg::GeoReference(site.geo), home_xy, dem, 55.0);
/// // path[i].position.z(): 55 m above the mean ground under footprint i, relative to home's ground
/// @endcode

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/gdal/gdal_io.hpp>
#include <adaptseg/geo/georeference.hpp>

#include <GeographicLib/Geodesic.hpp>
#include <gdal_priv.h>
#include <ogr_spatialref.h>

#include <opencv2/core.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <filesystem>
#include <limits>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

namespace adaptseg {

/// A digital elevation model: ground heights [m] on a raster grid in any CRS GDAL/PROJ
/// transforms WGS84 into, read whole into memory (band 1; its nodata value and non-finite
/// values are "no elevation"), looked up by bilinear interpolation between pixel centres.
/// Heights are in the DEM's own vertical datum (usually above the geoid, EGM96 or EGM2008):
/// use them as differences (follow_terrain).
class ElevationModel {
 public:
  /// The largest DEM read [pixels]: 200 MB of floats. A larger one is refused, with how to crop it.
  static constexpr double kMaxPixels = 5e7;

  /// @throws std::invalid_argument naming the file: missing, not a raster, no geotransform or
  ///         no CRS, a CRS without a transformation from WGS84, larger than kMaxPixels, or no
  ///         finite elevation at all.
  explicit ElevationModel(const std::filesystem::path& file) : file_(file) {
    const gdal::detail::Dataset d = gdal::detail::open(file);
    {
      const gdal::detail::QuietErrors quiet;
      if (d->GetGeoTransform(gt_.data()) != CE_None)
        gdal::detail::fail(file, "the DEM has no geotransform (georeference it, e.g. gdal_translate -a_srs -a_ullr)");
    }
    for (double v : gt_)
      if (!std::isfinite(v)) gdal::detail::fail(file, "the DEM's geotransform is not finite");
    if (!GDALInvGeoTransform(gt_.data(), inverse_.data()))
      gdal::detail::fail(file, "the DEM's geotransform cannot be inverted (pixels of no area)");
    width_ = d->GetRasterXSize();
    height_ = d->GetRasterYSize();
    if (static_cast<double>(width_) * height_ > kMaxPixels)
      gdal::detail::fail(file, "the DEM has " + std::to_string(width_) + " x " + std::to_string(height_) +
                                   " pixels, more than the 50000000 read: crop it to the site, e.g. gdal_translate "
                                   "-projwin ULX ULY LRX LRY");
    const OGRSpatialReference* srs = d->GetSpatialRef();
    if (srs == nullptr || srs->IsEmpty()) gdal::detail::fail(file, "the DEM has no coordinate reference system");
    crs_ = *srs;
    crs_.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    wgs84_.SetWellKnownGeogCS("WGS84");
    wgs84_.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    {
      const gdal::detail::QuietErrors quiet;
      to_dem_.reset(OGRCreateCoordinateTransformation(&wgs84_, &crs_));
      to_wgs84_.reset(OGRCreateCoordinateTransformation(&crs_, &wgs84_));
    }
    if (!to_dem_ || !to_wgs84_)
      gdal::detail::fail(file,
                         "no transformation between WGS84 and the DEM's CRS (" + gdal::detail::last_error() + ")");
    GDALRasterBand* band = d->GetRasterBand(1);
    z_ = cv::Mat(height_, width_, CV_32FC1);
    {
      const gdal::detail::QuietErrors quiet;
      CPLErrorReset();
      if (band->RasterIO(GF_Read, 0, 0, width_, height_, z_.ptr(), width_, height_, GDT_Float32, 0, 0) != CE_None)
        gdal::detail::fail(file, "cannot read the DEM's band 1 (" + gdal::detail::last_error() + ")");
    }
    int has_nodata = 0;
    const double nodata = band->GetNoDataValue(&has_nodata);
    bool any = false;
    for (int r = 0; r < height_; ++r) {
      float* row = z_.ptr<float>(r);
      for (int c = 0; c < width_; ++c) {
        if (!std::isfinite(row[c]) ||
            (has_nodata && static_cast<double>(row[c]) == static_cast<double>(static_cast<float>(nodata))))
          row[c] = std::numeric_limits<float>::quiet_NaN();
        else
          any = true;
      }
    }
    if (!any) gdal::detail::fail(file, "the DEM has no elevation: every pixel is nodata");
  }

  ElevationModel(ElevationModel&&) noexcept = default;
  ElevationModel& operator=(ElevationModel&&) noexcept = default;
  ElevationModel(const ElevationModel&) = delete;
  ElevationModel& operator=(const ElevationModel&) = delete;
  ~ElevationModel() = default;

  [[nodiscard]] const std::filesystem::path& file() const noexcept { return file_; }

  /// The ground elevation [m, the DEM's datum] at (`latitude_deg`, `longitude_deg`), bilinear
  /// between the four nearest pixel centres (the nearest pixel within half a pixel of the
  /// raster's border); empty outside the raster or next to a pixel without elevation.
  [[nodiscard]] std::optional<double> elevation_m(double latitude_deg, double longitude_deg) const {
    double x = longitude_deg, y = latitude_deg;
    if (!std::isfinite(x) || !std::isfinite(y) || !to_dem_->Transform(1, &x, &y)) return std::nullopt;
    const double col = inverse_[0] + inverse_[1] * x + inverse_[2] * y;
    const double row = inverse_[3] + inverse_[4] * x + inverse_[5] * y;
    if (!(col >= 0.0 && col <= width_ && row >= 0.0 && row <= height_)) return std::nullopt;
    // Between pixel centres, clamped to the raster.
    const double u = std::clamp(col - 0.5, 0.0, static_cast<double>(width_ - 1));
    const double v = std::clamp(row - 0.5, 0.0, static_cast<double>(height_ - 1));
    const int c0 = std::min(static_cast<int>(u), width_ - 1), r0 = std::min(static_cast<int>(v), height_ - 1);
    const int c1 = std::min(c0 + 1, width_ - 1), r1 = std::min(r0 + 1, height_ - 1);
    const double fu = u - c0, fv = v - r0;
    const double w[4] = {(1 - fu) * (1 - fv), fu * (1 - fv), (1 - fu) * fv, fu * fv};
    const float z[4] = {z_.at<float>(r0, c0), z_.at<float>(r0, c1), z_.at<float>(r1, c0), z_.at<float>(r1, c1)};
    double sum = 0.0;
    for (int k = 0; k < 4; ++k) {
      if (w[k] == 0.0) continue;
      if (std::isnan(z[k])) return std::nullopt;
      sum += w[k] * z[k];
    }
    return sum;
  }

  /// The centre of the raster's extent in WGS84 (altitude 0).
  [[nodiscard]] GeoPoint centre() const { return pixel_wgs84(0.5 * width_, 0.5 * height_); }

  /// Half the diagonal of the raster's extent [m] (on the ellipsoid, corner to corner).
  [[nodiscard]] double radius_m() const {
    const GeoPoint a = pixel_wgs84(0.0, 0.0), b = pixel_wgs84(width_, height_);
    double s12 = 0.0;
    GeographicLib::Geodesic::WGS84().Inverse(a.latitude_deg, a.longitude_deg, b.latitude_deg, b.longitude_deg, s12);
    return 0.5 * s12;
  }

 private:
  [[nodiscard]] GeoPoint pixel_wgs84(double col, double row) const {
    double x = gt_[0] + col * gt_[1] + row * gt_[2], y = gt_[3] + col * gt_[4] + row * gt_[5];
    if (!to_wgs84_->Transform(1, &x, &y)) return {std::numeric_limits<double>::quiet_NaN(), x, 0.0};
    return {y, x, 0.0};
  }

  struct CtDeleter {
    void operator()(OGRCoordinateTransformation* t) const noexcept { OGRCoordinateTransformation::DestroyCT(t); }
  };
  std::filesystem::path file_;
  std::array<double, 6> gt_{};
  std::array<double, 6> inverse_{};
  int width_ = 0;
  int height_ = 0;
  OGRSpatialReference crs_;
  OGRSpatialReference wgs84_;
  std::unique_ptr<OGRCoordinateTransformation, CtDeleter> to_dem_;
  std::unique_ptr<OGRCoordinateTransformation, CtDeleter> to_wgs84_;
  cv::Mat z_;  ///< CV_32FC1, NaN: no elevation
};

/// What follow_terrain() found under a path.
struct TerrainFollowing {
  double home_ground_m = 0.0;       ///< the DEM's elevation at home [m]
  std::vector<double> ground_m;     ///< per waypoint: the mean elevation under its footprint [m]
  std::vector<double> clearance_m;  ///< per waypoint: its height above the highest ground under its footprint [m]
  double highest_rise_m = 0.0;  ///< the highest ground under any footprint, above home's [m] (what a return must clear)

  /// The lowest of clearance_m (infinity for no waypoint).
  [[nodiscard]] double lowest_clearance_m() const {
    double low = std::numeric_limits<double>::infinity();
    for (double c : clearance_m) low = std::min(low, c);
    return low;
  }
};

/// Sets every waypoint's z [m above home, the altitude a MAV_FRAME_GLOBAL_RELATIVE_ALT item
/// flies] to `height_m` above the *mean* DEM elevation under its footprint, less the elevation at
/// home: z = height + mean ground(footprint) - ground(home). The footprint is sampled on a
/// `samples` x `samples` grid of cell centres through `frame` (the site frame in WGS84).
///
/// Why the mean: the GSD is the camera's distance to the ground over its focal length, and an
/// image's GSD is what the mission's decisions assume for the whole footprint; on a plane slope
/// the mean ground under the footprint is the ground at its centre, so the GSD holds there
/// exactly and within (relief within the footprint / 2) / height elsewhere, evenly above and
/// below. The maximum would make every image on a slope coarser than asked. What the maximum
/// is for, not hitting the ground, is checked apart: TerrainFollowing::clearance_m is each
/// waypoint's height above the highest ground under its footprint.
/// @throws std::invalid_argument if the DEM has no elevation at home or under a footprint
///         (naming the waypoint and where), `height_m` is not positive, or `samples` < 1.
inline TerrainFollowing follow_terrain(std::vector<Waypoint>& path, const GeoReference& frame,
                                       const Eigen::Vector2d& home_xy, const ElevationModel& dem, double height_m,
                                       int samples = 9) {
  detail::require_positive(height_m, "follow_terrain: height_m");
  detail::require(samples >= 1, "follow_terrain: samples must be >= 1", samples);
  const auto at = [&](const Eigen::Vector2d& xy) {
    const GeoPoint g = frame.to_wgs84(Eigen::Vector3d(xy.x(), xy.y(), 0.0));
    return std::make_pair(dem.elevation_m(g.latitude_deg, g.longitude_deg), g);
  };
  TerrainFollowing out;
  const auto [home_z, home_g] = at(home_xy);
  if (!home_z)
    throw std::invalid_argument("the DEM '" + dem.file().string() + "' has no elevation at the take-off point (" +
                                gdal::detail::num(home_g.latitude_deg) + ", " +
                                gdal::detail::num(home_g.longitude_deg) + ")");
  out.home_ground_m = *home_z;
  out.highest_rise_m = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < path.size(); ++i) {
    const Area& f = path[i].footprint;
    double sum = 0.0, highest = -std::numeric_limits<double>::infinity();
    for (int a = 0; a < samples; ++a)
      for (int b = 0; b < samples; ++b) {
        const Eigen::Vector2d xy(f.x_min_m + (a + 0.5) / samples * f.width_m(),
                                 f.y_min_m + (b + 0.5) / samples * f.height_m());
        const auto [z, g] = at(xy);
        if (!z)
          throw std::invalid_argument("the DEM '" + dem.file().string() + "' has no elevation under waypoint " +
                                      std::to_string(i) + "'s footprint, at (" + gdal::detail::num(g.latitude_deg) +
                                      ", " + gdal::detail::num(g.longitude_deg) + ")");
        sum += *z;
        highest = std::max(highest, *z);
      }
    const double mean = sum / (samples * samples);
    path[i].position.z() = height_m + mean - out.home_ground_m;
    out.ground_m.push_back(mean);
    out.clearance_m.push_back(path[i].position.z() + out.home_ground_m - highest);
    out.highest_rise_m = std::max(out.highest_rise_m, highest - out.home_ground_m);
  }
  return out;
}

/// The lowest height [m] above the DEM's ground along the straight legs through `points`
/// (site-frame positions, z relative to home, whose ground is `home_ground_m`), sampled every
/// `step_m` metres and at each point; where the DEM has no elevation the leg is not checked.
/// `where` gets the index of the leg's start with the lowest height.
[[nodiscard]] inline double lowest_leg_clearance_m(const std::vector<Eigen::Vector3d>& points,
                                                   const GeoReference& frame, const ElevationModel& dem,
                                                   double home_ground_m, double step_m, std::size_t* where = nullptr) {
  detail::require_positive(step_m, "lowest_leg_clearance_m: step_m");
  double low = std::numeric_limits<double>::infinity();
  for (std::size_t k = 1; k < points.size(); ++k) {
    const Eigen::Vector3d a = points[k - 1], b = points[k];
    const int n = std::max(1, static_cast<int>(std::ceil((b - a).head<2>().norm() / step_m)));
    for (int s = 0; s <= n; ++s) {
      const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(s) / n);
      const GeoPoint g = frame.to_wgs84(Eigen::Vector3d(p.x(), p.y(), 0.0));
      const auto z = dem.elevation_m(g.latitude_deg, g.longitude_deg);
      if (!z) continue;
      const double clearance = p.z() + home_ground_m - *z;
      if (clearance < low) {
        low = clearance;
        if (where != nullptr) *where = k - 1;
      }
    }
  }
  return low;
}

}  // namespace adaptseg
