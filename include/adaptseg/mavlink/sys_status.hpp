#pragma once
/// @file
/// SYS_STATUS (#1, common.xml): the onboard sensors' presence and health, battery, and link
/// error counts. CMake target adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// SYS_STATUS (#1). Members in the order of the definition; fields() gives the wire order.
/// A value the sender does not know is -1 (signed fields) or UINT16_MAX / 0 as the definition says.
struct SysStatus {
  static constexpr std::uint32_t kId = 1;                  ///< message id
  static constexpr std::string_view kName = "SYS_STATUS";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 124;           ///< published CRC_EXTRA

  std::uint32_t onboard_control_sensors_present = 0;  ///< MAV_SYS_STATUS_SENSOR bits: present
  std::uint32_t onboard_control_sensors_enabled = 0;  ///< MAV_SYS_STATUS_SENSOR bits: enabled
  std::uint32_t onboard_control_sensors_health = 0;   ///< MAV_SYS_STATUS_SENSOR bits: healthy (1) or not
  std::uint16_t load = 0;                             ///< main loop load [d%] (1000: 100 %)
  std::uint16_t voltage_battery = 0;                  ///< battery voltage [mV] (UINT16_MAX: unknown)
  std::int16_t current_battery = 0;                   ///< battery current [cA] (-1: unknown)
  std::int8_t battery_remaining = 0;                  ///< remaining battery [%] (-1: unknown)
  std::uint16_t drop_rate_comm = 0;                   ///< communication drop rate [c%]
  std::uint16_t errors_comm = 0;                      ///< communication errors
  std::uint16_t errors_count1 = 0;                    ///< autopilot-specific errors
  std::uint16_t errors_count2 = 0;                    ///< autopilot-specific errors
  std::uint16_t errors_count3 = 0;                    ///< autopilot-specific errors
  std::uint16_t errors_count4 = 0;                    ///< autopilot-specific errors
  /// Extension: MAV_SYS_STATUS_SENSOR_EXTENDED bits, present.
  std::uint32_t onboard_control_sensors_present_extended = 0;
  std::uint32_t onboard_control_sensors_enabled_extended = 0;  ///< extension: enabled
  std::uint32_t onboard_control_sensors_health_extended = 0;   ///< extension: healthy

  friend bool operator==(const SysStatus&, const SysStatus&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("onboard_control_sensors_present", &SysStatus::onboard_control_sensors_present);
    v.field("onboard_control_sensors_enabled", &SysStatus::onboard_control_sensors_enabled);
    v.field("onboard_control_sensors_health", &SysStatus::onboard_control_sensors_health);
    v.field("load", &SysStatus::load);
    v.field("voltage_battery", &SysStatus::voltage_battery);
    v.field("current_battery", &SysStatus::current_battery);
    v.field("drop_rate_comm", &SysStatus::drop_rate_comm);
    v.field("errors_comm", &SysStatus::errors_comm);
    v.field("errors_count1", &SysStatus::errors_count1);
    v.field("errors_count2", &SysStatus::errors_count2);
    v.field("errors_count3", &SysStatus::errors_count3);
    v.field("errors_count4", &SysStatus::errors_count4);
    v.field("battery_remaining", &SysStatus::battery_remaining);
    v.extensions();
    v.field("onboard_control_sensors_present_extended", &SysStatus::onboard_control_sensors_present_extended);
    v.field("onboard_control_sensors_enabled_extended", &SysStatus::onboard_control_sensors_enabled_extended);
    v.field("onboard_control_sensors_health_extended", &SysStatus::onboard_control_sensors_health_extended);
  }
};
static_assert(MessageType<SysStatus>);
static_assert(kBaseLength<SysStatus> == 31 && kFullLength<SysStatus> == 43);

}  // namespace adaptseg::mavlink
