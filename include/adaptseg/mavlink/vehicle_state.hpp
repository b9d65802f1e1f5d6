#pragma once
/// @file
/// What a VehicleLink knows of the vehicle and reports of its operations: the autopilot's
/// HEARTBEAT (VehicleInfo), its position (VehiclePosition) and GPS fix (GpsStatus), an arrival,
/// a camera capture, and the link's counts. CMake target adaptseg::mavlink.

#include <adaptseg/mavlink/camera_image_captured.hpp>
#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/parser.hpp>
#include <adaptseg/mavlink/site_limits.hpp>
#include <adaptseg/mavlink/vehicle_mode.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <string>

namespace adaptseg::mavlink {

/// What the autopilot's latest HEARTBEAT says, and who sent it.
struct VehicleInfo {
  std::uint8_t system_id = 0;      ///< the autopilot's system id
  std::uint8_t component_id = 0;   ///< the autopilot's component id (usually 1)
  std::uint8_t autopilot = 0;      ///< MAV_AUTOPILOT (PX4 12, ArduPilot 3)
  std::uint8_t type = 0;           ///< MAV_TYPE (quadrotor 2, ...)
  std::uint8_t base_mode = 0;      ///< MAV_MODE_FLAG bits
  std::uint32_t custom_mode = 0;   ///< the firmware's flight mode (vehicle_mode.hpp)
  std::uint8_t system_status = 0;  ///< MAV_STATE
  double received_s = 0.0;         ///< when the HEARTBEAT arrived [link clock s]

  [[nodiscard]] Firmware firmware() const { return firmware_of(autopilot); }
  /// Whether the motors are armed (MAV_MODE_FLAG_SAFETY_ARMED).
  [[nodiscard]] bool armed() const { return (base_mode & mav_mode_flag::kSafetyArmed) != 0; }
  /// The flight mode by name (`"Hold"`, `"GUIDED"`, `"mode 7"`).
  [[nodiscard]] std::string mode() const { return mode_name(firmware(), type, custom_mode); }
};

/// The autopilot's latest GLOBAL_POSITION_INT, in SI units.
struct VehiclePosition {
  double lat_deg = 0.0;    ///< latitude [deg]
  double lon_deg = 0.0;    ///< longitude [deg]
  double alt_msl_m = 0.0;  ///< altitude above mean sea level [m]
  double rel_alt_m = 0.0;  ///< altitude above home [m]
  double vn_mps = 0.0;     ///< ground speed north [m/s]
  double ve_mps = 0.0;     ///< ground speed east [m/s]
  double vd_mps = 0.0;     ///< speed down [m/s]
  /// Heading of the vehicle's nose [deg clockwise from north, 0..360); NaN where the autopilot
  /// says it is unknown (GLOBAL_POSITION_INT hdg UINT16_MAX).
  double heading_deg = std::numeric_limits<double>::quiet_NaN();
  std::uint32_t time_boot_ms = 0;  ///< the autopilot's time [ms since boot]
  double received_s = 0.0;         ///< when it arrived [link clock s]

  /// Home's altitude above mean sea level [m]: what relative altitudes are measured from.
  [[nodiscard]] double home_alt_msl_m() const { return alt_msl_m - rel_alt_m; }
  /// Horizontal speed [m/s].
  [[nodiscard]] double ground_speed_mps() const { return std::hypot(vn_mps, ve_mps); }
  /// As a target: latitude, longitude, altitude above home.
  [[nodiscard]] LatLonAlt lat_lon_alt() const { return {lat_deg, lon_deg, rel_alt_m}; }
};

/// The GNSS receiver's latest fix (GPS_RAW_INT).
struct GpsStatus {
  std::uint8_t fix_type = 0;    ///< GPS_FIX_TYPE (3: 3-D fix)
  std::uint8_t satellites = 0;  ///< satellites visible (255: unknown)
  double received_s = 0.0;      ///< when it arrived [link clock s]
};

/// Where the vehicle was when wait_arrival() counted it as arrived.
struct Arrival {
  double horizontal_m = 0.0;   ///< horizontal distance to the target [m]
  double vertical_m = 0.0;     ///< altitude above the target (negative: below) [m]
  double waited_s = 0.0;       ///< time wait_arrival() took [s]
  VehiclePosition position{};  ///< the position that counted
};

/// What trigger_camera() did.
struct CameraCapture {
  std::uint16_t command = 0;                   ///< the command sent (IMAGE_START_CAPTURE or DO_DIGICAM_CONTROL)
  std::optional<CameraImageCaptured> image{};  ///< the CAMERA_IMAGE_CAPTURED that came within capture_wait_s, if any
};

/// Counts of what a VehicleLink sent and received.
struct LinkStats {
  std::uint64_t frames_sent = 0;      ///< frames we sent (heartbeats and commands)
  std::uint64_t frames_received = 0;  ///< checked frames from the vehicle's system
  std::uint64_t heartbeats_sent = 0;  ///< our HEARTBEATs
  std::uint64_t commands_sent = 0;    ///< COMMAND_LONG and COMMAND_INT frames, retries included
  std::uint64_t command_retries = 0;  ///< of commands_sent, the sends after the first of a command
  std::uint64_t acks_received = 0;    ///< COMMAND_ACKs addressed to us
  ParseStats parse{};                 ///< what the parser saw (bad frames, garbage)
};

}  // namespace adaptseg::mavlink
