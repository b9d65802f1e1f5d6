#pragma once
/// @file
/// POSITION_TARGET_GLOBAL_INT (#87, common.xml): the setpoint the autopilot follows. CMake
/// target adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// POSITION_TARGET_GLOBAL_INT (#87): the autopilot's answer to SET_POSITION_TARGET_GLOBAL_INT,
/// the target it follows (fields as there). Members in the order of the definition; fields()
/// gives the wire order.
struct PositionTargetGlobalInt {
  static constexpr std::uint32_t kId = 87;                                 ///< message id
  static constexpr std::string_view kName = "POSITION_TARGET_GLOBAL_INT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 150;                           ///< published CRC_EXTRA

  std::uint32_t time_boot_ms = 0;     ///< autopilot's time since boot [ms]
  std::uint8_t coordinate_frame = 0;  ///< MAV_FRAME of the position (mav_frame::)
  std::uint16_t type_mask = 0;        ///< POSITION_TARGET_TYPEMASK bits: what is ignored
  std::int32_t lat_int = 0;           ///< latitude, WGS84 [degE7]
  std::int32_t lon_int = 0;           ///< longitude, WGS84 [degE7]
  float alt = 0.0F;                   ///< altitude in `coordinate_frame` [m]
  float vx = 0.0F;                    ///< velocity north [m/s]
  float vy = 0.0F;                    ///< velocity east [m/s]
  float vz = 0.0F;                    ///< velocity down [m/s]
  float afx = 0.0F;                   ///< acceleration (or force) north [m/s/s]
  float afy = 0.0F;                   ///< acceleration (or force) east [m/s/s]
  float afz = 0.0F;                   ///< acceleration (or force) down [m/s/s]
  float yaw = 0.0F;                   ///< yaw [rad]
  float yaw_rate = 0.0F;              ///< yaw rate [rad/s]

  friend bool operator==(const PositionTargetGlobalInt&, const PositionTargetGlobalInt&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("time_boot_ms", &PositionTargetGlobalInt::time_boot_ms);
    v.field("lat_int", &PositionTargetGlobalInt::lat_int);
    v.field("lon_int", &PositionTargetGlobalInt::lon_int);
    v.field("alt", &PositionTargetGlobalInt::alt);
    v.field("vx", &PositionTargetGlobalInt::vx);
    v.field("vy", &PositionTargetGlobalInt::vy);
    v.field("vz", &PositionTargetGlobalInt::vz);
    v.field("afx", &PositionTargetGlobalInt::afx);
    v.field("afy", &PositionTargetGlobalInt::afy);
    v.field("afz", &PositionTargetGlobalInt::afz);
    v.field("yaw", &PositionTargetGlobalInt::yaw);
    v.field("yaw_rate", &PositionTargetGlobalInt::yaw_rate);
    v.field("type_mask", &PositionTargetGlobalInt::type_mask);
    v.field("coordinate_frame", &PositionTargetGlobalInt::coordinate_frame);
  }
};
static_assert(MessageType<PositionTargetGlobalInt>);
static_assert(kBaseLength<PositionTargetGlobalInt> == 51 && kFullLength<PositionTargetGlobalInt> == 51);

}  // namespace adaptseg::mavlink
