#pragma once
/// @file
/// VehicleLink: the live link of a companion computer (or ground station) to a PX4 or ArduPilot
/// autopilot over MAVLink 2, driven by its caller without threads: connect, read the position,
/// fly to a target by guided reposition, wait for arrival, trigger the camera, return home.
/// Every command is acknowledged or sent again a bounded number of times; every wait is bounded;
/// a silent link, a refusal or anything unexpected ends the operation with a VehicleLinkError
/// and the link commands nothing more: the vehicle is left to its own failsafe. CMake target
/// adaptseg::mavlink (docs/mavlink.md, "The vehicle link").
///
/// @code
/// using namespace adaptseg::mavlink;
/// VehicleLink link(open_transport("udpin:14550"), SiteLimits(polygon, /*ceiling_m=*/120.0));
/// link.connect();                                    // heartbeat, streams, 3-D fix
/// for (const LatLonAlt& target : planner_targets) {
///   link.go_to(target);                              // DO_REPOSITION, acknowledged
///   link.wait_arrival(target, {.horizontal_m = 1.0, .vertical_m = 1.0});
///   link.trigger_camera();
///   // ... take and process the image, calling link.poll(link.now() + 0.5) meanwhile ...
/// }
/// link.return_to_launch();
/// @endcode
///
/// Why guided reposition, not an uploaded mission: see the comment above VehicleLink::go_to.

#include <adaptseg/mavlink/camera_image_captured.hpp>
#include <adaptseg/mavlink/command_int.hpp>
#include <adaptseg/mavlink/command_long.hpp>
#include <adaptseg/mavlink/detail/geodesy.hpp>
#include <adaptseg/mavlink/detail/link_channel.hpp>
#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/global_position_int.hpp>
#include <adaptseg/mavlink/gps_raw_int.hpp>
#include <adaptseg/mavlink/link_error.hpp>
#include <adaptseg/mavlink/link_options.hpp>
#include <adaptseg/mavlink/site_limits.hpp>
#include <adaptseg/mavlink/status_text.hpp>
#include <adaptseg/mavlink/transport.hpp>
#include <adaptseg/mavlink/vehicle_mode.hpp>
#include <adaptseg/mavlink/vehicle_state.hpp>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace adaptseg::mavlink {

/// The live link to one autopilot over a ByteTransport, driven synchronously by its caller.
///
/// Each operation blocks until it is done, acknowledged, or failed, reading and dispatching
/// the frames that arrive and sending our HEARTBEAT every LinkOptions::heartbeat_period_s
/// meanwhile; between operations the caller keeps the link alive with poll() (at least once a
/// second: the autopilot's own GCS-loss failsafe watches our heartbeat). Failures throw a
/// VehicleLinkError (LinkLost for a silent link) whose what() is one line naming the step; the
/// link sends no command after one of its own accord (no retry of a refused command, no RTL):
/// the vehicle is left to its own failsafe, the caller decides what else to do.
///
/// Commands: COMMAND_LONG, or COMMAND_INT for DO_REPOSITION, to the autopilot's component;
/// each is sent again after LinkOptions::ack_timeout_s without an answer, up to
/// LinkOptions::command_attempts sends (COMMAND_LONG's `confirmation` counts them);
/// MAV_RESULT_TEMPORARILY_REJECTED is sent again likewise, IN_PROGRESS waited for, any other
/// refusal (DENIED, FAILED, UNSUPPORTED, ...) fails at once.
///
/// Not thread-safe. The clock is injectable (tests drive a fake transport on a fake clock).
class VehicleLink {
 public:
  /// A link over `transport` that never sends the vehicle outside `limits`.
  /// @throws std::invalid_argument from LinkOptions::check().
  VehicleLink(AnyTransport transport, SiteLimits limits, LinkOptions options = {}, Clock clock = {})
      : channel_(std::move(transport), std::move(options), std::move(clock)), limits_(std::move(limits)) {}

  /// The link's clock [s]: deadlines for poll() are on it.
  [[nodiscard]] double now() const { return channel_.now(); }

  /// Waits for the autopilot's HEARTBEAT (LinkOptions::heartbeat_timeout_s), asks for its
  /// GLOBAL_POSITION_INT and GPS_RAW_INT streams (SET_MESSAGE_INTERVAL, acknowledged), then
  /// waits for a 3-D fix (GPS_RAW_INT fix_type >= 3) and a position after it
  /// (LinkOptions::fix_timeout_s). Returns the vehicle's HEARTBEAT.
  /// @throws VehicleLinkError: no_heartbeat, no_gps_fix (the vehicle refuses to start without
  ///         one), refused / no_ack (a stream request), link_lost.
  const VehicleInfo& connect() {
    const char* step = "connect";
    const double t0 = now();
    channel_.announce_at(t0);  // announce ourselves at once: some links talk only to who talks
    if (!channel_.pump_until(
            t0 + options().heartbeat_timeout_s, [&] { return seen().vehicle.has_value(); }, step)) {
      throw VehicleLinkError(LinkFailure::no_heartbeat, step,
                             "no HEARTBEAT from an autopilot within " + num(options().heartbeat_timeout_s) + " s on " +
                                 channel_.description());
    }
    channel_.request_interval(GlobalPositionInt::kId, options().position_interval_s, step);
    channel_.request_interval(GpsRawInt::kId, options().gps_interval_s, step);
    const double t1 = now();
    const auto ready = [&] {
      return seen().gps && seen().gps->fix_type >= gps_fix_type::k3dFix && seen().position &&
             seen().position->received_s >= seen().fix_since_s &&
             !(seen().position->lat_deg == 0.0 && seen().position->lon_deg == 0.0);
    };
    if (!channel_.pump_until(t1 + options().fix_timeout_s, ready, step)) {
      std::string why;
      if (!seen().gps) {
        why = "no GPS_RAW_INT came (no GPS, or the stream request was ignored)";
      } else if (seen().gps->fix_type < gps_fix_type::k3dFix) {
        why = "GPS_RAW_INT says fix_type " + std::to_string(seen().gps->fix_type) + " (" +
              fix_name(seen().gps->fix_type) + "), " + std::to_string(seen().gps->satellites) + " satellites";
      } else {
        why = "a 3-D fix but no valid GLOBAL_POSITION_INT after it";
      }
      throw VehicleLinkError(
          LinkFailure::no_gps_fix, step,
          "no 3-D GPS fix within " + num(options().fix_timeout_s) + " s: " + why + "; refusing to start without one");
    }
    connected_ = true;
    return *seen().vehicle;
  }

  /// Reads and dispatches what arrives, and sends our HEARTBEAT when due, until `deadline_s`
  /// (on now()'s clock). Call it while doing other work between operations.
  /// @throws LinkLost after connect() if the vehicle is silent for LinkOptions::link_timeout_s.
  void poll(double deadline_s) {
    channel_.pump_until(
        deadline_s, [] { return false; }, "poll");
  }

  /// Whether connect() succeeded.
  [[nodiscard]] bool connected() const { return connected_; }

  /// The autopilot's latest HEARTBEAT.
  /// @throws std::logic_error before one was heard (call connect() first).
  [[nodiscard]] const VehicleInfo& vehicle() const {
    if (!seen().vehicle) throw std::logic_error("VehicleLink::vehicle: no autopilot heard yet: call connect() first");
    return *seen().vehicle;
  }

  /// The latest GLOBAL_POSITION_INT (check its received_s against now() for its age).
  /// @throws std::logic_error before one arrived (call connect() first).
  [[nodiscard]] const VehiclePosition& position() const {
    if (!seen().position)
      throw std::logic_error("VehicleLink::position: no GLOBAL_POSITION_INT yet: call connect() first");
    return *seen().position;
  }

  /// The latest GPS_RAW_INT, if one arrived.
  [[nodiscard]] const std::optional<GpsStatus>& gps() const { return seen().gps; }

  // Why guided reposition rather than an uploaded mission that is updated waypoint by
  // waypoint. The planner chooses each waypoint after the previous image, so the vehicle is
  // sent one target at a time. DO_REPOSITION (COMMAND_INT) is one command with one COMMAND_ACK:
  // a lost frame costs one retry of the same, idempotent command, and the acknowledgement says
  // the vehicle took this very target. Updating a mission is the mission protocol's
  // multi-message transaction (MISSION_COUNT, MISSION_REQUEST_INT, MISSION_ITEM_INT ...,
  // MISSION_ACK) per change, plus MISSION_SET_CURRENT and AUTO mode, and a vehicle in AUTO flies
  // on through a stale mission while the upload is retried. Both firmwares take the command in
  // their guided modes (docs/mavlink.md, sources):
  // - PX4: the commander accepts DO_REPOSITION in any mode when param2 has
  //   MAV_DO_REPOSITION_FLAGS_CHANGE_MODE (1), switches to Hold (AUTO_LOITER) and the navigator
  //   flies to the position; newer PX4 answers UNSUPPORTED without that bit
  //   (src/modules/commander/Commander.cpp, handle_command). PX4 copies COMMAND_INT's z into the
  //   command's altitude whatever its frame (mavlink_receiver.cpp) and the navigator reads it
  //   above mean sea level (navigator_main.cpp), as MAVSDK's goto_location sends it; so the
  //   altitude goes out as MAV_FRAME_GLOBAL_INT, home's altitude above sea level (from
  //   GLOBAL_POSITION_INT: alt - relative_alt) plus the target's above home.
  // - ArduPilot (Copter, "Copter Commands in Guided Mode", ardupilot.org/dev/docs/
  //   copter-commands-in-guided-mode.html; GCS_Mavlink.cpp handle_command_int_do_reposition)
  //   answers DENIED unless the vehicle is in GUIDED or the change-mode bit is set, and reads
  //   the altitude in the command's frame (GLOBAL_INT: above sea level, as for PX4). The link
  //   sets GUIDED itself, once, with MAV_CMD_DO_SET_MODE (param1 MAV_MODE_FLAG_CUSTOM_MODE_ENABLED,
  //   param2 the mode number: Copter 4, Plane and Rover 15; "Get and Set FlightMode",
  //   ardupilot.org/dev/docs/mavlink-get-set-flightmode.html) and sees it in the HEARTBEAT;
  //   it sends the reposition without the change-mode bit, so that a vehicle a pilot or a
  //   failsafe took out of GUIDED is never pulled back into it.

  /// Sends the vehicle to `target` by guided reposition: MAV_CMD_DO_REPOSITION in a COMMAND_INT
  /// (MAV_FRAME_GLOBAL_INT, the altitude above sea level from home's), acknowledged (see above).
  /// Refuses, sending nothing, a target outside the SiteLimits, a disarmed vehicle, a vehicle
  /// returning or landing, and one that left the mode the link put it in. On ArduPilot it first
  /// sets GUIDED (once). Returns once the vehicle accepted the target (it is then flying there:
  /// wait_arrival()).
  /// @throws VehicleLinkError: outside_site, not_armed, mode_changed, stale_position, refused,
  ///         no_ack, link_lost.
  void go_to(const LatLonAlt& target) {
    const char* step = "go_to";
    require_connected(step);
    if (const auto why = limits_.violation(target)) {
      throw VehicleLinkError(LinkFailure::outside_site, step,
                             "refused to send the vehicle to " + to_string(target) + ": " + *why);
    }
    channel_.refresh(step);
    if (!seen().vehicle->armed()) {
      throw VehicleLinkError(LinkFailure::not_armed, step,
                             "the vehicle is disarmed: arm it and take off before the live loop sends targets");
    }
    check_mode(step);
    const VehiclePosition here = fresh_position(step);
    if (seen().vehicle->firmware() == Firmware::ardupilot && !in_control_) enter_guided(step);
    CommandInt cmd;
    cmd.target_system = seen().vehicle->system_id;
    cmd.target_component = seen().vehicle->component_id;
    cmd.frame = mav_frame::kGlobalInt;
    cmd.command = mav_cmd::kDoReposition;
    cmd.param1 = static_cast<float>(options().ground_speed_mps);
    cmd.param2 =
        seen().vehicle->firmware() == Firmware::ardupilot ? 0.0F : 1.0F;  // MAV_DO_REPOSITION_FLAGS_CHANGE_MODE
    cmd.param3 = 0.0F;
    cmd.param4 = std::numeric_limits<float>::quiet_NaN();  // yaw: unchanged
    cmd.x = static_cast<std::int32_t>(std::lround(target.lat_deg * 1e7));
    cmd.y = static_cast<std::int32_t>(std::lround(target.lon_deg * 1e7));
    cmd.z = static_cast<float>(here.home_alt_msl_m() + target.rel_alt_m);
    channel_.command(cmd, step);
    in_control_ = true;
    mode_settled_s_ = now() + options().mode_timeout_s;
  }

  /// Waits until the vehicle is within `criteria` of `target` (from GLOBAL_POSITION_INT:
  /// horizontal and vertical distance, and speed if asked) and returns where it was.
  /// @throws VehicleLinkError: stopped_short (no progress for criteria.stall_s while outside the
  ///         tolerance; the message names the distance left), arrival_timeout, mode_changed (the
  ///         pilot or a failsafe took over), stale_position, link_lost;
  ///         std::invalid_argument from ArrivalCriteria::check().
  Arrival wait_arrival(const LatLonAlt& target, const ArrivalCriteria& criteria = {}) {
    const char* step = "wait_arrival";
    criteria.check();
    require_connected(step);
    channel_.refresh(step);
    const double t0 = now();
    double seen_s = -std::numeric_limits<double>::infinity();
    double best_m = std::numeric_limits<double>::infinity();
    double best_s = t0;
    for (;;) {
      check_mode(step);
      const double t = now();
      const bool fresh = channel_.pump_until(
          std::min(t0 + criteria.timeout_s, t + options().position_timeout_s),
          [&] { return seen().position && seen().position->received_s > seen_s; }, step);
      const double t1 = now();
      if (fresh) {
        const VehiclePosition& p = *seen().position;
        seen_s = p.received_s;
        const double h = detail::horizontal_distance_m(target.lat_deg, target.lon_deg, p.lat_deg, p.lon_deg);
        const double v = p.rel_alt_m - target.rel_alt_m;
        if (h <= criteria.horizontal_m && std::fabs(v) <= criteria.vertical_m &&
            p.ground_speed_mps() <= criteria.max_speed_mps) {
          return Arrival{h, v, t1 - t0, p};
        }
        const double left = std::hypot(h, v);
        if (left < best_m - criteria.min_progress_m || !std::isfinite(best_m)) {
          best_m = left;
          best_s = t1;
        } else if (t1 - best_s >= criteria.stall_s) {
          throw VehicleLinkError(LinkFailure::stopped_short, step,
                                 "the vehicle stopped " + num(left) + " m short of " + to_string(target) + " (" +
                                     num(h) + " m horizontally, " + num(std::fabs(v)) +
                                     " m vertically) and made no progress for " + num(t1 - best_s) + " s; tolerance " +
                                     num(criteria.horizontal_m) + " m horizontal, " + num(criteria.vertical_m) +
                                     " m vertical");
        }
      } else if (!seen().position || t1 - seen().position->received_s >= options().position_timeout_s) {
        throw VehicleLinkError(LinkFailure::stale_position, step,
                               "no GLOBAL_POSITION_INT for " + num(options().position_timeout_s) +
                                   " s while the vehicle's other frames still come");
      }
      if (t1 - t0 >= criteria.timeout_s) {
        const std::string left =
            seen().position ? num(detail::horizontal_distance_m(target.lat_deg, target.lon_deg,
                                                                seen().position->lat_deg, seen().position->lon_deg))
                            : std::string("?");
        throw VehicleLinkError(LinkFailure::arrival_timeout, step,
                               "the vehicle did not reach " + to_string(target) + " within " + num(criteria.timeout_s) +
                                   " s (" + left + " m left horizontally)");
      }
    }
  }

  /// Takes one picture with the autopilot's camera: MAV_CMD_IMAGE_START_CAPTURE (one image,
  /// all cameras, a new sequence number so that a retransmission takes no second one) on PX4,
  /// MAV_CMD_DO_DIGICAM_CONTROL (shoot) on ArduPilot, which supports it in every version
  /// (IMAGE_START_CAPTURE only from 4.4; ardupilot.org/dev/docs/mavlink-camera.html), or
  /// LinkOptions::camera_command; acknowledged. Reports the CAMERA_IMAGE_CAPTURED that comes
  /// within LinkOptions::capture_wait_s, if one does.
  /// @throws VehicleLinkError: refused, no_ack, link_lost.
  CameraCapture trigger_camera() {
    const char* step = "trigger_camera";
    require_connected(step);
    channel_.refresh(step);
    CommandLong cmd = channel_.command_long_to_vehicle();
    cmd.command = options().camera_command != 0                       ? options().camera_command
                  : seen().vehicle->firmware() == Firmware::ardupilot ? mav_cmd::kDoDigicamControl
                                                                      : mav_cmd::kImageStartCapture;
    if (cmd.command == mav_cmd::kImageStartCapture) {
      cmd.param1 = 0.0F;  // all cameras
      cmd.param2 = 0.0F;  // interval: none
      cmd.param3 = 1.0F;  // one image
      cmd.param4 = static_cast<float>(++capture_sequence_);
    } else {
      cmd.param5 = 1.0F;  // shoot
    }
    channel_.inbox().images.clear();
    channel_.command(cmd, step);
    if (options().capture_wait_s > 0.0) {
      channel_.pump_until(
          now() + options().capture_wait_s, [&] { return !channel_.inbox().images.empty(); }, step);
    }
    CameraCapture out;
    out.command = cmd.command;
    if (!channel_.inbox().images.empty()) out.image = channel_.inbox().images.back();
    return out;
  }

  /// Sends the vehicle home: MAV_CMD_NAV_RETURN_TO_LAUNCH, acknowledged (the autopilot flies
  /// home at its return altitude and lands). The link stops watching the mode: the vehicle is
  /// in its RTL mode now.
  /// @throws VehicleLinkError: refused, no_ack, link_lost.
  void return_to_launch() {
    const char* step = "return_to_launch";
    require_connected(step);
    channel_.refresh(step);
    CommandLong cmd = channel_.command_long_to_vehicle();
    cmd.command = mav_cmd::kNavReturnToLaunch;
    channel_.command(cmd, step);
    in_control_ = false;
  }

  /// Waits up to `timeout_s` for the vehicle's HEARTBEAT to say it is disarmed (landed after
  /// RTL); true if it did.
  /// @throws LinkLost.
  bool wait_disarmed(double timeout_s) {
    require_connected("wait_disarmed");
    return channel_.pump_until(
        now() + timeout_s, [&] { return !seen().vehicle->armed(); }, "wait_disarmed");
  }

  /// The latest STATUSTEXT from the vehicle, if any (PreArm and failsafe messages).
  [[nodiscard]] const std::optional<StatusText>& last_status_text() const { return seen().status_text; }

  /// Counts of frames, commands and retries.
  [[nodiscard]] LinkStats stats() const { return channel_.stats(); }

  [[nodiscard]] const SiteLimits& limits() const { return limits_; }                ///< the site's limits
  [[nodiscard]] const LinkOptions& options() const { return channel_.options(); }   ///< the settings
  [[nodiscard]] std::string description() const { return channel_.description(); }  ///< the transport

  /// Bytes read from the transport at a time: a UDP datagram of the largest size.
  static constexpr std::size_t kReceiveBufferSize = detail::LinkChannel::kReceiveBufferSize;

 private:
  // What the vehicle has told the link.
  [[nodiscard]] const detail::VehicleInbox& seen() const { return channel_.inbox(); }

  // Puts ArduPilot in GUIDED and waits for its HEARTBEAT to say so.
  void enter_guided(const char* step) {
    const std::optional<std::uint32_t> mode =
        options().ardupilot_guided_mode ? options().ardupilot_guided_mode : ardupilot_guided_mode(seen().vehicle->type);
    if (!mode) {
      throw VehicleLinkError(LinkFailure::refused, step,
                             "ArduPilot's GUIDED mode number for MAV_TYPE " + std::to_string(seen().vehicle->type) +
                                 " is unknown: set LinkOptions::ardupilot_guided_mode");
    }
    if (seen().vehicle->custom_mode != *mode) {
      CommandLong cmd = channel_.command_long_to_vehicle();
      cmd.command = mav_cmd::kDoSetMode;
      cmd.param1 = static_cast<float>(mav_mode_flag::kCustomModeEnabled);
      cmd.param2 = static_cast<float>(*mode);
      channel_.command(cmd, step);
      const double t = now();
      if (!channel_.pump_until(
              t + options().mode_timeout_s,
              [&] { return seen().vehicle->received_s > t && seen().vehicle->custom_mode == *mode; }, step)) {
        throw VehicleLinkError(LinkFailure::refused, step,
                               "the vehicle acknowledged DO_SET_MODE " +
                                   mode_name(Firmware::ardupilot, seen().vehicle->type, *mode) +
                                   " but its HEARTBEAT still says " + seen().vehicle->mode() + " after " +
                                   num(options().mode_timeout_s) + " s");
      }
    }
    guided_mode_ = *mode;
  }

  // The mode a vehicle under our control must be in.
  std::uint32_t expected_mode() const {
    return seen().vehicle->firmware() == Firmware::px4 ? px4_mode::kHold : guided_mode_;
  }

  // Throws mode_changed if the vehicle is returning or landing, or left the mode we put it in
  // (judged on a HEARTBEAT that came after the mode had time to show).
  void check_mode(const char* step) const {
    const VehicleInfo& v = *seen().vehicle;
    if (is_returning_or_landing(v.firmware(), v.type, v.custom_mode)) {
      throw VehicleLinkError(LinkFailure::mode_changed, step,
                             "the vehicle is in " + v.mode() +
                                 " (a failsafe or the pilot is bringing it home): the link does not command it");
    }
    if (in_control_ && v.firmware() != Firmware::other && v.received_s > mode_settled_s_ &&
        v.custom_mode != expected_mode()) {
      throw VehicleLinkError(LinkFailure::mode_changed, step,
                             "the vehicle left " + mode_name(v.firmware(), v.type, expected_mode()) + " for " +
                                 v.mode() + " (the pilot or a failsafe took over): the link stops commanding it");
    }
  }

  // The latest position, read just now and younger than position_timeout_s.
  VehiclePosition fresh_position(const char* step) const {
    if (!seen().position || now() - seen().position->received_s >= options().position_timeout_s) {
      throw VehicleLinkError(LinkFailure::stale_position, step,
                             "no GLOBAL_POSITION_INT in the last " + num(options().position_timeout_s) + " s");
    }
    return *seen().position;
  }

  void require_connected(const char* step) const {
    if (!connected_) throw std::logic_error(std::string("VehicleLink::") + step + ": call connect() first");
  }

  // `x` to `decimals` digits after the point, for messages.
  static std::string num(double x, int decimals = 1) { return detail::LinkChannel::num(x, decimals); }

  static std::string fix_name(std::uint8_t fix_type) {
    switch (fix_type) {
      case gps_fix_type::kNoGps: return "no GPS";
      case gps_fix_type::kNoFix: return "no fix";
      case gps_fix_type::k2dFix: return "2-D fix";
      default: return "fix";
    }
  }

  detail::LinkChannel channel_;
  SiteLimits limits_;
  bool connected_ = false;
  bool in_control_ = false;        // a go_to was accepted since connect() or the last RTL
  std::uint32_t guided_mode_ = 0;  // ArduPilot's GUIDED number, once set
  double mode_settled_s_ = 0.0;    // the mode a go_to asked for shows in HEARTBEATs after this
  std::uint32_t capture_sequence_ = 0;
};

}  // namespace adaptseg::mavlink
