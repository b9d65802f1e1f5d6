#pragma once
/// @file
/// A site to survey as a field engineer has it before any label (ground nobody has labelled):
/// the area as a polygon (GeoJSON, KML, or any vector file GDAL's OGR reads) or an
/// orthomosaic without labels (its pixels with data). Turned into a site frame and the
/// SurveyArea the planners take (the rectangle to cover and, as its valid mask, where the site
/// is), and a lawnmower laid to cover it: the grid centred on the site, every waypoint moved at
/// least a margin inside the site's outline (and out of its holes), and the outline as a
/// geofence. CMake target adaptseg::gdal.

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
  const double cols_d = std::ceil((x1 - x0) * px - 1e-9), rows_d = std::ceil((y1 - y0) * px - 1e-9);
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
  const int cols = static_cast<int>(cols_d), rows = static_cast<int>(rows_d);
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
  OGRLayer* layer = d->GetLayer(0);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation, void (*)(OGRCoordinateTransformation*)> to_wgs84(
      nullptr, [](OGRCoordinateTransformation* t) { OGRCoordinateTransformation::DestroyCT(t); });
  if (const OGRSpatialReference* srs = layer->GetSpatialRef(); srs != nullptr && !srs->IsSame(&wgs84)) {
    OGRSpatialReference src(*srs);
    src.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
    to_wgs84.reset(OGRCreateCoordinateTransformation(&src, &wgs84));
    if (!to_wgs84) throw std::invalid_argument(where + ": its CRS has no transformation to WGS84");
  }
  // Longitude, latitude of every ring; which are holes.
  std::vector<std::vector<Eigen::Vector2d>> rings;
  std::vector<bool> holes;
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
  layer->ResetReading();
  for (OGRFeature* f; (f = layer->GetNextFeature()) != nullptr; OGRFeature::DestroyFeature(f)) {
    const OGRGeometry* g = f->GetGeometryRef();
    if (g == nullptr) continue;
    const auto type = wkbFlatten(g->getGeometryType());
    if (type == wkbPolygon) add_polygon(*g->toPolygon());
    if (type == wkbMultiPolygon)
      for (const OGRPolygon* p : *g->toMultiPolygon()) add_polygon(*p);
  }
  if (rings.empty())
    throw std::invalid_argument(where + ": no polygon in its first layer (an area is a Polygon or MultiPolygon)");
  return detail::site_from_wgs84(where, file.stem().string(), rings, holes, map_gsd_cm, altitude_m);
}

/// How a site's lawnmower is laid.
struct SiteSurveyOptions {
  LawnmowerOverlap overlap{};  ///< image overlap along and across the rows
  /// How far inside the site's outline every waypoint must lie [m], from outer edges and holes
  /// alike: the waypoint is the footprint's centre (a nadir camera), and a GNSS position error of
  /// a metre or two (the horizontal accuracy of a small UAV's receiver) must not carry the UAV
  /// across the geofence, the outline itself. 0: on the site, to the mask's pixel.
  double inside_margin_m = 2.0;
  /// The lawnmower starts in the grid corner nearest this site-frame point [m] (the take-off
  /// point); empty: the corner (x_min, y_min).
  std::optional<Eigen::Vector2d> start_xy;

  /// @throws std::invalid_argument naming the first invalid member.
  void validate() const {
    detail::require(std::isfinite(inside_margin_m) && inside_margin_m >= 0.0,
                    "SiteSurveyOptions: inside_margin_m must be finite and >= 0", inside_margin_m);
    detail::require(!start_xy || start_xy->allFinite(), "SiteSurveyOptions: start_xy must be finite",
                    start_xy ? start_xy->norm() : 0.0);
  }
};

/// A site's lawnmower and what it leaves out.
struct SiteSurvey {
  std::vector<Waypoint> waypoints;  ///< in visiting order, each at least the margin inside the site
  std::size_t moved = 0;      ///< cells whose centre lay outside (or too near the edge) and whose waypoint moved inward
  std::size_t dropped = 0;    ///< cells with some site under them but no point the margin inside: not flown
  double site_m2 = 0.0;       ///< the site's area on its mask [m^2]
  double uncovered_m2 = 0.0;  ///< the site's area under no footprint [m^2]

  /// Share of the site under a footprint, in [0, 1].
  [[nodiscard]] double coverage() const { return site_m2 > 0.0 ? 1.0 - uncovered_m2 / site_m2 : 0.0; }
};

namespace detail {

/// The site-frame point nearest `c` among the mask's pixels in `rect` that lie at least
/// `margin_m` inside the site (a pixel's distance to the nearest pixel off the site, less the
/// 1.5 pixel a rasterised edge may be off by); empty if there is none.
inline std::optional<Eigen::Vector2d> nearest_inside(const SurveySite& site, const cv::Rect& rect,
                                                     const Eigen::Vector2d& c, double margin_m) {
  const cv::Mat& mask = site.area.valid_mask;
  const double px_m = site.area.map_gsd_cm / 100.0;
  const double need_px = margin_m / px_m + 1.5;
  // The window around `rect`, padded so that every pixel of `rect` sees the edges within need_px;
  // beyond the mask nothing is site.
  const int pad = static_cast<int>(std::ceil(need_px)) + 2;
  const cv::Rect window(rect.x - pad, rect.y - pad, rect.width + 2 * pad, rect.height + 2 * pad);
  cv::Mat sub(window.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect in = window & cv::Rect(0, 0, mask.cols, mask.rows);
  if (in.area() > 0) mask(in).copyTo(sub(in - window.tl()));
  cv::Mat distance;
  cv::distanceTransform(sub != 0, distance, cv::DIST_L2, cv::DIST_MASK_PRECISE);
  const double cx = c.x() / px_m - window.x - 0.5,
               cy = mask.rows - c.y() / px_m - window.y - 0.5;  // c in window pixels
  double best = std::numeric_limits<double>::infinity();
  std::optional<Eigen::Vector2d> out;
  for (int r = pad; r < pad + rect.height; ++r) {
    const float* d = distance.ptr<float>(r);
    for (int col = pad; col < pad + rect.width; ++col) {
      if (d[col] < need_px) continue;
      const double dd = (col - cx) * (col - cx) + (r - cy) * (r - cy);
      if (dd >= best) continue;
      best = dd;
      out = Eigen::Vector2d((window.x + col + 0.5) * px_m, (mask.rows - (window.y + r + 0.5)) * px_m);
    }
  }
  return out;
}

}  // namespace detail

/// The lawnmower that covers `site` at `gsd_cm`: the grid of LawnmowerPlanner centred on the
/// site's rectangle (its overhang split evenly between opposite sides), started in the corner
/// nearest `options.start_xy`, the cells with none of the site under them skipped, and every
/// waypoint at least `options.inside_margin_m` inside the site's outline and outside its holes
/// (the outline's polygon, SurveySite::contains).
///
/// A cell whose centre is not that far inside is *moved*, not dropped: its waypoint goes to the
/// nearest point of its footprint that is (to the mask's pixel), and its footprint with it, so
/// the image still sees the site's edge the cell was laid for. Dropping such cells would leave a
/// strip up to half a footprint wide unmapped along every edge and around every hole; moving
/// them leaves unmapped only what no footprint reaches after the move (a concave corner, a
/// sliver), which SiteSurvey::uncovered_m2 reports. A cell with no point of its footprint the
/// margin inside (a sliver of site under its corner) is dropped and counted.
/// @throws std::invalid_argument for invalid options, or as LawnmowerPlanner::plan.
[[nodiscard]] inline SiteSurvey survey_site(const SurveySite& site, const CameraModel& camera, double gsd_cm,
                                            const SiteSurveyOptions& options = {}) {
  options.validate();
  const LawnmowerPlanner planner(camera, options.overlap);
  const Area grid = planner.centred_grid(site.area.area, gsd_cm);
  const cv::Mat& mask = site.area.valid_mask;
  const cv::Rect full(0, 0, mask.cols, mask.rows);
  const double map_gsd = site.area.map_gsd_cm;
  const auto keep = [&](const Area& a) {
    const cv::Rect r = raster_rect(a, map_gsd, mask.rows) & full;
    return r.area() > 0 && cv::countNonZero(mask(r)) > 0;
  };
  const std::vector<Waypoint> cells =
      planner.plan(grid, gsd_cm, options.start_xy.value_or(Eigen::Vector2d(grid.x_min_m, grid.y_min_m)), keep);
  SiteSurvey out;
  for (Waypoint w : cells) {
    const Eigen::Vector2d c = w.position.head<2>();
    if (!site.contains(c, options.inside_margin_m)) {
      const cv::Rect rect = raster_rect(w.footprint, map_gsd, mask.rows) & full;
      const auto p = detail::nearest_inside(site, rect, c, options.inside_margin_m);
      // The raster's pick, checked against the polygon itself.
      if (!p || !site.contains(*p, options.inside_margin_m)) {
        ++out.dropped;
        continue;
      }
      const Eigen::Vector2d shift = *p - c;
      w.position.head<2>() = *p;
      w.footprint = {w.footprint.x_min_m + shift.x(), w.footprint.y_min_m + shift.y(), w.footprint.x_max_m + shift.x(),
                     w.footprint.y_max_m + shift.y()};
      ++out.moved;
    }
    out.waypoints.push_back(w);
  }
  cv::Mat seen(mask.size(), CV_8UC1, cv::Scalar(0));
  for (const auto& w : out.waypoints) {
    const cv::Rect r = raster_rect(w.footprint, map_gsd, mask.rows) & full;
    if (r.area() > 0) seen(r).setTo(255);
  }
  const double px_m2 = (map_gsd / 100.0) * (map_gsd / 100.0);
  out.site_m2 = cv::countNonZero(mask) * px_m2;
  cv::Mat unseen;
  cv::bitwise_and(mask, ~seen, unseen);
  out.uncovered_m2 = cv::countNonZero(unseen) * px_m2;
  return out;
}

/// survey_site()'s waypoints with `overlap` and the default margin (2 m inside), from the
/// corner (x_min, y_min).
/// @throws std::invalid_argument as LawnmowerPlanner::plan.
[[nodiscard]] inline std::vector<Waypoint> plan_site_survey(const SurveySite& site, const CameraModel& camera,
                                                            double gsd_cm, LawnmowerOverlap overlap = {}) {
  SiteSurveyOptions options;
  options.overlap = overlap;
  return survey_site(site, camera, gsd_cm, options).waypoints;
}

/// A site's geofence in its own frame [m]: its rings, simplified to fit, each an inclusion
/// polygon (an outer ring) or an exclusion one (a hole).
struct SiteFence {
  std::vector<std::vector<Eigen::Vector2d>> rings;  ///< not closed (the first vertex not repeated)
  std::vector<bool> inclusion;                      ///< one flag per ring

  /// Vertices of all rings together.
  [[nodiscard]] std::size_t vertices() const {
    std::size_t n = 0;
    for (const auto& r : rings) n += r.size();
    return n;
  }

  /// The fence in WGS84 through the site frame `geo` (altitudes 0: unused).
  [[nodiscard]] std::vector<GeoFencePolygon> wgs84(const FieldGeo& geo) const {
    const GeoReference frame(geo);
    std::vector<GeoFencePolygon> out;
    for (std::size_t k = 0; k < rings.size(); ++k) {
      GeoFencePolygon f;
      f.inclusion = inclusion[k];
      for (const auto& v : rings[k]) {
        GeoPoint g = frame.to_wgs84(Eigen::Vector3d(v.x(), v.y(), 0.0));
        g.altitude_m = 0.0;
        f.vertices.push_back(g);
      }
      out.push_back(std::move(f));
    }
    return out;
  }
};

/// The site's outline as a geofence: each outer ring an inclusion polygon, each hole an
/// exclusion one (the site's polygon, holes and all). Rings with more vertices than
/// `max_vertices` (all together) are simplified (Douglas-Peucker, cv::approxPolyDP) by the
/// smallest tolerance that fits, at most `tolerance_m`: with the tolerance below the inside
/// margin, every waypoint the margin inside stays inside the simplified fence.
/// @throws std::invalid_argument if even `tolerance_m` leaves more than `max_vertices`, naming
///         both counts.
[[nodiscard]] inline SiteFence site_fence(const SurveySite& site,
                                          std::size_t max_vertices = std::numeric_limits<std::size_t>::max(),
                                          double tolerance_m = 0.0) {
  SiteFence fence;
  // The rings without a closing repeat of their first vertex (OGR's rings have one).
  for (std::size_t k = 0; k < site.rings.size(); ++k) {
    auto& q = fence.rings.emplace_back(site.rings[k]);
    while (q.size() > 3 && (q.back() - q.front()).norm() < 1e-9) q.pop_back();
    fence.inclusion.push_back(!(k < site.holes.size() && site.holes[k]));
  }
  if (fence.vertices() <= max_vertices) return fence;
  const auto simplified = [&](double epsilon) {
    SiteFence out{{}, fence.inclusion};
    for (const auto& r : fence.rings) {
      // Floats about the ring's first vertex: sub-millimetre over kilometres.
      std::vector<cv::Point2f> p, q;
      for (const auto& v : r)
        p.emplace_back(static_cast<float>(v.x() - r[0].x()), static_cast<float>(v.y() - r[0].y()));
      cv::approxPolyDP(p, q, epsilon, true);
      auto& o = out.rings.emplace_back();
      if (q.size() < 3) {  // a ring smaller than the tolerance: keep a triangle of it
        for (std::size_t k : {std::size_t{0}, r.size() / 3, 2 * r.size() / 3}) o.push_back(r[k]);
        continue;
      }
      for (const auto& v : q) o.emplace_back(r[0].x() + v.x, r[0].y() + v.y);
    }
    return out;
  };
  if (const SiteFence coarsest = simplified(tolerance_m); coarsest.vertices() > max_vertices)
    throw std::invalid_argument("the site's outline has " + std::to_string(fence.vertices()) + " vertices, and " +
                                std::to_string(coarsest.vertices()) + " simplified by up to " +
                                gdal::detail::num(tolerance_m) + " m: more than the " + std::to_string(max_vertices) +
                                " geofence vertices the autopilot keeps; simplify the polygon (ogr2ogr -simplify) or "
                                "widen the inside margin");
  double lo = 0.0, hi = tolerance_m;  // the smallest tolerance that fits, to 1 % of the largest
  while (hi - lo > 0.01 * tolerance_m) {
    const double mid = 0.5 * (lo + hi);
    if (simplified(mid).vertices() <= max_vertices)
      hi = mid;
    else
      lo = mid;
  }
  return simplified(hi);
}

/// site_fence() in WGS84.
/// @throws std::invalid_argument as site_fence().
[[nodiscard]] inline std::vector<GeoFencePolygon> site_geofence(
    const SurveySite& site, std::size_t max_vertices = std::numeric_limits<std::size_t>::max(),
    double tolerance_m = 0.0) {
  return site_fence(site, max_vertices, tolerance_m).wgs84(site.geo);
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
