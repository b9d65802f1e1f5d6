#pragma once
/// @file
/// The flight stacks a link tells apart, and the custom modes (HEARTBEAT `custom_mode`) it needs
/// of each: PX4's main and sub modes, ArduPilot's mode numbers per vehicle. CMake target
/// adaptseg::mavlink.
///
/// Sources: PX4, `src/modules/commander/px4_custom_mode.h` (custom_mode = main mode << 16 |
/// sub mode << 24); ArduPilot, "Get and Set FlightMode" (ardupilot.org/dev/docs/
/// mavlink-get-set-flightmode.html) and each vehicle's FLTMODE1 parameter (Copter GUIDED 4,
/// Plane and Rover GUIDED 15).

#include <adaptseg/core/detail/named_rows.hpp>
#include <adaptseg/mavlink/enums.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string>

namespace adaptseg::mavlink {

/// Which flight stack sent a HEARTBEAT (its `autopilot` field).
enum class Firmware {
  px4,        ///< MAV_AUTOPILOT_PX4 (12)
  ardupilot,  ///< MAV_AUTOPILOT_ARDUPILOTMEGA (3)
  other,      ///< any other: commanded as PX4 is, but its modes are not watched
};

/// The Firmware of a HEARTBEAT's `autopilot` value.
[[nodiscard]] constexpr Firmware firmware_of(std::uint8_t autopilot) {
  if (autopilot == mav_autopilot::kPx4) return Firmware::px4;
  if (autopilot == mav_autopilot::kArduPilotMega) return Firmware::ardupilot;
  return Firmware::other;
}

/// Every Firmware by name.
inline constexpr std::array<adaptseg::detail::NamedValue<Firmware>, 3> kFirmwares{{
    {Firmware::px4, "PX4"},
    {Firmware::ardupilot, "ArduPilot"},
    {Firmware::other, "other"},
}};

/// `"PX4"`, `"ArduPilot"`, `"other"` (also for a value out of range).
[[nodiscard]] inline std::string to_string(Firmware f) { return adaptseg::detail::name_or(kFirmwares, f, "other"); }

/// PX4's custom modes: custom_mode = main mode << 16 | sub mode << 24.
namespace px4_mode {
inline constexpr std::uint8_t kMainManual = 1;    ///< PX4_CUSTOM_MAIN_MODE_MANUAL
inline constexpr std::uint8_t kMainAltctl = 2;    ///< PX4_CUSTOM_MAIN_MODE_ALTCTL
inline constexpr std::uint8_t kMainPosctl = 3;    ///< PX4_CUSTOM_MAIN_MODE_POSCTL (Position)
inline constexpr std::uint8_t kMainAuto = 4;      ///< PX4_CUSTOM_MAIN_MODE_AUTO
inline constexpr std::uint8_t kMainOffboard = 6;  ///< PX4_CUSTOM_MAIN_MODE_OFFBOARD
inline constexpr std::uint8_t kAutoTakeoff = 2;   ///< PX4_CUSTOM_SUB_MODE_AUTO_TAKEOFF
inline constexpr std::uint8_t kAutoLoiter = 3;    ///< PX4_CUSTOM_SUB_MODE_AUTO_LOITER (Hold)
inline constexpr std::uint8_t kAutoMission = 4;   ///< PX4_CUSTOM_SUB_MODE_AUTO_MISSION
inline constexpr std::uint8_t kAutoRtl = 5;       ///< PX4_CUSTOM_SUB_MODE_AUTO_RTL (Return)
inline constexpr std::uint8_t kAutoLand = 6;      ///< PX4_CUSTOM_SUB_MODE_AUTO_LAND

/// The HEARTBEAT custom_mode of main mode `main` and sub mode `sub`.
[[nodiscard]] constexpr std::uint32_t custom_mode(std::uint8_t main, std::uint8_t sub = 0) {
  return (static_cast<std::uint32_t>(main) << 16) | (static_cast<std::uint32_t>(sub) << 24);
}
[[nodiscard]] constexpr std::uint8_t main_mode(std::uint32_t custom) { return static_cast<std::uint8_t>(custom >> 16); }
[[nodiscard]] constexpr std::uint8_t sub_mode(std::uint32_t custom) { return static_cast<std::uint8_t>(custom >> 24); }

/// Hold (AUTO_LOITER): where a DO_REPOSITION leaves PX4.
inline constexpr std::uint32_t kHold = custom_mode(kMainAuto, kAutoLoiter);
}  // namespace px4_mode

/// ArduPilot's mode numbers that a link needs (Copter's; Plane and Rover number theirs otherwise).
namespace ardupilot_mode {
inline constexpr std::uint32_t kCopterAuto = 3;       ///< Copter AUTO
inline constexpr std::uint32_t kCopterGuided = 4;     ///< Copter GUIDED
inline constexpr std::uint32_t kCopterLoiter = 5;     ///< Copter LOITER
inline constexpr std::uint32_t kCopterRtl = 6;        ///< Copter RTL
inline constexpr std::uint32_t kCopterLand = 9;       ///< Copter LAND
inline constexpr std::uint32_t kCopterSmartRtl = 21;  ///< Copter SMART_RTL
inline constexpr std::uint32_t kPlaneGuided = 15;     ///< Plane GUIDED (Rover's is 15 too)
inline constexpr std::uint32_t kPlaneRtl = 11;        ///< Plane RTL (Rover's is 11 too)
}  // namespace ardupilot_mode

/// Whether MAV_TYPE `type` is a rotorcraft that ArduCopter flies (or ArduSub, which numbers GUIDED alike).
[[nodiscard]] constexpr bool is_copter_type(std::uint8_t type) {
  return type == mav_type::kQuadrotor || type == 3 /* coaxial */ || type == mav_type::kHelicopter ||
         type == mav_type::kHexarotor || type == mav_type::kOctorotor || type == 15 /* tricopter */ ||
         type == 29 /* dodecarotor */ || type == 12 /* submarine: ArduSub GUIDED 4 */;
}

/// ArduPilot's GUIDED mode number for a vehicle of MAV_TYPE `type`: 4 for Copter (and Sub), 15
/// for Plane (fixed wing, VTOL) and Rover (ground rover, boat); nullopt for a type it cannot tell.
[[nodiscard]] constexpr std::optional<std::uint32_t> ardupilot_guided_mode(std::uint8_t type) {
  if (is_copter_type(type)) return ardupilot_mode::kCopterGuided;
  if (type == mav_type::kFixedWing || (type >= 19 && type <= 25) /* VTOL types */ || type == 10 /* ground rover */ ||
      type == 11 /* surface boat */) {
    return ardupilot_mode::kPlaneGuided;
  }
  return std::nullopt;
}

/// Whether `custom_mode` is one in which the vehicle returns home or lands (the link does not
/// command a vehicle in it: a failsafe or the pilot chose it).
[[nodiscard]] constexpr bool is_returning_or_landing(Firmware firmware, std::uint8_t type, std::uint32_t custom) {
  if (firmware == Firmware::px4) {
    return px4_mode::main_mode(custom) == px4_mode::kMainAuto &&
           (px4_mode::sub_mode(custom) == px4_mode::kAutoRtl || px4_mode::sub_mode(custom) == px4_mode::kAutoLand);
  }
  if (firmware == Firmware::ardupilot) {
    if (is_copter_type(type)) {
      return custom == ardupilot_mode::kCopterRtl || custom == ardupilot_mode::kCopterLand ||
             custom == ardupilot_mode::kCopterSmartRtl;
    }
    return custom == ardupilot_mode::kPlaneRtl || custom == 12 /* Rover SMART_RTL */ || custom == 20 /* QLAND */ ||
           custom == 21 /* QRTL */;
  }
  return false;
}

/// A mode's name for messages: PX4's (`"Hold"`, `"Return"`, `"Position"`), ArduCopter's
/// (`"GUIDED"`, `"LOITER"`, `"RTL"`), else `"mode N"`.
[[nodiscard]] inline std::string mode_name(Firmware firmware, std::uint8_t type, std::uint32_t custom) {
  if (firmware == Firmware::px4) {
    const std::uint8_t main = px4_mode::main_mode(custom);
    const std::uint8_t sub = px4_mode::sub_mode(custom);
    switch (main) {
      case px4_mode::kMainManual: return "Manual";
      case px4_mode::kMainAltctl: return "Altitude";
      case px4_mode::kMainPosctl: return "Position";
      case px4_mode::kMainOffboard: return "Offboard";
      case px4_mode::kMainAuto:
        switch (sub) {
          case px4_mode::kAutoTakeoff: return "Takeoff";
          case px4_mode::kAutoLoiter: return "Hold";
          case px4_mode::kAutoMission: return "Mission";
          case px4_mode::kAutoRtl: return "Return";
          case px4_mode::kAutoLand: return "Land";
          default: return "Auto sub mode " + std::to_string(sub);
        }
      default: return "main mode " + std::to_string(main);
    }
  }
  if (firmware == Firmware::ardupilot && is_copter_type(type)) {
    switch (custom) {
      case 0: return "STABILIZE";
      case 2: return "ALT_HOLD";
      case ardupilot_mode::kCopterAuto: return "AUTO";
      case ardupilot_mode::kCopterGuided: return "GUIDED";
      case ardupilot_mode::kCopterLoiter: return "LOITER";
      case ardupilot_mode::kCopterRtl: return "RTL";
      case ardupilot_mode::kCopterLand: return "LAND";
      case 16: return "POSHOLD";
      case 17: return "BRAKE";
      case ardupilot_mode::kCopterSmartRtl: return "SMART_RTL";
      default: break;
    }
  }
  return "mode " + std::to_string(custom);
}

}  // namespace adaptseg::mavlink
