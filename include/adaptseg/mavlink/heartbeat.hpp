#pragma once
/// @file
/// HEARTBEAT (#0, minimal.xml): a system or component is present and responding, and what it
/// is. CMake target adaptseg::mavlink.

#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// HEARTBEAT (#0): sent at 1 Hz by every system; `type` and `autopilot` tell a PX4 vehicle
/// (`autopilot == mav_autopilot::kPx4`) from an ArduPilot one (`mav_autopilot::kArduPilotMega`)
/// and either from a ground station (`type == mav_type::kGcs`). Members in the order of the
/// definition; fields() gives the wire order.
struct Heartbeat {
  static constexpr std::uint32_t kId = 0;                 ///< message id
  static constexpr std::string_view kName = "HEARTBEAT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 50;           ///< published CRC_EXTRA

  std::uint8_t type = 0;           ///< MAV_TYPE (mav_type::)
  std::uint8_t autopilot = 0;      ///< MAV_AUTOPILOT (mav_autopilot::)
  std::uint8_t base_mode = 0;      ///< MAV_MODE_FLAG bits (mav_mode_flag::)
  std::uint32_t custom_mode = 0;   ///< the autopilot's own flight mode (PX4: main mode << 16 | sub mode << 24)
  std::uint8_t system_status = 0;  ///< MAV_STATE (mav_state::)
  std::uint8_t mavlink_version = kMavlinkVersion;  ///< MAVLink version (3)

  friend bool operator==(const Heartbeat&, const Heartbeat&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("custom_mode", &Heartbeat::custom_mode);
    v.field("type", &Heartbeat::type);
    v.field("autopilot", &Heartbeat::autopilot);
    v.field("base_mode", &Heartbeat::base_mode);
    v.field("system_status", &Heartbeat::system_status);
    v.field("mavlink_version", &Heartbeat::mavlink_version);
  }
};
static_assert(MessageType<Heartbeat>);
static_assert(kBaseLength<Heartbeat> == 9 && kFullLength<Heartbeat> == 9);

}  // namespace adaptseg::mavlink
