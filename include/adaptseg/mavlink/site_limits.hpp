#pragma once
/// @file
/// SiteLimits: where a VehicleLink may send the vehicle (a polygon in latitude and longitude,
/// an altitude band above home); a target outside is never sent. CMake target adaptseg::mavlink.
///
/// @code
/// using namespace adaptseg::mavlink;
/// const SiteLimits site({{25.2000, 55.3000}, {25.2000, 55.3020}, {25.2018, 55.3020}, {25.2018, 55.3000}},
///                       /*ceiling_m=*/120.0);
/// site.violation({25.2009, 55.3010, 60.0});   // nullopt: inside
/// site.violation({25.2009, 55.3010, 150.0});  // "altitude 150.0 m above home is above the ceiling 120.0 m"
/// @endcode

#include <cmath>
#include <cstddef>
#include <cstdio>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::mavlink {

/// A point of a site's boundary, WGS84 [deg].
struct LatLon {
  double lat_deg = 0.0;  ///< latitude [deg], -90..90
  double lon_deg = 0.0;  ///< longitude [deg], -180..180
  friend bool operator==(const LatLon&, const LatLon&) = default;
};

/// A position to fly to: WGS84 latitude and longitude, altitude above home (the take-off point),
/// as the planner's altitudes and the autopilots' relative altitudes are.
struct LatLonAlt {
  double lat_deg = 0.0;    ///< latitude [deg]
  double lon_deg = 0.0;    ///< longitude [deg]
  double rel_alt_m = 0.0;  ///< altitude above home [m]
  friend bool operator==(const LatLonAlt&, const LatLonAlt&) = default;
};

/// `p` as `"(25.2009000, 55.3010000, 60.0 m)"`: latitude and longitude to 1 cm, altitude above home.
[[nodiscard]] inline std::string to_string(const LatLonAlt& p) {
  char text[96];
  std::snprintf(text, sizeof(text), "(%.7f, %.7f, %.1f m)", p.lat_deg, p.lon_deg, p.rel_alt_m);
  return text;
}

/// The limits of a site: a simple polygon (its vertices in order, either sense, not closed:
/// the last joins the first) and an altitude band above home [floor_m, ceiling_m]. The polygon
/// is taken as flat in latitude and longitude (edges are straight in degrees), which a site of
/// a few kilometres allows; it may not span the antimeridian (a longitude range under 180 deg).
/// Value type; the constructor checks it once.
class SiteLimits {
 public:
  /// @throws std::invalid_argument naming the parameter: fewer than 3 vertices, a vertex not
  ///         finite or out of range, a polygon of no area or spanning 180 deg of longitude or
  ///         more, a ceiling not finite or not above a finite floor.
  SiteLimits(std::vector<LatLon> polygon, double ceiling_m, double floor_m = 0.0)
      : polygon_(std::move(polygon)), ceiling_m_(ceiling_m), floor_m_(floor_m) {
    if (polygon_.size() < 3) {
      throw std::invalid_argument("SiteLimits: polygon needs at least 3 vertices (got " +
                                  std::to_string(polygon_.size()) + ")");
    }
    double lon_min = 1e9;
    double lon_max = -1e9;
    for (std::size_t i = 0; i < polygon_.size(); ++i) {
      const LatLon& v = polygon_[i];
      if (!std::isfinite(v.lat_deg) || !std::isfinite(v.lon_deg) || std::fabs(v.lat_deg) > 90.0 ||
          std::fabs(v.lon_deg) > 180.0) {
        throw std::invalid_argument("SiteLimits: polygon vertex " + std::to_string(i) +
                                    " must be a latitude in -90..90 and a longitude in -180..180 (got " +
                                    std::to_string(v.lat_deg) + ", " + std::to_string(v.lon_deg) + ")");
      }
      lon_min = std::fmin(lon_min, v.lon_deg);
      lon_max = std::fmax(lon_max, v.lon_deg);
    }
    if (lon_max - lon_min >= 180.0) {
      throw std::invalid_argument(
          "SiteLimits: polygon spans 180 deg of longitude or more (the antimeridian is not "
          "supported)");
    }
    if (std::fabs(twice_area()) < 1e-18) throw std::invalid_argument("SiteLimits: polygon has no area");
    if (!std::isfinite(floor_m_))
      throw std::invalid_argument("SiteLimits: floor_m must be finite (got " + std::to_string(floor_m_) + ")");
    if (!std::isfinite(ceiling_m_) || ceiling_m_ <= floor_m_) {
      throw std::invalid_argument("SiteLimits: ceiling_m must be finite and above floor_m " + std::to_string(floor_m_) +
                                  " (got " + std::to_string(ceiling_m_) + ")");
    }
  }

  /// Whether (lat, lon) is inside the polygon (a point on an edge may count either way;
  /// NaN is outside).
  [[nodiscard]] bool contains(double lat_deg, double lon_deg) const {
    if (!std::isfinite(lat_deg) || !std::isfinite(lon_deg)) return false;
    bool inside = false;
    for (std::size_t i = 0, j = polygon_.size() - 1; i < polygon_.size(); j = i++) {
      const LatLon& a = polygon_[i];
      const LatLon& b = polygon_[j];
      if ((a.lat_deg > lat_deg) != (b.lat_deg > lat_deg)) {
        const double lon_cross = a.lon_deg + (lat_deg - a.lat_deg) * (b.lon_deg - a.lon_deg) / (b.lat_deg - a.lat_deg);
        if (lon_deg < lon_cross) inside = !inside;
      }
    }
    return inside;
  }

  /// Why `p` may not be flown to (`"outside the site polygon"`, `"altitude 150.0 m above home
  /// is above the ceiling 120.0 m"`, `"not a finite position"`), or nullopt if it may.
  [[nodiscard]] std::optional<std::string> violation(const LatLonAlt& p) const {
    if (!std::isfinite(p.lat_deg) || !std::isfinite(p.lon_deg) || !std::isfinite(p.rel_alt_m)) {
      return std::string("not a finite position");
    }
    if (!contains(p.lat_deg, p.lon_deg)) return std::string("outside the site polygon");
    char text[128];
    if (p.rel_alt_m > ceiling_m_) {
      std::snprintf(text, sizeof(text), "altitude %.1f m above home is above the ceiling %.1f m", p.rel_alt_m,
                    ceiling_m_);
      return std::string(text);
    }
    if (p.rel_alt_m < floor_m_) {
      std::snprintf(text, sizeof(text), "altitude %.1f m above home is below the floor %.1f m", p.rel_alt_m, floor_m_);
      return std::string(text);
    }
    return std::nullopt;
  }

  [[nodiscard]] const std::vector<LatLon>& polygon() const { return polygon_; }  ///< the vertices, as given
  [[nodiscard]] double ceiling_m() const { return ceiling_m_; }                  ///< highest altitude above home [m]
  [[nodiscard]] double floor_m() const { return floor_m_; }                      ///< lowest altitude above home [m]

 private:
  [[nodiscard]] double twice_area() const {
    double sum = 0.0;
    for (std::size_t i = 0, j = polygon_.size() - 1; i < polygon_.size(); j = i++) {
      sum += (polygon_[j].lon_deg - polygon_[i].lon_deg) * (polygon_[j].lat_deg + polygon_[i].lat_deg);
    }
    return sum;
  }

  std::vector<LatLon> polygon_;
  double ceiling_m_ = 0.0;
  double floor_m_ = 0.0;
};

}  // namespace adaptseg::mavlink
