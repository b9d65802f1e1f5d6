#pragma once
/// @file
/// A survey site's outline (survey_site.hpp) as a geofence: each outer ring an inclusion
/// polygon, each hole an exclusion one, simplified to the vertices the autopilot keeps. CMake
/// target adaptseg::gdal.

#include <adaptseg/core/error.hpp>
#include <adaptseg/gdal/detail/dataset.hpp>
#include <adaptseg/gdal/survey_site.hpp>
#include <adaptseg/geo/georeference.hpp>
#include <adaptseg/geo/mission_export.hpp>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace adaptseg {

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

}  // namespace adaptseg
