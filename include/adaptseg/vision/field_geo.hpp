#pragma once
/// @file
/// Where a field lies on the Earth: its anchor, heading and scale (FieldGeo, the `geo:` section
/// of field.yaml), and the projected CRS of a field read from GeoTIFFs (FieldCrs). Plain data,
/// held by Field (field.hpp); the conversions are in <adaptseg/geo/georeference.hpp>.

#include <adaptseg/core/error.hpp>

#include <cmath>
#include <string>

namespace adaptseg {

/// Where a field lies on the Earth: the optional `geo:` section of `field.yaml`
/// (docs/data_format.md). Plain data; the conversions live in `<adaptseg/geo/georeference.hpp>`
/// (adaptseg::geo, GeographicLib).
///
/// The anchor point (`anchor_x_m`, `anchor_y_m`) of the field frame is at (`latitude_deg`,
/// `longitude_deg`) on the field plane, whose height is `altitude_m`. The field's +x axis
/// points to the compass bearing `heading_deg` (degrees clockwise from north), +y 90 degrees
/// counter-clockwise from it seen from above (the frame is right-handed with z up): heading
/// 90 puts +x east and +y north, heading 0 puts +x north and +y west.
struct FieldGeo {
  double latitude_deg = 0.0;   ///< WGS84 latitude of the anchor [deg], in [-90, 90]
  double longitude_deg = 0.0;  ///< WGS84 longitude of the anchor [deg], in [-180, 180]
  double altitude_m = 0.0;     ///< height of the field plane above the WGS84 ellipsoid [m]
  double heading_deg = 90.0;   ///< compass bearing of the field's +x axis [deg clockwise from north]
  /// Field-frame position of the anchor [m]: (0, 0), the frame origin, for a loaded field;
  /// Field::sub_field moves the frame origin and shifts the anchor accordingly.
  double anchor_x_m = 0.0;
  double anchor_y_m = 0.0;  ///< see anchor_x_m
  /// Field-frame metres per metre on the ground at the anchor: 1 for a `geo:` section; a
  /// projected grid's scale factor (e.g. 0.9996 on a UTM zone's central meridian) for a field
  /// georeferenced by its raster (<adaptseg/gdal/gdal_io.hpp>), whose frame is in the grid's metres.
  double scale = 1.0;

  friend bool operator==(const FieldGeo&, const FieldGeo&) = default;
};

/// The projected coordinate reference system of a field georeferenced by its raster (a
/// GeoTIFF, read by <adaptseg/gdal/gdal_io.hpp>): the field frame is the CRS's grid shifted to the
/// orthomosaic's bottom-left corner, +x along the easting axis, +y along the northing axis
/// (north-up grids only). Plain data; written back into the fused map's GeoTIFF.
struct FieldCrs {
  std::string wkt;                 ///< the CRS as WKT (what GDAL read from the raster)
  double origin_easting_m = 0.0;   ///< CRS easting of the field frame's origin [m]
  double origin_northing_m = 0.0;  ///< CRS northing of the field frame's origin [m]

  friend bool operator==(const FieldCrs&, const FieldCrs&) = default;
};

namespace detail {

/// Checks a FieldGeo; `where` prefixes the message (e.g. "geo").
/// @throws std::invalid_argument naming the member and its value.
inline void validate_field_geo(const FieldGeo& g, const std::string& where) {
  require(std::isfinite(g.latitude_deg) && g.latitude_deg >= -90.0 && g.latitude_deg <= 90.0,
          where + ".latitude_deg must be in [-90, 90]", g.latitude_deg);
  require(std::isfinite(g.longitude_deg) && g.longitude_deg >= -180.0 && g.longitude_deg <= 180.0,
          where + ".longitude_deg must be in [-180, 180]", g.longitude_deg);
  require_finite(g.altitude_m, where + ".altitude_m");
  require_finite(g.heading_deg, where + ".heading_deg");
  require_finite(g.anchor_x_m, where + ".anchor_x_m");
  require_finite(g.anchor_y_m, where + ".anchor_y_m");
  require(std::isfinite(g.scale) && g.scale > 0.5 && g.scale < 2.0, where + ".scale must be in (0.5, 2)", g.scale);
}

}  // namespace detail

}  // namespace adaptseg
