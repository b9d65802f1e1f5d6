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
#include <adaptseg/mavlink/command_ack.hpp>
#include <adaptseg/mavlink/command_int.hpp>
#include <adaptseg/mavlink/command_long.hpp>
#include <adaptseg/mavlink/detail/geodesy.hpp>
#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/frame.hpp>
#include <adaptseg/mavlink/global_position_int.hpp>
#include <adaptseg/mavlink/gps_raw_int.hpp>
#include <adaptseg/mavlink/heartbeat.hpp>
#include <adaptseg/mavlink/link_error.hpp>
#include <adaptseg/mavlink/link_options.hpp>
#include <adaptseg/mavlink/message.hpp>
#include <adaptseg/mavlink/parser.hpp>
#include <adaptseg/mavlink/site_limits.hpp>
#include <adaptseg/mavlink/status_text.hpp>
#include <adaptseg/mavlink/transport.hpp>
#include <adaptseg/mavlink/vehicle_mode.hpp>
#include <adaptseg/mavlink/vehicle_state.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace adaptseg::mavlink {

/// The link's clock: seconds, monotonic, any origin. Tests give a fake one.
using Clock = std::function<double()>;

/// std::chrono::steady_clock in seconds: the default Clock.
[[nodiscard]] inline double steady_clock_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

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
      : transport_(std::move(transport)),
        limits_(std::move(limits)),
        options_(std::move(options)),
        clock_(clock ? std::move(clock) : Clock(&steady_clock_s)),
        buffer_(kReceiveBufferSize) {
    options_.check();
  }

  /// The link's clock [s]: deadlines for poll() are on it.
  [[nodiscard]] double now() const { return clock_(); }

  /// Waits for the autopilot's HEARTBEAT (LinkOptions::heartbeat_timeout_s), asks for its
  /// GLOBAL_POSITION_INT and GPS_RAW_INT streams (SET_MESSAGE_INTERVAL, acknowledged), then
  /// waits for a 3-D fix (GPS_RAW_INT fix_type >= 3) and a position after it
  /// (LinkOptions::fix_timeout_s). Returns the vehicle's HEARTBEAT.
  /// @throws VehicleLinkError: no_heartbeat, no_gps_fix (the vehicle refuses to start without
  ///         one), refused / no_ack (a stream request), link_lost.
  const VehicleInfo& connect() {
    const char* step = "connect";
    const double t0 = now();
    next_heartbeat_s_ = t0;  // announce ourselves at once: some links talk only to who talks
    if (!pump_until(
            t0 + options_.heartbeat_timeout_s, [&] { return vehicle_.has_value(); }, step)) {
      throw VehicleLinkError(LinkFailure::no_heartbeat, step,
                             "no HEARTBEAT from an autopilot within " + num(options_.heartbeat_timeout_s) + " s on " +
                                 transport_.description());
    }
    request_interval(GlobalPositionInt::kId, options_.position_interval_s, step);
    request_interval(GpsRawInt::kId, options_.gps_interval_s, step);
    const double t1 = now();
    const auto ready = [&] {
      return gps_ && gps_->fix_type >= gps_fix_type::k3dFix && position_ && position_->received_s >= fix_since_s_ &&
             !(position_->lat_deg == 0.0 && position_->lon_deg == 0.0);
    };
    if (!pump_until(t1 + options_.fix_timeout_s, ready, step)) {
      std::string why;
      if (!gps_) {
        why = "no GPS_RAW_INT came (no GPS, or the stream request was ignored)";
      } else if (gps_->fix_type < gps_fix_type::k3dFix) {
        why = "GPS_RAW_INT says fix_type " + std::to_string(gps_->fix_type) + " (" + fix_name(gps_->fix_type) + "), " +
              std::to_string(gps_->satellites) + " satellites";
      } else {
        why = "a 3-D fix but no valid GLOBAL_POSITION_INT after it";
      }
      throw VehicleLinkError(
          LinkFailure::no_gps_fix, step,
          "no 3-D GPS fix within " + num(options_.fix_timeout_s) + " s: " + why + "; refusing to start without one");
    }
    connected_ = true;
    return *vehicle_;
  }

  /// Reads and dispatches what arrives, and sends our HEARTBEAT when due, until `deadline_s`
  /// (on now()'s clock). Call it while doing other work between operations.
  /// @throws LinkLost after connect() if the vehicle is silent for LinkOptions::link_timeout_s.
  void poll(double deadline_s) {
    pump_until(
        deadline_s, [] { return false; }, "poll");
  }

  /// Whether connect() succeeded.
  [[nodiscard]] bool connected() const { return connected_; }

  /// The autopilot's latest HEARTBEAT.
  /// @throws std::logic_error before one was heard (call connect() first).
  [[nodiscard]] const VehicleInfo& vehicle() const {
    if (!vehicle_) throw std::logic_error("VehicleLink::vehicle: no autopilot heard yet: call connect() first");
    return *vehicle_;
  }

  /// The latest GLOBAL_POSITION_INT (check its received_s against now() for its age).
  /// @throws std::logic_error before one arrived (call connect() first).
  [[nodiscard]] const VehiclePosition& position() const {
    if (!position_) throw std::logic_error("VehicleLink::position: no GLOBAL_POSITION_INT yet: call connect() first");
    return *position_;
  }

  /// The latest GPS_RAW_INT, if one arrived.
  [[nodiscard]] const std::optional<GpsStatus>& gps() const { return gps_; }

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
    refresh(step);
    if (!vehicle_->armed()) {
      throw VehicleLinkError(LinkFailure::not_armed, step,
                             "the vehicle is disarmed: arm it and take off before the live loop sends targets");
    }
    check_mode(step);
    const VehiclePosition here = fresh_position(step);
    if (vehicle_->firmware() == Firmware::ardupilot && !in_control_) enter_guided(step);
    CommandInt cmd;
    cmd.target_system = vehicle_->system_id;
    cmd.target_component = vehicle_->component_id;
    cmd.frame = mav_frame::kGlobalInt;
    cmd.command = mav_cmd::kDoReposition;
    cmd.param1 = static_cast<float>(options_.ground_speed_mps);
    cmd.param2 = vehicle_->firmware() == Firmware::ardupilot ? 0.0F : 1.0F;  // MAV_DO_REPOSITION_FLAGS_CHANGE_MODE
    cmd.param3 = 0.0F;
    cmd.param4 = std::numeric_limits<float>::quiet_NaN();  // yaw: unchanged
    cmd.x = static_cast<std::int32_t>(std::lround(target.lat_deg * 1e7));
    cmd.y = static_cast<std::int32_t>(std::lround(target.lon_deg * 1e7));
    cmd.z = static_cast<float>(here.home_alt_msl_m() + target.rel_alt_m);
    command(cmd, step);
    in_control_ = true;
    mode_settled_s_ = now() + options_.mode_timeout_s;
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
    refresh(step);
    const double t0 = now();
    double seen_s = -std::numeric_limits<double>::infinity();
    double best_m = std::numeric_limits<double>::infinity();
    double best_s = t0;
    for (;;) {
      check_mode(step);
      const double t = now();
      const bool fresh = pump_until(
          std::min(t0 + criteria.timeout_s, t + options_.position_timeout_s),
          [&] { return position_ && position_->received_s > seen_s; }, step);
      const double t1 = now();
      if (fresh) {
        const VehiclePosition& p = *position_;
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
      } else if (!position_ || t1 - position_->received_s >= options_.position_timeout_s) {
        throw VehicleLinkError(LinkFailure::stale_position, step,
                               "no GLOBAL_POSITION_INT for " + num(options_.position_timeout_s) +
                                   " s while the vehicle's other frames still come");
      }
      if (t1 - t0 >= criteria.timeout_s) {
        const std::string left = position_ ? num(detail::horizontal_distance_m(target.lat_deg, target.lon_deg,
                                                                               position_->lat_deg, position_->lon_deg))
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
    refresh(step);
    CommandLong cmd = command_long_to_vehicle();
    cmd.command = options_.camera_command != 0                  ? options_.camera_command
                  : vehicle_->firmware() == Firmware::ardupilot ? mav_cmd::kDoDigicamControl
                                                                : mav_cmd::kImageStartCapture;
    if (cmd.command == mav_cmd::kImageStartCapture) {
      cmd.param1 = 0.0F;  // all cameras
      cmd.param2 = 0.0F;  // interval: none
      cmd.param3 = 1.0F;  // one image
      cmd.param4 = static_cast<float>(++capture_sequence_);
    } else {
      cmd.param5 = 1.0F;  // shoot
    }
    images_.clear();
    command(cmd, step);
    if (options_.capture_wait_s > 0.0) {
      pump_until(
          now() + options_.capture_wait_s, [&] { return !images_.empty(); }, step);
    }
    CameraCapture out;
    out.command = cmd.command;
    if (!images_.empty()) out.image = images_.back();
    return out;
  }

  /// Sends the vehicle home: MAV_CMD_NAV_RETURN_TO_LAUNCH, acknowledged (the autopilot flies
  /// home at its return altitude and lands). The link stops watching the mode: the vehicle is
  /// in its RTL mode now.
  /// @throws VehicleLinkError: refused, no_ack, link_lost.
  void return_to_launch() {
    const char* step = "return_to_launch";
    require_connected(step);
    refresh(step);
    CommandLong cmd = command_long_to_vehicle();
    cmd.command = mav_cmd::kNavReturnToLaunch;
    command(cmd, step);
    in_control_ = false;
  }

  /// Waits up to `timeout_s` for the vehicle's HEARTBEAT to say it is disarmed (landed after
  /// RTL); true if it did.
  /// @throws LinkLost.
  bool wait_disarmed(double timeout_s) {
    require_connected("wait_disarmed");
    return pump_until(
        now() + timeout_s, [&] { return !vehicle_->armed(); }, "wait_disarmed");
  }

  /// The latest STATUSTEXT from the vehicle, if any (PreArm and failsafe messages).
  [[nodiscard]] const std::optional<StatusText>& last_status_text() const { return last_status_text_; }

  /// Counts of frames, commands and retries.
  [[nodiscard]] LinkStats stats() const {
    LinkStats s = stats_;
    s.parse = parser_.stats();
    return s;
  }

  [[nodiscard]] const SiteLimits& limits() const { return limits_; }                  ///< the site's limits
  [[nodiscard]] const LinkOptions& options() const { return options_; }               ///< the settings
  [[nodiscard]] std::string description() const { return transport_.description(); }  ///< the transport

  /// Bytes read from the transport at a time: a UDP datagram of the largest size.
  static constexpr std::size_t kReceiveBufferSize = 65536;

 private:
  // --- the loop: receive, dispatch, heartbeat, link loss ---

  // Runs the link until done() or deadline_s; false if the deadline came first.
  template <typename Done>
  bool pump_until(double deadline_s, Done&& done, const char* step) {
    for (;;) {
      if (done()) return true;
      const double t = now();
      if (vehicle_ && t - last_vehicle_frame_s_ >= options_.link_timeout_s) {
        if (drain(step) > 0) continue;  // frames that waited while the caller was busy
        throw_link_lost(step, t);
      }
      if (t >= deadline_s) return false;
      send_heartbeat_if_due(t);
      double until = std::min(deadline_s, next_heartbeat_s_);
      if (vehicle_) until = std::min(until, last_vehicle_frame_s_ + options_.link_timeout_s);
      receive_once(std::max(0.0, until - t));
    }
  }

  // Reads what waited while the caller was busy, then throws LinkLost if the vehicle has still
  // been silent too long: every operation starts here, so that none sends to a lost link.
  void refresh(const char* step) {
    drain(step);
    const double t = now();
    if (vehicle_ && t - last_vehicle_frame_s_ >= options_.link_timeout_s) throw_link_lost(step, t);
  }

  [[noreturn]] void throw_link_lost(const char* step, double t) const {
    throw LinkLost(step, "no frame from the vehicle (system " + std::to_string(vehicle_->system_id) + ") for " +
                             num(t - last_vehicle_frame_s_) + " s on " + transport_.description() +
                             ": the link is lost; the vehicle is left to its own failsafe");
  }

  // Reads what is waiting, without waiting; the bytes read.
  std::size_t drain(const char*) {
    std::size_t total = 0;
    for (int i = 0; i < 100000; ++i) {
      const std::size_t n = receive_once(0.0);
      if (n == 0) break;
      total += n;
    }
    return total;
  }

  std::size_t receive_once(double timeout_s) {
    const std::size_t n = transport_.receive(buffer_, timeout_s);
    if (n == 0) return 0;
    parser_.feed(std::span<const std::uint8_t>(buffer_.data(), n));
    while (const std::optional<Frame> frame = parser_.next()) dispatch(*frame);
    return n;
  }

  void send_heartbeat_if_due(double t) {
    if (t < next_heartbeat_s_) return;
    Heartbeat hb;
    hb.type = options_.heartbeat_type;
    hb.autopilot = mav_autopilot::kInvalid;
    hb.base_mode = 0;
    hb.custom_mode = 0;
    hb.system_status = mav_state::kActive;
    send(hb);
    ++stats_.heartbeats_sent;
    next_heartbeat_s_ += options_.heartbeat_period_s;
    if (next_heartbeat_s_ <= t) next_heartbeat_s_ = t + options_.heartbeat_period_s;
  }

  template <MessageType M>
  void send(const M& msg) {
    transport_.send(encode(msg, FrameHeader{sequence_++, options_.system_id, options_.component_id}));
    ++stats_.frames_sent;
  }

  static bool is_autopilot(const Heartbeat& hb) {
    return hb.autopilot != mav_autopilot::kInvalid && hb.type != mav_type::kGcs &&
           hb.type != mav_type::kOnboardController && hb.type != mav_type::kCamera && hb.type != mav_type::kGimbal;
  }

  void dispatch(const Frame& frame) {
    if (frame.system_id == options_.system_id && frame.component_id == options_.component_id) return;  // ours, echoed
    const Message msg = decode(frame);
    const double t = now();
    if (!vehicle_) {
      const auto* hb = std::get_if<Heartbeat>(&msg);
      if (hb == nullptr || !is_autopilot(*hb)) return;
      if (options_.vehicle_system_id != 0 && frame.system_id != options_.vehicle_system_id) return;
      vehicle_ = VehicleInfo{};
      vehicle_->system_id = frame.system_id;
      vehicle_->component_id = frame.component_id;
    }
    if (frame.system_id != vehicle_->system_id) return;
    last_vehicle_frame_s_ = t;
    ++stats_.frames_received;
    if (const auto* hb = std::get_if<Heartbeat>(&msg)) {
      if (frame.component_id != vehicle_->component_id) return;  // a camera's, a gimbal's
      vehicle_->autopilot = hb->autopilot;
      vehicle_->type = hb->type;
      vehicle_->base_mode = hb->base_mode;
      vehicle_->custom_mode = hb->custom_mode;
      vehicle_->system_status = hb->system_status;
      vehicle_->received_s = t;
    } else if (const auto* gp = std::get_if<GlobalPositionInt>(&msg)) {
      VehiclePosition p;
      p.lat_deg = gp->lat * 1e-7;
      p.lon_deg = gp->lon * 1e-7;
      p.alt_msl_m = gp->alt * 1e-3;
      p.rel_alt_m = gp->relative_alt * 1e-3;
      p.vn_mps = gp->vx * 1e-2;
      p.ve_mps = gp->vy * 1e-2;
      p.vd_mps = gp->vz * 1e-2;
      if (gp->hdg != std::numeric_limits<std::uint16_t>::max()) p.heading_deg = gp->hdg * 1e-2;
      p.time_boot_ms = gp->time_boot_ms;
      p.received_s = t;
      position_ = p;
    } else if (const auto* gps = std::get_if<GpsRawInt>(&msg)) {
      if (gps->fix_type >= gps_fix_type::k3dFix && (!gps_ || gps_->fix_type < gps_fix_type::k3dFix)) fix_since_s_ = t;
      gps_ = GpsStatus{gps->fix_type, gps->satellites_visible, t};
    } else if (const auto* ack = std::get_if<CommandAck>(&msg)) {
      // The extension fields name the command's sender where the firmware fills them.
      if ((ack->target_system == 0 || ack->target_system == options_.system_id) &&
          (ack->target_component == 0 || ack->target_component == options_.component_id)) {
        acks_.push_back(*ack);
        ++stats_.acks_received;
      }
    } else if (const auto* image = std::get_if<CameraImageCaptured>(&msg)) {
      images_.push_back(*image);
    } else if (const auto* text = std::get_if<StatusText>(&msg)) {
      last_status_text_ = *text;
      last_status_text_s_ = t;
    }
  }

  // --- commands ---

  CommandLong command_long_to_vehicle() const {
    CommandLong cmd;
    cmd.target_system = vehicle_->system_id;
    cmd.target_component = vehicle_->component_id;
    return cmd;
  }

  std::optional<CommandAck> take_ack(std::uint16_t command) {
    const auto it = std::find_if(acks_.begin(), acks_.end(), [&](const CommandAck& a) { return a.command == command; });
    if (it == acks_.end()) return std::nullopt;
    const CommandAck ack = *it;
    acks_.erase(it);
    return ack;
  }

  // Sends `cmd` until it is acknowledged; see the class comment for the rules.
  template <typename Command>
  CommandAck command(Command cmd, const char* step) {
    const std::uint16_t id = cmd.command;
    acks_.clear();
    const double started_s = now();
    bool temporarily_rejected = false;
    for (int attempt = 1; attempt <= options_.command_attempts; ++attempt) {
      if constexpr (std::is_same_v<Command, CommandLong>) {
        cmd.confirmation = static_cast<std::uint8_t>(std::min(attempt - 1, 255));
      }
      send(cmd);
      ++stats_.commands_sent;
      if (attempt > 1) ++stats_.command_retries;
      const double sent_s = now();
      double deadline_s = sent_s + options_.ack_timeout_s;
      for (;;) {
        std::optional<CommandAck> ack;
        if (!pump_until(
                deadline_s, [&] { return (ack = take_ack(id)).has_value(); }, step))
          break;
        if (ack->result == mav_result::kAccepted) return *ack;
        if (ack->result == mav_result::kInProgress) {  // a final answer follows
          deadline_s = std::min(now() + options_.ack_timeout_s, sent_s + options_.in_progress_timeout_s);
          continue;
        }
        if (ack->result == mav_result::kTemporarilyRejected) {  // try again once this attempt's time is up
          temporarily_rejected = true;
          pump_until(
              deadline_s, [] { return false; }, step);
          break;
        }
        throw VehicleLinkError(
            LinkFailure::refused, step,
            "the vehicle refused " + command_name(id) + ": " + result_name(ack->result) + vehicle_says(started_s));
      }
    }
    if (temporarily_rejected) {
      throw VehicleLinkError(LinkFailure::no_ack, step,
                             command_name(id) + " was TEMPORARILY_REJECTED, " +
                                 std::to_string(options_.command_attempts) + " attempts in " + num(now() - started_s) +
                                 " s" + vehicle_says(started_s));
    }
    throw VehicleLinkError(LinkFailure::no_ack, step,
                           "no COMMAND_ACK for " + command_name(id) + " after " +
                               std::to_string(options_.command_attempts) + " attempts, " + num(options_.ack_timeout_s) +
                               " s each");
  }

  // " (the vehicle says: ...)" for a warning or worse STATUSTEXT since `since_s`.
  std::string vehicle_says(double since_s) const {
    if (!last_status_text_ || last_status_text_s_ < since_s || last_status_text_->severity > mav_severity::kWarning) {
      return {};
    }
    return " (the vehicle says: \"" + last_status_text_->text + "\")";
  }

  void request_interval(std::uint32_t message_id, double interval_s, const char* step) {
    CommandLong cmd = command_long_to_vehicle();
    cmd.command = mav_cmd::kSetMessageInterval;
    cmd.param1 = static_cast<float>(message_id);
    cmd.param2 = static_cast<float>(interval_s * 1e6);
    command(cmd, step);
  }

  // Puts ArduPilot in GUIDED and waits for its HEARTBEAT to say so.
  void enter_guided(const char* step) {
    const std::optional<std::uint32_t> mode =
        options_.ardupilot_guided_mode ? options_.ardupilot_guided_mode : ardupilot_guided_mode(vehicle_->type);
    if (!mode) {
      throw VehicleLinkError(LinkFailure::refused, step,
                             "ArduPilot's GUIDED mode number for MAV_TYPE " + std::to_string(vehicle_->type) +
                                 " is unknown: set LinkOptions::ardupilot_guided_mode");
    }
    if (vehicle_->custom_mode != *mode) {
      CommandLong cmd = command_long_to_vehicle();
      cmd.command = mav_cmd::kDoSetMode;
      cmd.param1 = static_cast<float>(mav_mode_flag::kCustomModeEnabled);
      cmd.param2 = static_cast<float>(*mode);
      command(cmd, step);
      const double t = now();
      if (!pump_until(
              t + options_.mode_timeout_s, [&] { return vehicle_->received_s > t && vehicle_->custom_mode == *mode; },
              step)) {
        throw VehicleLinkError(
            LinkFailure::refused, step,
            "the vehicle acknowledged DO_SET_MODE " + mode_name(Firmware::ardupilot, vehicle_->type, *mode) +
                " but its HEARTBEAT still says " + vehicle_->mode() + " after " + num(options_.mode_timeout_s) + " s");
      }
    }
    guided_mode_ = *mode;
  }

  // The mode a vehicle under our control must be in.
  std::uint32_t expected_mode() const { return vehicle_->firmware() == Firmware::px4 ? px4_mode::kHold : guided_mode_; }

  // Throws mode_changed if the vehicle is returning or landing, or left the mode we put it in
  // (judged on a HEARTBEAT that came after the mode had time to show).
  void check_mode(const char* step) const {
    const VehicleInfo& v = *vehicle_;
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
    if (!position_ || now() - position_->received_s >= options_.position_timeout_s) {
      throw VehicleLinkError(LinkFailure::stale_position, step,
                             "no GLOBAL_POSITION_INT in the last " + num(options_.position_timeout_s) + " s");
    }
    return *position_;
  }

  void require_connected(const char* step) const {
    if (!connected_) throw std::logic_error(std::string("VehicleLink::") + step + ": call connect() first");
  }

  // `x` to `decimals` digits after the point, for messages.
  static std::string num(double x, int decimals = 1) { return detail::fixed_text(x, decimals); }

  static std::string fix_name(std::uint8_t fix_type) {
    switch (fix_type) {
      case gps_fix_type::kNoGps: return "no GPS";
      case gps_fix_type::kNoFix: return "no fix";
      case gps_fix_type::k2dFix: return "2-D fix";
      default: return "fix";
    }
  }

  AnyTransport transport_;
  SiteLimits limits_;
  LinkOptions options_;
  Clock clock_;
  Parser parser_;
  std::vector<std::uint8_t> buffer_;
  std::uint8_t sequence_ = 0;
  double next_heartbeat_s_ = -std::numeric_limits<double>::infinity();
  double last_vehicle_frame_s_ = 0.0;
  std::optional<VehicleInfo> vehicle_;
  std::optional<VehiclePosition> position_;
  std::optional<GpsStatus> gps_;
  double fix_since_s_ = 0.0;
  std::vector<CommandAck> acks_;
  std::vector<CameraImageCaptured> images_;
  std::optional<StatusText> last_status_text_;
  double last_status_text_s_ = 0.0;
  bool connected_ = false;
  bool in_control_ = false;        // a go_to was accepted since connect() or the last RTL
  std::uint32_t guided_mode_ = 0;  // ArduPilot's GUIDED number, once set
  double mode_settled_s_ = 0.0;    // the mode a go_to asked for shows in HEARTBEATs after this
  std::uint32_t capture_sequence_ = 0;
  LinkStats stats_;
};

}  // namespace adaptseg::mavlink
