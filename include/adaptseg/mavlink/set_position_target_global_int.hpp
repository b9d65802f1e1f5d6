#pragma once
/// @file
/// SET_POSITION_TARGET_GLOBAL_INT (#86, common.xml): a setpoint in WGS84 for an autopilot in
/// offboard (PX4) or guided (ArduPilot) mode. CMake target adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// SET_POSITION_TARGET_GLOBAL_INT (#86): position, velocity, acceleration and yaw targets;
/// `type_mask` (position_target_typemask::) says which to ignore. The autopilot echoes what it
/// follows in POSITION_TARGET_GLOBAL_INT. Members in the order of the definition; fields()
/// gives the wire order.
struct SetPositionTargetGlobalInt {
  static constexpr std::uint32_t kId = 86;                                     ///< message id
  static constexpr std::string_view kName = "SET_POSITION_TARGET_GLOBAL_INT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 5;                                 ///< published CRC_EXTRA

  std::uint32_t time_boot_ms = 0;     ///< sender's time since boot [ms]
  std::uint8_t target_system = 0;     ///< system id of the target
  std::uint8_t target_component = 0;  ///< component id of the target
  std::uint8_t coordinate_frame = 0;  ///< MAV_FRAME of the position (mav_frame::, e.g. kGlobalRelativeAltInt)
  std::uint16_t type_mask = 0;        ///< POSITION_TARGET_TYPEMASK bits: what to ignore
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

  friend bool operator==(const SetPositionTargetGlobalInt&, const SetPositionTargetGlobalInt&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("time_boot_ms", &SetPositionTargetGlobalInt::time_boot_ms);
    v.field("lat_int", &SetPositionTargetGlobalInt::lat_int);
    v.field("lon_int", &SetPositionTargetGlobalInt::lon_int);
    v.field("alt", &SetPositionTargetGlobalInt::alt);
    v.field("vx", &SetPositionTargetGlobalInt::vx);
    v.field("vy", &SetPositionTargetGlobalInt::vy);
    v.field("vz", &SetPositionTargetGlobalInt::vz);
    v.field("afx", &SetPositionTargetGlobalInt::afx);
    v.field("afy", &SetPositionTargetGlobalInt::afy);
    v.field("afz", &SetPositionTargetGlobalInt::afz);
    v.field("yaw", &SetPositionTargetGlobalInt::yaw);
    v.field("yaw_rate", &SetPositionTargetGlobalInt::yaw_rate);
    v.field("type_mask", &SetPositionTargetGlobalInt::type_mask);
    v.field("target_system", &SetPositionTargetGlobalInt::target_system);
    v.field("target_component", &SetPositionTargetGlobalInt::target_component);
    v.field("coordinate_frame", &SetPositionTargetGlobalInt::coordinate_frame);
  }
};
static_assert(MessageType<SetPositionTargetGlobalInt>);
static_assert(kBaseLength<SetPositionTargetGlobalInt> == 53 && kFullLength<SetPositionTargetGlobalInt> == 53);

}  // namespace adaptseg::mavlink
