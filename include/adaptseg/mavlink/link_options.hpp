#pragma once
/// @file
/// The settings of a VehicleLink (LinkOptions: who it is, how long it waits, how often it asks
/// again) and of one wait for arrival (ArrivalCriteria), each checked once with check(). CMake
/// target adaptseg::mavlink (docs/mavlink.md, "Timeouts, retries, identity").

#include <adaptseg/mavlink/enums.hpp>

#include <cmath>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace adaptseg::mavlink {

/// The settings of a VehicleLink: who it is, how long it waits, how often it asks again.
/// Checked once, by the VehicleLink constructor (check()).
struct LinkOptions {
  /// Our system id: 255, a ground station's, whose heartbeat ArduPilot's GCS failsafe watches (SYSID_MYGCS).
  std::uint8_t system_id = 255;
  std::uint8_t component_id = mav_component::kMissionPlanner;  ///< our component id (190, as QGroundControl)
  /// Our HEARTBEAT's type: a ground station's, whose heartbeat PX4's data-link-loss failsafe watches.
  std::uint8_t heartbeat_type = mav_type::kGcs;
  std::uint8_t vehicle_system_id = 0;   ///< the autopilot's system id to talk to (0: the first autopilot heard)
  double heartbeat_period_s = 1.0;      ///< our HEARTBEAT period [s] (MAVLink: 1 Hz)
  double heartbeat_timeout_s = 10.0;    ///< connect(): longest wait for the autopilot's first HEARTBEAT [s]
  double fix_timeout_s = 30.0;          ///< connect(): longest wait for a 3-D fix and a position [s]
  double link_timeout_s = 3.0;          ///< no frame from the vehicle this long: the link is lost [s]
  double ack_timeout_s = 1.0;           ///< wait for a COMMAND_ACK before sending the command again [s]
  int command_attempts = 4;             ///< sends of one command at most (the first and the retries), 1..100
  double in_progress_timeout_s = 10.0;  ///< longest wait after MAV_RESULT_IN_PROGRESS for the final answer [s]
  double position_interval_s = 0.1;     ///< GLOBAL_POSITION_INT period asked for (SET_MESSAGE_INTERVAL) [s]
  double gps_interval_s = 0.5;          ///< GPS_RAW_INT period asked for [s]
  double position_timeout_s = 2.0;      ///< no GLOBAL_POSITION_INT this long while frames come: stale [s]
  double mode_timeout_s = 3.0;          ///< time for a mode change to show in the HEARTBEAT [s]
  double ground_speed_mps = -1.0;       ///< DO_REPOSITION's ground speed [m/s] (-1: the vehicle's default)
  double capture_wait_s = 1.0;          ///< trigger_camera(): wait this long for CAMERA_IMAGE_CAPTURED [s] (0: none)
  /// trigger_camera()'s command: 0 by firmware (PX4: IMAGE_START_CAPTURE, ArduPilot:
  /// DO_DIGICAM_CONTROL), or mav_cmd::kImageStartCapture, mav_cmd::kDoDigicamControl.
  std::uint16_t camera_command = 0;
  /// ArduPilot's GUIDED mode number (nullopt: from the HEARTBEAT's MAV_TYPE, ardupilot_guided_mode()).
  std::optional<std::uint32_t> ardupilot_guided_mode{};

  /// @throws std::invalid_argument naming the field and its value
  ///         (`"LinkOptions: ack_timeout_s must be finite and > 0 (got -1.000000)"`).
  void check() const {
    const auto positive = [](double v, const char* name) {
      if (!std::isfinite(v) || v <= 0.0) {
        throw std::invalid_argument(std::string("LinkOptions: ") + name + " must be finite and > 0 (got " +
                                    std::to_string(v) + ")");
      }
    };
    if (system_id == 0) throw std::invalid_argument("LinkOptions: system_id must be 1..255 (got 0)");
    positive(heartbeat_period_s, "heartbeat_period_s");
    positive(heartbeat_timeout_s, "heartbeat_timeout_s");
    positive(fix_timeout_s, "fix_timeout_s");
    positive(link_timeout_s, "link_timeout_s");
    positive(ack_timeout_s, "ack_timeout_s");
    positive(in_progress_timeout_s, "in_progress_timeout_s");
    positive(position_interval_s, "position_interval_s");
    positive(gps_interval_s, "gps_interval_s");
    positive(position_timeout_s, "position_timeout_s");
    positive(mode_timeout_s, "mode_timeout_s");
    if (command_attempts < 1 || command_attempts > 100) {
      throw std::invalid_argument("LinkOptions: command_attempts must be 1..100 (got " +
                                  std::to_string(command_attempts) + ")");
    }
    if (!(ground_speed_mps == -1.0 || (std::isfinite(ground_speed_mps) && ground_speed_mps > 0.0))) {
      throw std::invalid_argument(
          "LinkOptions: ground_speed_mps must be -1 (the vehicle's default) or finite and > 0 "
          "(got " +
          std::to_string(ground_speed_mps) + ")");
    }
    if (!std::isfinite(capture_wait_s) || capture_wait_s < 0.0) {
      throw std::invalid_argument("LinkOptions: capture_wait_s must be finite and >= 0 (got " +
                                  std::to_string(capture_wait_s) + ")");
    }
    if (camera_command != 0 && camera_command != mav_cmd::kImageStartCapture &&
        camera_command != mav_cmd::kDoDigicamControl) {
      throw std::invalid_argument(
          "LinkOptions: camera_command must be 0 (by firmware), 2000 (IMAGE_START_CAPTURE) or "
          "203 (DO_DIGICAM_CONTROL) (got " +
          std::to_string(camera_command) + ")");
    }
  }
};

/// When wait_arrival() counts the vehicle as there, and how long it waits.
struct ArrivalCriteria {
  double horizontal_m = 1.0;  ///< horizontal distance to the target at most [m]
  double vertical_m = 1.0;    ///< vertical distance at most [m]
  /// Horizontal speed at most [m/s] (infinity: not checked): the vehicle has settled.
  double max_speed_mps = std::numeric_limits<double>::infinity();
  double timeout_s = 300.0;     ///< longest wait [s]
  double stall_s = 5.0;         ///< no progress this long, outside the tolerance: stopped short [s]
  double min_progress_m = 0.2;  ///< what counts as progress: the distance left shrinks by this much [m]

  /// @throws std::invalid_argument naming the field and its value.
  void check() const {
    const auto positive = [](double v, const char* name) {
      if (!std::isfinite(v) || v <= 0.0) {
        throw std::invalid_argument(std::string("ArrivalCriteria: ") + name + " must be finite and > 0 (got " +
                                    std::to_string(v) + ")");
      }
    };
    positive(horizontal_m, "horizontal_m");
    positive(vertical_m, "vertical_m");
    positive(timeout_s, "timeout_s");
    positive(stall_s, "stall_s");
    positive(min_progress_m, "min_progress_m");
    if (std::isnan(max_speed_mps) || max_speed_mps <= 0.0) {
      throw std::invalid_argument("ArrivalCriteria: max_speed_mps must be > 0 (got " + std::to_string(max_speed_mps) +
                                  ")");
    }
  }
};

}  // namespace adaptseg::mavlink
