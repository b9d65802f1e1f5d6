#pragma once
/// @file
/// What a VehicleLink throws when an operation cannot be done: VehicleLinkError, one line that
/// names the step and what happened, and a LinkFailure to branch on; LinkLost for a link that
/// went silent; and the names its messages give commands and results. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/enums.hpp>

#include <cstdint>
#include <cstdio>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>

namespace adaptseg::detail {

/// `x` with `decimals` digits after the point (`"2.0"`), for the link's messages.
[[nodiscard]] inline std::string fixed_text(double x, int decimals = 1) {
  char text[64];
  std::snprintf(text, sizeof(text), "%.*f", decimals, x);
  return text;
}

}  // namespace adaptseg::detail

namespace adaptseg::mavlink {

/// `"DO_REPOSITION (192)"`: a MAV_CMD the link sends, by name and number.
[[nodiscard]] inline std::string command_name(std::uint16_t command) {
  const char* name = nullptr;
  switch (command) {
    case mav_cmd::kNavReturnToLaunch: name = "NAV_RETURN_TO_LAUNCH"; break;
    case mav_cmd::kDoSetMode: name = "DO_SET_MODE"; break;
    case mav_cmd::kDoReposition: name = "DO_REPOSITION"; break;
    case mav_cmd::kDoDigicamControl: name = "DO_DIGICAM_CONTROL"; break;
    case mav_cmd::kSetMessageInterval: name = "SET_MESSAGE_INTERVAL"; break;
    case mav_cmd::kImageStartCapture: name = "IMAGE_START_CAPTURE"; break;
    default: return "command " + std::to_string(command);
  }
  return std::string(name) + " (" + std::to_string(command) + ")";
}

/// `"MAV_RESULT_DENIED"`: a COMMAND_ACK result by name.
[[nodiscard]] inline std::string result_name(std::uint8_t result) {
  switch (result) {
    case mav_result::kAccepted: return "MAV_RESULT_ACCEPTED";
    case mav_result::kTemporarilyRejected: return "MAV_RESULT_TEMPORARILY_REJECTED";
    case mav_result::kDenied: return "MAV_RESULT_DENIED";
    case mav_result::kUnsupported: return "MAV_RESULT_UNSUPPORTED";
    case mav_result::kFailed: return "MAV_RESULT_FAILED";
    case mav_result::kInProgress: return "MAV_RESULT_IN_PROGRESS";
    case mav_result::kCancelled: return "MAV_RESULT_CANCELLED";
    case mav_result::kCommandLongOnly: return "MAV_RESULT_COMMAND_LONG_ONLY";
    case mav_result::kCommandIntOnly: return "MAV_RESULT_COMMAND_INT_ONLY";
    case mav_result::kCommandUnsupportedMavFrame: return "MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME";
    default: return "MAV_RESULT " + std::to_string(result);
  }
}

/// Why a VehicleLink operation failed. In every case the link has stopped commanding: the
/// vehicle is left to its own failsafe (docs/mavlink.md, "The vehicle link").
enum class LinkFailure {
  no_heartbeat,     ///< connect(): no HEARTBEAT from an autopilot in time
  no_gps_fix,       ///< connect(): no 3-D GPS fix (or no position) in time
  link_lost,        ///< no frame from the vehicle for LinkOptions::link_timeout_s (thrown as LinkLost)
  refused,          ///< the vehicle answered a command DENIED, FAILED, UNSUPPORTED, ... or did not take a mode
  no_ack,           ///< no COMMAND_ACK after every attempt (or only TEMPORARILY_REJECTED)
  outside_site,     ///< a target outside the SiteLimits: never sent
  not_armed,        ///< a target for a vehicle that is disarmed: never sent
  mode_changed,     ///< the vehicle left the mode the link put it in (the pilot or a failsafe took over)
  stopped_short,    ///< wait_arrival(): no progress while still outside the tolerance
  arrival_timeout,  ///< wait_arrival(): not within the tolerance in time
  stale_position,   ///< no GLOBAL_POSITION_INT for LinkOptions::position_timeout_s while frames still come
};

/// `"link_lost"`, `"refused"`, ...: the enumerator's name.
[[nodiscard]] constexpr std::string_view to_string(LinkFailure f) {
  switch (f) {
    case LinkFailure::no_heartbeat: return "no_heartbeat";
    case LinkFailure::no_gps_fix: return "no_gps_fix";
    case LinkFailure::link_lost: return "link_lost";
    case LinkFailure::refused: return "refused";
    case LinkFailure::no_ack: return "no_ack";
    case LinkFailure::outside_site: return "outside_site";
    case LinkFailure::not_armed: return "not_armed";
    case LinkFailure::mode_changed: return "mode_changed";
    case LinkFailure::stopped_short: return "stopped_short";
    case LinkFailure::arrival_timeout: return "arrival_timeout";
    case LinkFailure::stale_position: return "stale_position";
  }
  return "unknown";
}

/// A VehicleLink operation that could not be done. what() is one line, `"<step>: <what
/// happened>"` (`"go_to: the vehicle refused DO_REPOSITION (192): MAV_RESULT_DENIED"`).
class VehicleLinkError : public std::runtime_error {
 public:
  VehicleLinkError(LinkFailure failure, std::string step, const std::string& what)
      : std::runtime_error(step + ": " + what), failure_(failure), step_(std::move(step)) {}

  /// Why it failed.
  [[nodiscard]] LinkFailure failure() const { return failure_; }
  /// The operation that failed: `"connect"`, `"go_to"`, `"wait_arrival"`, `"trigger_camera"`,
  /// `"return_to_launch"`, `"poll"`, ...
  [[nodiscard]] const std::string& step() const { return step_; }

 private:
  LinkFailure failure_;
  std::string step_;
};

/// The link went silent: no frame from the vehicle for LinkOptions::link_timeout_s. Its
/// failure() is LinkFailure::link_lost.
class LinkLost : public VehicleLinkError {
 public:
  LinkLost(std::string step, const std::string& what)
      : VehicleLinkError(LinkFailure::link_lost, std::move(step), what) {}
};

}  // namespace adaptseg::mavlink
