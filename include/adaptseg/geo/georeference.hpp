#pragma once
/// @file
/// Geo-reference of a field: field frame <-> WGS84 latitude, longitude and height, through
/// GeographicLib's local tangent plane (`GeographicLib::LocalCartesian`, exact conversion
/// between geodetic and local east-north-up coordinates on the WGS84 ellipsoid).
/// CMake target adaptseg::geo.

#include <adaptseg/core/error.hpp>
#include <adaptseg/vision/field.hpp>

#include <Eigen/Core>
#include <GeographicLib/LocalCartesian.hpp>
#include <GeographicLib/Math.hpp>

#include <stdexcept>

namespace adaptseg {

/// A WGS84 position.
struct GeoPoint {
  double latitude_deg = 0.0;   ///< [deg], north positive
  double longitude_deg = 0.0;  ///< [deg], east positive, in [-180, 180]
  double altitude_m = 0.0;     ///< height above the WGS84 ellipsoid [m]

  friend bool operator==(const GeoPoint&, const GeoPoint&) = default;
};

/// Converts between a field's frame and WGS84 (docs/data_format.md, "Geo-reference").
///
/// With h the heading (compass bearing of the field's +x axis, clockwise from north) and
/// (ax, ay) the anchor's field-frame position, a field point (x, y, z) lies at
///
///     east  = ((x - ax) sin h - (y - ay) cos h) / k
///     north = ((x - ax) cos h + (y - ay) sin h) / k
///     up    = z
///
/// (k = FieldGeo::scale: 1 for a `geo:` section; a projected grid's scale factor at the
/// anchor for a field georeferenced by its GeoTIFF, see <adaptseg/gdal/gdal_io.hpp>)
/// in the local tangent plane (east-north-up) whose origin is the anchor at the field
/// plane's height, and GeographicLib::LocalCartesian maps that plane to WGS84. Heading 90:
/// +x east, +y north; heading 0: +x north, +y west. The field frame is flat; over a field
/// the tangent plane departs from the ellipsoid by d^2 / 2R (0.08 m at d = 1 km).
///
/// @code
/// const adaptseg::Field field = adaptseg::Field::load(dir);   // with a geo: section
/// const adaptseg::GeoReference geo(field);
/// const adaptseg::GeoPoint p = geo.to_wgs84({10.0, 5.0, 30.0});
/// const Eigen::Vector3d back = geo.to_field(p);                 // (10, 5, 30) to < 1 nm
/// @endcode
class GeoReference {
 public:
  /// @throws std::invalid_argument for a latitude outside [-90, 90], a longitude outside
  ///         [-180, 180], or a non-finite altitude, heading or anchor.
  explicit GeoReference(const FieldGeo& geo)
      : geo_(checked(geo)), local_(geo.latitude_deg, geo.longitude_deg, geo.altitude_m) {
    // sincosd is exact at multiples of 90 degrees, so heading 90 maps +x exactly east.
    GeographicLib::Math::sincosd(geo_.heading_deg, sin_h_, cos_h_);
  }

  /// The geo-reference of `field`.
  /// @throws std::invalid_argument if the field has none (no `geo:` section).
  explicit GeoReference(const Field& field) : GeoReference(require_geo(field)) {}

  [[nodiscard]] const FieldGeo& geo() const noexcept { return geo_; }

  /// Field frame (x, y, z) [m] -> local east, north, up [m] about the anchor.
  [[nodiscard]] Eigen::Vector3d field_to_enu(const Eigen::Vector3d& p) const noexcept {
    const double dx = (p.x() - geo_.anchor_x_m) / geo_.scale;
    const double dy = (p.y() - geo_.anchor_y_m) / geo_.scale;
    return {dx * sin_h_ - dy * cos_h_, dx * cos_h_ + dy * sin_h_, p.z()};
  }

  /// Local east, north, up [m] about the anchor -> field frame (x, y, z) [m].
  [[nodiscard]] Eigen::Vector3d enu_to_field(const Eigen::Vector3d& enu) const noexcept {
    const double k = geo_.scale;
    return {geo_.anchor_x_m + k * (enu.x() * sin_h_ + enu.y() * cos_h_),
            geo_.anchor_y_m + k * (-enu.x() * cos_h_ + enu.y() * sin_h_), enu.z()};
  }

  /// Field frame (x, y, z) [m], z above the field plane -> WGS84. The altitude is the
  /// ellipsoidal height of the point (the field plane's `altitude_m` + z, plus the tangent
  /// plane's rise above the ellipsoid away from the anchor).
  [[nodiscard]] GeoPoint to_wgs84(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d enu = field_to_enu(p);
    // The anchor itself: its own coordinates, free of the round trip through geocentric ones.
    if (enu.x() == 0.0 && enu.y() == 0.0) return {geo_.latitude_deg, geo_.longitude_deg, geo_.altitude_m + enu.z()};
    GeoPoint g;
    local_.Reverse(enu.x(), enu.y(), enu.z(), g.latitude_deg, g.longitude_deg, g.altitude_m);
    return g;
  }

  /// WGS84 -> field frame (x, y, z) [m]; the inverse of to_wgs84.
  /// @throws std::invalid_argument for a non-finite coordinate or a latitude outside [-90, 90].
  [[nodiscard]] Eigen::Vector3d to_field(const GeoPoint& g) const {
    detail::require(std::isfinite(g.latitude_deg) && g.latitude_deg >= -90.0 && g.latitude_deg <= 90.0,
                    "GeoReference::to_field: latitude_deg must be in [-90, 90]", g.latitude_deg);
    detail::require_finite(g.longitude_deg, "GeoReference::to_field: longitude_deg");
    detail::require_finite(g.altitude_m, "GeoReference::to_field: altitude_m");
    Eigen::Vector3d enu;
    local_.Forward(g.latitude_deg, g.longitude_deg, g.altitude_m, enu.x(), enu.y(), enu.z());
    return enu_to_field(enu);
  }

 private:
  static const FieldGeo& checked(const FieldGeo& geo) {
    detail::validate_field_geo(geo, "GeoReference: geo");
    return geo;
  }
  static const FieldGeo& require_geo(const Field& field) {
    if (!field.geo())
      throw std::invalid_argument("field '" + field.name() +
                                  "' has no geo-reference (add a 'geo:' section to field.yaml)");
    return *field.geo();
  }

  FieldGeo geo_;
  GeographicLib::LocalCartesian local_;
  double sin_h_ = 1.0;
  double cos_h_ = 0.0;
};

}  // namespace adaptseg
