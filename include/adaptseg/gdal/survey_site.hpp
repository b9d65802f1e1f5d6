#pragma once
/// @file
/// A site to survey as a field engineer has it before any label (ground nobody has labelled):
/// the area as a polygon (GeoJSON, KML, or any vector file GDAL's OGR reads) or an
/// orthomosaic without labels (its pixels with data). Turned into a site frame and the
/// SurveyArea the planners take (the rectangle to cover and, as its valid mask, where the site
/// is). The lawnmower laid to cover it is site_lawnmower.hpp's, the outline as a geofence
/// site_fence.hpp's. CMake target adaptseg::gdal.

#include <adaptseg/core/error.hpp>
#include <adaptseg/core/lawnmower_planner.hpp>
#include <adaptseg/gdal/gdal_io.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/geo/mission_export.hpp>
#include <adaptseg/vision/adaptive_options.hpp>
#include <adaptseg/vision/image.hpp>

#include <GeographicLib/Geodesic.hpp>
#include <GeographicLib/LocalCartesian.hpp>
#include <ogrsf_frmts.h>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <filesystem>
#include <limits>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg {

namespace detail {

/// True if `xy` lies inside an odd number of `rings` (closed or not; on an edge: either way).
inline bool even_odd_contains(const std::vector<std::vector<Eigen::Vector2d>>& rings, const Eigen::Vector2d& xy) {
  bool inside = false;
  for (const auto& r : rings)
    for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++)
      if ((r[i].y() > xy.y()) != (r[j].y() > xy.y()) &&
          xy.x() < (r[j].x() - r[i].x()) * (xy.y() - r[i].y()) / (r[j].y() - r[i].y()) + r[i].x())
        inside = !inside;
  return inside;
}

}  // namespace detail

/// A site: its frame on the Earth and the ground to cover in it.
struct SurveySite {
  std::string name;  ///< the file's stem
  /// The site frame: x along the longer side of the area's smallest enclosing rectangle, y across
  /// it, origin at that rectangle's corner; `anchor_x_m`, `anchor_y_m` the frame position of the
  /// area's centre (`latitude_deg`, `longitude_deg`), on a plane at `altitude_m`.
  FieldGeo geo;
  /// The rectangle [0, width] x [0, height] of the frame, the map GSD, and as valid mask the
  /// site's pixels (the polygon rasterised, or the orthomosaic's pixels with data).
  SurveyArea area;
  /// The area's outline in the site frame [m], one ring after another (holes included): what
  /// the plan must cover. A point is on the site when it lies inside an odd number of rings
  /// (even-odd, as the mask is filled).
  std::vector<std::vector<Eigen::Vector2d>> rings;
  /// `holes[i]`: ring i is an inner ring of its polygon (a hole: a pond, a building); the
  /// others are outer rings. One flag per ring.
  std::vector<bool> holes;

  /// True if `xy` [m, site frame] lies on the site: inside an odd number of rings (on an edge:
  /// either way).
  [[nodiscard]] bool contains(const Eigen::Vector2d& xy) const { return detail::even_odd_contains(rings, xy); }

  /// Distance [m] from `xy` to the nearest edge of any ring (outer or hole).
  [[nodiscard]] double distance_to_edge_m(const Eigen::Vector2d& xy) const {
    double best = std::numeric_limits<double>::infinity();
    for (const auto& r : rings)
      for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++) {
        const Eigen::Vector2d a = r[j], ab = r[i] - r[j];
        const double len2 = ab.squaredNorm();
        const double t = len2 > 0.0 ? std::clamp((xy - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
        best = std::min(best, (a + t * ab - xy).norm());
      }
    return best;
  }

  /// True if `xy` lies on the site at least `margin_m` from every edge.
  [[nodiscard]] bool contains(const Eigen::Vector2d& xy, double margin_m) const {
    return contains(xy) && distance_to_edge_m(xy) >= margin_m;
  }

  /// The site's area [m^2]: its outer rings' less its holes' (shoelace, in the site frame).
  [[nodiscard]] double area_m2() const {
    double a = 0.0;
    for (std::size_t k = 0; k < rings.size(); ++k) {
      const auto& r = rings[k];
      double twice = 0.0;
      for (std::size_t i = 0, j = r.size() - 1; i < r.size(); j = i++)
        twice += r[j].x() * r[i].y() - r[i].x() * r[j].y();
      a += (k < holes.size() && holes[k] ? -0.5 : 0.5) * std::abs(twice);
    }
    return std::max(0.0, a);
  }

  /// The centre of the area's extent (the frame's anchor) in WGS84, at the frame plane's height.
  [[nodiscard]] GeoPoint centre() const { return {geo.latitude_deg, geo.longitude_deg, geo.altitude_m}; }

  /// Half the diagonal of the area's rectangle [m]: every point of the site lies within this of
  /// centre().
  [[nodiscard]] double radius_m() const { return 0.5 * std::hypot(area.area.width_m(), area.area.height_m()); }

  /// The frame as a field.yaml `geo:` section (anchor at the origin, the rectangle's corner;
  /// heading the bearing of +x there): what a field of this site's labelled images declares.
  /// Equals `geo` to within a millimetre over a few kilometres (two tangent planes a site apart).
  [[nodiscard]] FieldGeo origin_geo() const {
    const GeoReference frame(geo);
    const GeoPoint o = frame.to_wgs84(Eigen::Vector3d::Zero());
    const GeoPoint ahead = frame.to_wgs84(Eigen::Vector3d(std::max(1.0, area.area.width_m()), 0.0, 0.0));
    double distance_m = 0.0, azimuth_deg = 0.0, azimuth_there_deg = 0.0;
    GeographicLib::Geodesic::WGS84().Inverse(o.latitude_deg, o.longitude_deg, ahead.latitude_deg, ahead.longitude_deg,
                                             distance_m, azimuth_deg, azimuth_there_deg);
    return FieldGeo{o.latitude_deg,
                    o.longitude_deg,
                    geo.altitude_m,
                    azimuth_deg < 0.0 ? azimuth_deg + 360.0 : azimuth_deg,
                    0.0,
                    0.0,
                    1.0};
  }
};

namespace detail {

/// The smallest-area enclosing rectangle of `points` (the convex hull's edges as candidate
/// directions): the angle of its longer side [rad, counter-clockwise from +x].
inline double enclosing_rectangle_angle(const std::vector<Eigen::Vector2d>& points) {
  // OpenCV's hull takes floats: about the points' mean, a millimetre at 10 km.
  Eigen::Vector2d mean = Eigen::Vector2d::Zero();
  for (const auto& q : points) mean += q / static_cast<double>(points.size());
  std::vector<cv::Point2f> p;
  for (const auto& q : points)
    p.emplace_back(static_cast<float>(q.x() - mean.x()), static_cast<float>(q.y() - mean.y()));
  const cv::RotatedRect r = cv::minAreaRect(p);
  cv::Point2f v[4];
  r.points(v);
  const cv::Point2f a = v[1] - v[0], b = v[2] - v[1];
  const cv::Point2f longer = std::hypot(a.x, a.y) >= std::hypot(b.x, b.y) ? a : b;
  return std::atan2(longer.y, longer.x);
}

/// The mask of a site whose frame extends `width_m` x `height_m` at `map_gsd_cm`.
/// @throws std::invalid_argument for more than 4e8 pixels, naming the coarsest GSD that fits.
[[nodiscard]] inline cv::Size site_mask_size(double width_m, double height_m, double map_gsd_cm) {
  const double px = 100.0 / map_gsd_cm;
  const double cols_d = std::ceil(width_m * px - 1e-9), rows_d = std::ceil(height_m * px - 1e-9);
  if (constexpr double kMaxPixels = 4e8; cols_d * rows_d > kMaxPixels) {
    // The coarsest GSD, to a millimetre, whose mask fits.
    const double fits_cm = std::ceil(map_gsd_cm * std::sqrt(cols_d * rows_d / kMaxPixels) * 10.0 + 1e-9) / 10.0;
    throw std::invalid_argument("the site's mask at " + gdal::detail::num(map_gsd_cm) + " cm/px would be " +
                                std::to_string(static_cast<long long>(cols_d)) + " x " +
                                std::to_string(static_cast<long long>(rows_d)) + " = " +
                                std::to_string(static_cast<long long>(cols_d * rows_d)) +
                                " pixels, more than the 400000000 allowed: a map GSD of at least " +
                                gdal::detail::num(fits_cm) + " cm/px fits (--map-gsd-cm)");
  }
  return {static_cast<int>(cols_d), static_cast<int>(rows_d)};
}

/// The site of `rings_enu` (east, north [m] about the tangent point `origin`; `holes[i]`: ring i
/// is an inner ring): the frame along the enclosing rectangle's longer side, the mask
/// rasterised at `map_gsd_cm`.
inline SurveySite site_from_rings(std::string name, const GeoPoint& origin, double altitude_m,
                                  const std::vector<std::vector<Eigen::Vector2d>>& rings_enu,
                                  const std::vector<bool>& holes, double map_gsd_cm) {
  std::vector<Eigen::Vector2d> all;
  for (const auto& r : rings_enu) all.insert(all.end(), r.begin(), r.end());
  require(all.size() >= 3, "the area needs a polygon of at least 3 points; points", all.size());
  const double angle = enclosing_rectangle_angle(all);  // of +x, from east, counter-clockwise
  const double c = std::cos(angle), s = std::sin(angle);
  const auto rotate = [&](const Eigen::Vector2d& e) {
    return Eigen::Vector2d(c * e.x() + s * e.y(), -s * e.x() + c * e.y());
  };
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  for (const auto& e : all) {
    const Eigen::Vector2d q = rotate(e);
    x0 = std::min(x0, q.x()), y0 = std::min(y0, q.y()), x1 = std::max(x1, q.x()), y1 = std::max(y1, q.y());
  }
  require(x1 - x0 > 0.0 && y1 - y0 > 0.0, "the area has no extent [m^2]", (x1 - x0) * (y1 - y0));
  SurveySite site;
  site.name = std::move(name);
  // +x at compass bearing 90 - angle [deg]; the tangent point (0, 0 east-north) at -(x0, y0).
  site.geo = FieldGeo{origin.latitude_deg,
                      origin.longitude_deg,
                      altitude_m,
                      std::remainder(90.0 - angle * 180.0 / std::numbers::pi, 360.0),
                      -x0,
                      -y0,
                      1.0};
  if (site.geo.heading_deg < 0.0) site.geo.heading_deg += 360.0;
  site.area.area = {0.0, 0.0, x1 - x0, y1 - y0};
  site.area.map_gsd_cm = map_gsd_cm;
  const double px = 100.0 / map_gsd_cm;
  const cv::Size mask_size = site_mask_size(x1 - x0, y1 - y0, map_gsd_cm);
  const int cols = mask_size.width, rows = mask_size.height;
  site.area.valid_mask = cv::Mat(rows, cols, CV_8UC1, cv::Scalar(0));
  // Each ring in the frame, and filled even-odd (an inner ring, a hole, stays out).
  for (std::size_t k = 0; k < rings_enu.size(); ++k) {
    const auto& r = rings_enu[k];
    std::vector<Eigen::Vector2d> ring;
    std::vector<cv::Point> poly;
    for (const auto& e : r) {
      ring.push_back(rotate(e) - Eigen::Vector2d(x0, y0));
      poly.emplace_back(static_cast<int>(std::lround(ring.back().x() * px)),
                        static_cast<int>(std::lround(rows - ring.back().y() * px)));
    }
    cv::Mat ring_mask(rows, cols, CV_8UC1, cv::Scalar(0));
    cv::fillPoly(ring_mask, std::vector<std::vector<cv::Point>>{poly}, cv::Scalar(255));
    cv::bitwise_xor(site.area.valid_mask, ring_mask, site.area.valid_mask);
    site.rings.push_back(std::move(ring));
    site.holes.push_back(k < holes.size() && holes[k]);
  }
  require(cv::countNonZero(site.area.valid_mask) > 0,
          "the area covers no pixel of the site's mask (a polygon without area, or one smaller than map_gsd_cm); "
          "its enclosing rectangle [m^2]",
          (x1 - x0) * (y1 - y0));
  return site;
}

/// The site from WGS84 rings (longitude, latitude; `holes` as site_from_rings): the tangent
/// plane at the centre of their extent, then site_from_rings.
inline SurveySite site_from_wgs84(const std::string& where, std::string name,
                                  const std::vector<std::vector<Eigen::Vector2d>>& rings,
                                  const std::vector<bool>& holes, double map_gsd_cm, double altitude_m) {
  for (const auto& r : rings)
    for (const auto& p : r) {
      if (std::isfinite(p.x()) && std::isfinite(p.y()) && std::abs(p.y()) <= 90.0 && std::abs(p.x()) <= 180.0) continue;
      // A latitude beyond 90 whose longitude would be a latitude: most likely swapped.
      const bool swapped =
          std::isfinite(p.x()) && std::isfinite(p.y()) && std::abs(p.y()) <= 180.0 && std::abs(p.x()) <= 90.0;
      throw std::invalid_argument(where + ": longitude, latitude out of range: (" + gdal::detail::num(p.x()) + ", " +
                                  gdal::detail::num(p.y()) + ")" +
                                  (swapped
                                       ? ": are latitude and longitude swapped? GeoJSON and KML list longitude first"
                                       : ": coordinates in metres need the file's CRS declared"));
    }
  double lon0 = rings[0][0].x(), lon1 = lon0, lat0 = rings[0][0].y(), lat1 = lat0;
  for (const auto& r : rings)
    for (const auto& p : r)
      lon0 = std::min(lon0, p.x()), lon1 = std::max(lon1, p.x()), lat0 = std::min(lat0, p.y()),
      lat1 = std::max(lat1, p.y());
  const GeoPoint centre{0.5 * (lat0 + lat1), 0.5 * (lon0 + lon1), altitude_m};
  const GeographicLib::LocalCartesian plane(centre.latitude_deg, centre.longitude_deg, altitude_m);
  std::vector<std::vector<Eigen::Vector2d>> enu;
  for (const auto& r : rings) {
    auto& e = enu.emplace_back();
    for (const auto& p : r) {
      double x = 0, y = 0, z = 0;
      plane.Forward(p.y(), p.x(), altitude_m, x, y, z);
      e.emplace_back(x, y);
    }
  }
  try {
    return site_from_rings(std::move(name), centre, altitude_m, enu, holes, map_gsd_cm);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(where + ": " + e.what());
  }
}

/// The outline of an orthomosaic's pixels with data (alpha > 0, not the bands' nodata), in WGS84.
inline std::vector<std::vector<Eigen::Vector2d>> raster_outline(const std::filesystem::path& file,
                                                                const std::string& where) {
  const gdal::detail::Dataset d = gdal::detail::open(file);
  const gdal::RasterGrid grid = gdal::detail::grid_of(*d, file);
  cv::Mat data(grid.height_px, grid.width_px, CV_8UC1, cv::Scalar(255));
  if (d->GetRasterCount() >= 4 && d->GetRasterBand(4)->GetColorInterpretation() == GCI_AlphaBand)
    data = gdal::detail::read_interleaved(*d, file, {4}) > 0;
  bool all_nodata = d->GetRasterCount() >= 3;
  for (int b = 1; b <= 3 && all_nodata; ++b) all_nodata = gdal::detail::nodata_byte(*d, b, file).has_value();
  if (all_nodata) {
    const cv::Mat rgb = gdal::detail::read_interleaved(*d, file, {1, 2, 3});
    const int n0 = *gdal::detail::nodata_byte(*d, 1, file), n1 = *gdal::detail::nodata_byte(*d, 2, file),
              n2 = *gdal::detail::nodata_byte(*d, 3, file);
    cv::Mat is_nodata;
    cv::inRange(rgb, cv::Scalar(n0, n1, n2), cv::Scalar(n0, n1, n2), is_nodata);
    data.setTo(0, is_nodata);
  }
  std::vector<std::vector<cv::Point>> contours;
  cv::findContours(data, contours, cv::RETR_EXTERNAL, cv::CHAIN_APPROX_SIMPLE);
  if (contours.empty()) throw std::invalid_argument(where + ": the orthomosaic has no pixel with data");
  const gdal::detail::CrsToWgs84 to_wgs84(grid.crs_wkt, file);
  std::vector<std::vector<Eigen::Vector2d>> rings;
  for (const auto& c : contours) {
    auto& r = rings.emplace_back();
    for (const cv::Point& p : c) {
      // The pixel's outer corners are what the contour's pixel centres stand for: half a pixel of
      // margin, negligible against a footprint.
      const double e = grid.geotransform[0] + (p.x + 0.5) * grid.geotransform[1];
      const double n = grid.geotransform[3] + (p.y + 0.5) * grid.geotransform[5];
      const auto [lat, lon] = to_wgs84(e, n);
      r.emplace_back(lon, lat);
    }
  }
  return rings;
}

/// Longitude, latitude of every ring of every Polygon and MultiPolygon of `layer`, in WGS84,
/// into `rings`; which are holes into `holes`.
/// @throws std::invalid_argument (prefixed `where`) for a CRS or a point that does not transform.
inline void layer_rings(OGRLayer& layer, const std::string& where, std::vector<std::vector<Eigen::Vector2d>>& rings,
                        std::vector<bool>& holes) {
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation, void (*)(OGRCoordinateTransformation*)> to_wgs84(
      nullptr, [](OGRCoordinateTransformation* t) { OGRCoordinateTransformation::DestroyCT(t); });
  if (const OGRSpatialReference* srs = layer.GetSpatialRef(); srs != nullptr && !srs->IsSame(&wgs84)) {
    OGRSpatialReference src(*srs);
    src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to_wgs84.reset(OGRCreateCoordinateTransformation(&src, &wgs84));
    if (!to_wgs84) throw std::invalid_argument(where + ": its CRS has no transformation to WGS84");
  }
  const auto add_polygon = [&](const OGRPolygon& poly) {
    for (int k = -1; k < poly.getNumInteriorRings(); ++k) {
      const OGRLinearRing* ring = k < 0 ? poly.getExteriorRing() : poly.getInteriorRing(k);
      if (ring == nullptr || ring->getNumPoints() < 3) continue;
      std::vector<Eigen::Vector2d> r;
      for (int i = 0; i < ring->getNumPoints(); ++i) {
        double x = ring->getX(i), y = ring->getY(i);
        if (to_wgs84 && !to_wgs84->Transform(1, &x, &y))
          throw std::invalid_argument(where + ": a point does not transform to WGS84");
        r.emplace_back(x, y);
      }
      rings.push_back(std::move(r));
      holes.push_back(k >= 0);
    }
  };
  layer.ResetReading();
  for (OGRFeature* f; (f = layer.GetNextFeature()) != nullptr; OGRFeature::DestroyFeature(f)) {
    const OGRGeometry* g = f->GetGeometryRef();
    if (g == nullptr) continue;
    const auto type = wkbFlatten(g->getGeometryType());
    if (type == wkbPolygon) add_polygon(*g->toPolygon());
    if (type == wkbMultiPolygon)
      for (const OGRPolygon* p : *g->toMultiPolygon()) add_polygon(*p);
  }
}

}  // namespace detail

/// The site of an area file: the polygons of a vector file (GeoJSON, KML, Shapefile, ...: any
/// layer GDAL's OGR reads; every Polygon and MultiPolygon of its first layer, holes kept out), in
/// any CRS OGR can transform to WGS84, or an orthomosaic without labels (a raster in a projected
/// CRS: the outline of its pixels with data, i.e. alpha > 0 and not its bands' nodata). The
/// frame's plane is at `altitude_m` (the take-off height above the ellipsoid, as a field's
/// `geo:` `altitude_m`); the mask at `map_gsd_cm`.
/// @throws std::invalid_argument naming the file for one that is missing or unreadable, no
///         polygon (or no pixel with data), a CRS without a transformation to WGS84, or an area
///         too small or too large.
[[nodiscard]] inline SurveySite load_survey_site(const std::filesystem::path& file, double map_gsd_cm = 10.0,
                                                 double altitude_m = 0.0) {
  detail::require_positive(map_gsd_cm, "load_survey_site: map_gsd_cm");
  gdal::detail::register_drivers();
  const std::string where = "survey area '" + file.string() + "'";
  if (!std::filesystem::is_regular_file(file)) throw std::invalid_argument(where + ": file not found");
  gdal::detail::Dataset d;
  {
    const gdal::detail::QuietErrors quiet;
    d.reset(GDALDataset::Open(file.c_str(), GDAL_OF_VECTOR | GDAL_OF_READONLY));
  }
  if (!d) {
    bool raster = false;
    {
      const gdal::detail::QuietErrors quiet;
      raster = gdal::detail::Dataset(GDALDataset::Open(file.c_str(), GDAL_OF_RASTER | GDAL_OF_READONLY)) != nullptr;
    }
    if (!raster) throw std::invalid_argument(where + ": neither a vector file nor a raster GDAL reads");
    const auto outline = detail::raster_outline(file, where);  // outer contours only: no holes
    return detail::site_from_wgs84(where, file.stem().string(), outline, std::vector<bool>(outline.size(), false),
                                   map_gsd_cm, altitude_m);
  }
  if (d->GetLayerCount() < 1) throw std::invalid_argument(where + ": no layer");
  std::vector<std::vector<Eigen::Vector2d>> rings;
  std::vector<bool> holes;
  detail::layer_rings(*d->GetLayer(0), where, rings, holes);
  if (rings.empty())
    throw std::invalid_argument(where + ": no polygon in its first layer (an area is a Polygon or MultiPolygon)");
  return detail::site_from_wgs84(where, file.stem().string(), rings, holes, map_gsd_cm, altitude_m);
}

/// Distance [m] between two WGS84 points on the ellipsoid.
[[nodiscard]] inline double geodesic_distance_m(const GeoPoint& a, const GeoPoint& b) {
  double s12 = 0.0;
  GeographicLib::Geodesic::WGS84().Inverse(a.latitude_deg, a.longitude_deg, b.latitude_deg, b.longitude_deg, s12);
  return s12;
}

/// True if `site` lies farther than `radius_m` (plus its own radius) from `p`, but would lie
/// within that reach with its latitude and longitude swapped (or, the same, `p` swapped would):
/// a sign that one of the two was written in the other order (GeoJSON and KML list longitude
/// first; a LAT,LON option latitude first).
[[nodiscard]] inline bool looks_swapped(const SurveySite& site, const GeoPoint& p, double radius_m) {
  const GeoPoint c = site.centre();
  if (std::abs(c.longitude_deg) > 90.0) return false;  // swapped, no latitude
  const double reach = radius_m + site.radius_m();
  const GeoPoint swapped{c.longitude_deg, c.latitude_deg, c.altitude_m};
  return geodesic_distance_m(c, p) > reach && geodesic_distance_m(swapped, p) <= reach;
}

}  // namespace adaptseg
