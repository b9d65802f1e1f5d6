#pragma once
/// @file
/// GPS_RAW_INT (#24, common.xml): the GNSS receiver's raw fix. CMake target adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// GPS_RAW_INT (#24): the receiver's fix, not the autopilot's position estimate
/// (GLOBAL_POSITION_INT). Members in the order of the definition; fields() gives the wire order.
struct GpsRawInt {
  static constexpr std::uint32_t kId = 24;                  ///< message id
  static constexpr std::string_view kName = "GPS_RAW_INT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 24;             ///< published CRC_EXTRA

  std::uint64_t time_usec = 0;          ///< timestamp [us] (since boot or UNIX epoch)
  std::uint8_t fix_type = 0;            ///< GPS_FIX_TYPE (gps_fix_type::)
  std::int32_t lat = 0;                 ///< latitude, WGS84 [degE7]
  std::int32_t lon = 0;                 ///< longitude, WGS84 [degE7]
  std::int32_t alt = 0;                 ///< altitude above mean sea level [mm]
  std::uint16_t eph = 0;                ///< horizontal dilution of precision [x100] (UINT16_MAX: unknown)
  std::uint16_t epv = 0;                ///< vertical dilution of precision [x100] (UINT16_MAX: unknown)
  std::uint16_t vel = 0;                ///< ground speed [cm/s] (UINT16_MAX: unknown)
  std::uint16_t cog = 0;                ///< course over ground [cdeg], 0..35999 (UINT16_MAX: unknown)
  std::uint8_t satellites_visible = 0;  ///< satellites visible (UINT8_MAX: unknown)
  std::int32_t alt_ellipsoid = 0;       ///< extension: altitude above the WGS84 ellipsoid [mm]
  std::uint32_t h_acc = 0;              ///< extension: position uncertainty [mm]
  std::uint32_t v_acc = 0;              ///< extension: altitude uncertainty [mm]
  std::uint32_t vel_acc = 0;            ///< extension: speed uncertainty [mm/s]
  std::uint32_t hdg_acc = 0;            ///< extension: heading uncertainty [degE5]
  std::uint16_t yaw = 0;                ///< extension: yaw from north [cdeg] (0: unknown, 36000: north)

  friend bool operator==(const GpsRawInt&, const GpsRawInt&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("time_usec", &GpsRawInt::time_usec);
    v.field("lat", &GpsRawInt::lat);
    v.field("lon", &GpsRawInt::lon);
    v.field("alt", &GpsRawInt::alt);
    v.field("eph", &GpsRawInt::eph);
    v.field("epv", &GpsRawInt::epv);
    v.field("vel", &GpsRawInt::vel);
    v.field("cog", &GpsRawInt::cog);
    v.field("fix_type", &GpsRawInt::fix_type);
    v.field("satellites_visible", &GpsRawInt::satellites_visible);
    v.extensions();
    v.field("alt_ellipsoid", &GpsRawInt::alt_ellipsoid);
    v.field("h_acc", &GpsRawInt::h_acc);
    v.field("v_acc", &GpsRawInt::v_acc);
    v.field("vel_acc", &GpsRawInt::vel_acc);
    v.field("hdg_acc", &GpsRawInt::hdg_acc);
    v.field("yaw", &GpsRawInt::yaw);
  }
};
static_assert(MessageType<GpsRawInt>);
static_assert(kBaseLength<GpsRawInt> == 30 && kFullLength<GpsRawInt> == 52);

}  // namespace adaptseg::mavlink
