#pragma once
/// @file
/// GLOBAL_POSITION_INT (#33, common.xml): the autopilot's fused position estimate. CMake
/// target adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// GLOBAL_POSITION_INT (#33): position, height above home and velocity (NED) as the
/// autopilot's estimator fuses them. Members in the order of the definition (= wire order).
struct GlobalPositionInt {
  static constexpr std::uint32_t kId = 33;                          ///< message id
  static constexpr std::string_view kName = "GLOBAL_POSITION_INT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 104;                    ///< published CRC_EXTRA

  std::uint32_t time_boot_ms = 0;  ///< time since the autopilot booted [ms]
  std::int32_t lat = 0;            ///< latitude, WGS84 [degE7]
  std::int32_t lon = 0;            ///< longitude, WGS84 [degE7]
  std::int32_t alt = 0;            ///< altitude above mean sea level [mm]
  std::int32_t relative_alt = 0;   ///< altitude above home [mm]
  std::int16_t vx = 0;             ///< ground speed north [cm/s]
  std::int16_t vy = 0;             ///< ground speed east [cm/s]
  std::int16_t vz = 0;             ///< ground speed down [cm/s]
  std::uint16_t hdg = 0;           ///< heading [cdeg], 0..35999 (UINT16_MAX: unknown)

  friend bool operator==(const GlobalPositionInt&, const GlobalPositionInt&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("time_boot_ms", &GlobalPositionInt::time_boot_ms);
    v.field("lat", &GlobalPositionInt::lat);
    v.field("lon", &GlobalPositionInt::lon);
    v.field("alt", &GlobalPositionInt::alt);
    v.field("relative_alt", &GlobalPositionInt::relative_alt);
    v.field("vx", &GlobalPositionInt::vx);
    v.field("vy", &GlobalPositionInt::vy);
    v.field("vz", &GlobalPositionInt::vz);
    v.field("hdg", &GlobalPositionInt::hdg);
  }
};
static_assert(MessageType<GlobalPositionInt>);
static_assert(kBaseLength<GlobalPositionInt> == 28 && kFullLength<GlobalPositionInt> == 28);

}  // namespace adaptseg::mavlink
