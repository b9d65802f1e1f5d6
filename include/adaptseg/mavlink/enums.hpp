#pragma once
/// @file
/// The values of the MAVLink enumerations (common.xml, minimal.xml) that a link to a PX4 or
/// ArduPilot autopilot needs, as named constants of the wire fields' types: one namespace per
/// MAVLink enumeration (`MAV_CMD_DO_REPOSITION` is `mav_cmd::kDoReposition`). CMake target
/// adaptseg::mavlink.
///
/// The fields of the message structs stay plain integers, so that any value a peer sends
/// (one of a newer definition included) decodes and compares: `ack.command ==
/// mav_cmd::kDoReposition`, `(hb.base_mode & mav_mode_flag::kSafetyArmed) != 0`.

#include <cstdint>

namespace adaptseg::mavlink {

/// The `mavlink_version` HEARTBEAT carries: 3 for MAVLink 1.0 and 2.0.
inline constexpr std::uint8_t kMavlinkVersion = 3;

/// MAV_CMD: commands of COMMAND_LONG / COMMAND_INT (`command`, uint16).
namespace mav_cmd {
inline constexpr std::uint16_t kNavWaypoint = 16;        ///< MAV_CMD_NAV_WAYPOINT
inline constexpr std::uint16_t kNavReturnToLaunch = 20;  ///< MAV_CMD_NAV_RETURN_TO_LAUNCH: no parameters
inline constexpr std::uint16_t kNavLand = 21;            ///< MAV_CMD_NAV_LAND
/// MAV_CMD_NAV_TAKEOFF: p1 pitch, p4 yaw [deg], p5-p6 latitude, longitude, p7 altitude [m]
inline constexpr std::uint16_t kNavTakeoff = 22;
/// MAV_CMD_DO_SET_MODE: p1 base mode (MAV_MODE_FLAG, with kCustomModeEnabled), p2 custom mode,
/// p3 custom sub-mode (autopilot specific)
inline constexpr std::uint16_t kDoSetMode = 176;
/// MAV_CMD_DO_REPOSITION: p1 ground speed [m/s] (-1: default), p2 bitmask (1: change mode),
/// p4 yaw [deg] (NaN: unchanged), x, y latitude, longitude, z altitude [m] in the command's frame
inline constexpr std::uint16_t kDoReposition = 192;
/// MAV_CMD_DO_DIGICAM_CONTROL: p5 1 = take one shot
inline constexpr std::uint16_t kDoDigicamControl = 203;
/// MAV_CMD_COMPONENT_ARM_DISARM: p1 1 arm, 0 disarm; p2 21196 forces it
inline constexpr std::uint16_t kComponentArmDisarm = 400;
/// MAV_CMD_SET_MESSAGE_INTERVAL: p1 message id, p2 interval [us] (-1: stop, 0: default)
inline constexpr std::uint16_t kSetMessageInterval = 511;
/// MAV_CMD_REQUEST_MESSAGE: p1 message id, p2-p7 message specific
inline constexpr std::uint16_t kRequestMessage = 512;
/// MAV_CMD_IMAGE_START_CAPTURE: p2 interval [s], p3 number of images, p4 sequence number
inline constexpr std::uint16_t kImageStartCapture = 2000;
}  // namespace mav_cmd

/// MAV_RESULT: COMMAND_ACK's `result` (uint8).
namespace mav_result {
inline constexpr std::uint8_t kAccepted = 0;                    ///< MAV_RESULT_ACCEPTED
inline constexpr std::uint8_t kTemporarilyRejected = 1;         ///< MAV_RESULT_TEMPORARILY_REJECTED
inline constexpr std::uint8_t kDenied = 2;                      ///< MAV_RESULT_DENIED
inline constexpr std::uint8_t kUnsupported = 3;                 ///< MAV_RESULT_UNSUPPORTED
inline constexpr std::uint8_t kFailed = 4;                      ///< MAV_RESULT_FAILED
inline constexpr std::uint8_t kInProgress = 5;                  ///< MAV_RESULT_IN_PROGRESS: another ACK follows
inline constexpr std::uint8_t kCancelled = 6;                   ///< MAV_RESULT_CANCELLED
inline constexpr std::uint8_t kCommandLongOnly = 7;             ///< MAV_RESULT_COMMAND_LONG_ONLY
inline constexpr std::uint8_t kCommandIntOnly = 8;              ///< MAV_RESULT_COMMAND_INT_ONLY
inline constexpr std::uint8_t kCommandUnsupportedMavFrame = 9;  ///< MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME
}  // namespace mav_result

/// MAV_FRAME: `frame` of COMMAND_INT, `coordinate_frame` of the position targets (uint8).
namespace mav_frame {
inline constexpr std::uint8_t kGlobal = 0;             ///< MAV_FRAME_GLOBAL: altitude above mean sea level
inline constexpr std::uint8_t kGlobalRelativeAlt = 3;  ///< MAV_FRAME_GLOBAL_RELATIVE_ALT: altitude above home
/// MAV_FRAME_GLOBAL_INT: latitude and longitude scaled by 1e7, altitude above mean sea level
inline constexpr std::uint8_t kGlobalInt = 5;
/// MAV_FRAME_GLOBAL_RELATIVE_ALT_INT: latitude and longitude scaled by 1e7, altitude above home
/// (newer common.xml marks the `_INT` frames synonyms of kGlobal and kGlobalRelativeAlt)
inline constexpr std::uint8_t kGlobalRelativeAltInt = 6;
}  // namespace mav_frame

/// GPS_FIX_TYPE: GPS_RAW_INT's `fix_type` (uint8).
namespace gps_fix_type {
inline constexpr std::uint8_t kNoGps = 0;     ///< GPS_FIX_TYPE_NO_GPS
inline constexpr std::uint8_t kNoFix = 1;     ///< GPS_FIX_TYPE_NO_FIX
inline constexpr std::uint8_t k2dFix = 2;     ///< GPS_FIX_TYPE_2D_FIX
inline constexpr std::uint8_t k3dFix = 3;     ///< GPS_FIX_TYPE_3D_FIX
inline constexpr std::uint8_t kDgps = 4;      ///< GPS_FIX_TYPE_DGPS
inline constexpr std::uint8_t kRtkFloat = 5;  ///< GPS_FIX_TYPE_RTK_FLOAT
inline constexpr std::uint8_t kRtkFixed = 6;  ///< GPS_FIX_TYPE_RTK_FIXED
inline constexpr std::uint8_t kStatic = 7;    ///< GPS_FIX_TYPE_STATIC
inline constexpr std::uint8_t kPpp = 8;       ///< GPS_FIX_TYPE_PPP
}  // namespace gps_fix_type

/// MAV_MODE_FLAG: bits of HEARTBEAT's `base_mode` (uint8).
namespace mav_mode_flag {
/// MAV_MODE_FLAG_CUSTOM_MODE_ENABLED: custom_mode is meaningful
inline constexpr std::uint8_t kCustomModeEnabled = 1;
inline constexpr std::uint8_t kTestEnabled = 2;          ///< MAV_MODE_FLAG_TEST_ENABLED
inline constexpr std::uint8_t kAutoEnabled = 4;          ///< MAV_MODE_FLAG_AUTO_ENABLED
inline constexpr std::uint8_t kGuidedEnabled = 8;        ///< MAV_MODE_FLAG_GUIDED_ENABLED
inline constexpr std::uint8_t kStabilizeEnabled = 16;    ///< MAV_MODE_FLAG_STABILIZE_ENABLED
inline constexpr std::uint8_t kHilEnabled = 32;          ///< MAV_MODE_FLAG_HIL_ENABLED
inline constexpr std::uint8_t kManualInputEnabled = 64;  ///< MAV_MODE_FLAG_MANUAL_INPUT_ENABLED
inline constexpr std::uint8_t kSafetyArmed = 128;        ///< MAV_MODE_FLAG_SAFETY_ARMED: the motors are armed
}  // namespace mav_mode_flag

/// MAV_TYPE: HEARTBEAT's `type` (uint8), the kind of system that sends it.
namespace mav_type {
inline constexpr std::uint8_t kGeneric = 0;             ///< MAV_TYPE_GENERIC
inline constexpr std::uint8_t kFixedWing = 1;           ///< MAV_TYPE_FIXED_WING
inline constexpr std::uint8_t kQuadrotor = 2;           ///< MAV_TYPE_QUADROTOR
inline constexpr std::uint8_t kHelicopter = 4;          ///< MAV_TYPE_HELICOPTER
inline constexpr std::uint8_t kGcs = 6;                 ///< MAV_TYPE_GCS: a ground station, not a vehicle
inline constexpr std::uint8_t kHexarotor = 13;          ///< MAV_TYPE_HEXAROTOR
inline constexpr std::uint8_t kOctorotor = 14;          ///< MAV_TYPE_OCTOROTOR
inline constexpr std::uint8_t kOnboardController = 18;  ///< MAV_TYPE_ONBOARD_CONTROLLER: a companion computer
inline constexpr std::uint8_t kGimbal = 26;             ///< MAV_TYPE_GIMBAL
inline constexpr std::uint8_t kCamera = 30;             ///< MAV_TYPE_CAMERA
}  // namespace mav_type

/// MAV_AUTOPILOT: HEARTBEAT's `autopilot` (uint8), which firmware sends it.
namespace mav_autopilot {
inline constexpr std::uint8_t kGeneric = 0;        ///< MAV_AUTOPILOT_GENERIC
inline constexpr std::uint8_t kArduPilotMega = 3;  ///< MAV_AUTOPILOT_ARDUPILOTMEGA: ArduPilot
/// MAV_AUTOPILOT_INVALID: not an autopilot (a GCS, a camera, a companion)
inline constexpr std::uint8_t kInvalid = 8;
inline constexpr std::uint8_t kPx4 = 12;  ///< MAV_AUTOPILOT_PX4
}  // namespace mav_autopilot

/// MAV_STATE: HEARTBEAT's `system_status` (uint8).
namespace mav_state {
inline constexpr std::uint8_t kUninit = 0;             ///< MAV_STATE_UNINIT
inline constexpr std::uint8_t kBoot = 1;               ///< MAV_STATE_BOOT
inline constexpr std::uint8_t kCalibrating = 2;        ///< MAV_STATE_CALIBRATING
inline constexpr std::uint8_t kStandby = 3;            ///< MAV_STATE_STANDBY: on the ground, ready
inline constexpr std::uint8_t kActive = 4;             ///< MAV_STATE_ACTIVE: motors engaged or flying
inline constexpr std::uint8_t kCritical = 5;           ///< MAV_STATE_CRITICAL
inline constexpr std::uint8_t kEmergency = 6;          ///< MAV_STATE_EMERGENCY
inline constexpr std::uint8_t kPoweroff = 7;           ///< MAV_STATE_POWEROFF
inline constexpr std::uint8_t kFlightTermination = 8;  ///< MAV_STATE_FLIGHT_TERMINATION
}  // namespace mav_state

/// MAV_LANDED_STATE: EXTENDED_SYS_STATE's `landed_state` (uint8).
namespace mav_landed_state {
inline constexpr std::uint8_t kUndefined = 0;  ///< MAV_LANDED_STATE_UNDEFINED
inline constexpr std::uint8_t kOnGround = 1;   ///< MAV_LANDED_STATE_ON_GROUND
inline constexpr std::uint8_t kInAir = 2;      ///< MAV_LANDED_STATE_IN_AIR
inline constexpr std::uint8_t kTakeoff = 3;    ///< MAV_LANDED_STATE_TAKEOFF
inline constexpr std::uint8_t kLanding = 4;    ///< MAV_LANDED_STATE_LANDING
}  // namespace mav_landed_state

/// MAV_VTOL_STATE: EXTENDED_SYS_STATE's `vtol_state` (uint8).
namespace mav_vtol_state {
inline constexpr std::uint8_t kUndefined = 0;       ///< MAV_VTOL_STATE_UNDEFINED: not a VTOL
inline constexpr std::uint8_t kTransitionToFw = 1;  ///< MAV_VTOL_STATE_TRANSITION_TO_FW
inline constexpr std::uint8_t kTransitionToMc = 2;  ///< MAV_VTOL_STATE_TRANSITION_TO_MC
inline constexpr std::uint8_t kMc = 3;              ///< MAV_VTOL_STATE_MC
inline constexpr std::uint8_t kFw = 4;              ///< MAV_VTOL_STATE_FW
}  // namespace mav_vtol_state

/// MAV_SEVERITY: STATUSTEXT's `severity` (uint8), most severe first.
namespace mav_severity {
inline constexpr std::uint8_t kEmergency = 0;  ///< MAV_SEVERITY_EMERGENCY
inline constexpr std::uint8_t kAlert = 1;      ///< MAV_SEVERITY_ALERT
inline constexpr std::uint8_t kCritical = 2;   ///< MAV_SEVERITY_CRITICAL
inline constexpr std::uint8_t kError = 3;      ///< MAV_SEVERITY_ERROR
inline constexpr std::uint8_t kWarning = 4;    ///< MAV_SEVERITY_WARNING
inline constexpr std::uint8_t kNotice = 5;     ///< MAV_SEVERITY_NOTICE
inline constexpr std::uint8_t kInfo = 6;       ///< MAV_SEVERITY_INFO
inline constexpr std::uint8_t kDebug = 7;      ///< MAV_SEVERITY_DEBUG
}  // namespace mav_severity

/// MAV_COMPONENT: component ids of a frame's sender and of a command's target (uint8).
namespace mav_component {
inline constexpr std::uint8_t kAll = 0;                ///< MAV_COMP_ID_ALL: every component (a target)
inline constexpr std::uint8_t kAutopilot1 = 1;         ///< MAV_COMP_ID_AUTOPILOT1
inline constexpr std::uint8_t kCamera = 100;           ///< MAV_COMP_ID_CAMERA
inline constexpr std::uint8_t kMissionPlanner = 190;   ///< MAV_COMP_ID_MISSIONPLANNER: a GCS
inline constexpr std::uint8_t kOnboardComputer = 191;  ///< MAV_COMP_ID_ONBOARD_COMPUTER: a companion computer
}  // namespace mav_component

/// POSITION_TARGET_TYPEMASK: bits of the position targets' `type_mask` (uint16); a set bit
/// tells the autopilot to ignore that part of the target.
namespace position_target_typemask {
inline constexpr std::uint16_t kXIgnore = 1;           ///< POSITION_TARGET_TYPEMASK_X_IGNORE
inline constexpr std::uint16_t kYIgnore = 2;           ///< POSITION_TARGET_TYPEMASK_Y_IGNORE
inline constexpr std::uint16_t kZIgnore = 4;           ///< POSITION_TARGET_TYPEMASK_Z_IGNORE
inline constexpr std::uint16_t kVxIgnore = 8;          ///< POSITION_TARGET_TYPEMASK_VX_IGNORE
inline constexpr std::uint16_t kVyIgnore = 16;         ///< POSITION_TARGET_TYPEMASK_VY_IGNORE
inline constexpr std::uint16_t kVzIgnore = 32;         ///< POSITION_TARGET_TYPEMASK_VZ_IGNORE
inline constexpr std::uint16_t kAxIgnore = 64;         ///< POSITION_TARGET_TYPEMASK_AX_IGNORE
inline constexpr std::uint16_t kAyIgnore = 128;        ///< POSITION_TARGET_TYPEMASK_AY_IGNORE
inline constexpr std::uint16_t kAzIgnore = 256;        ///< POSITION_TARGET_TYPEMASK_AZ_IGNORE
inline constexpr std::uint16_t kForceSet = 512;        ///< POSITION_TARGET_TYPEMASK_FORCE_SET
inline constexpr std::uint16_t kYawIgnore = 1024;      ///< POSITION_TARGET_TYPEMASK_YAW_IGNORE
inline constexpr std::uint16_t kYawRateIgnore = 2048;  ///< POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE
/// A position only: velocity, acceleration, yaw and yaw rate ignored.
inline constexpr std::uint16_t kPositionOnly =
    kVxIgnore | kVyIgnore | kVzIgnore | kAxIgnore | kAyIgnore | kAzIgnore | kYawIgnore | kYawRateIgnore;
}  // namespace position_target_typemask

}  // namespace adaptseg::mavlink
