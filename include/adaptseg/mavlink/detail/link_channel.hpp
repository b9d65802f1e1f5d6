#pragma once
/// @file
/// Internals of vehicle_link.hpp: the link's channel to one autopilot. It reads and dispatches
/// frames into what the vehicle said (VehicleInbox), sends our HEARTBEAT when due, watches for a
/// silent vehicle (LinkLost), and sends commands until they are acknowledged (the rules in
/// VehicleLink's class comment). VehicleLink flies with it: what to command, and when.

#include <adaptseg/mavlink/camera_image_captured.hpp>
#include <adaptseg/mavlink/command_ack.hpp>
#include <adaptseg/mavlink/command_int.hpp>
#include <adaptseg/mavlink/command_long.hpp>
#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/frame.hpp>
#include <adaptseg/mavlink/global_position_int.hpp>
#include <adaptseg/mavlink/gps_raw_int.hpp>
#include <adaptseg/mavlink/heartbeat.hpp>
#include <adaptseg/mavlink/link_error.hpp>
#include <adaptseg/mavlink/link_options.hpp>
#include <adaptseg/mavlink/message.hpp>
#include <adaptseg/mavlink/parser.hpp>
#include <adaptseg/mavlink/status_text.hpp>
#include <adaptseg/mavlink/transport.hpp>
#include <adaptseg/mavlink/vehicle_state.hpp>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <optional>
#include <span>
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

}  // namespace adaptseg::mavlink

namespace adaptseg::detail {

/// What the vehicle has told the link: its HEARTBEAT, position, GPS, the acknowledgements and
/// captures not yet taken, its latest STATUSTEXT, and when its last frame came.
struct VehicleInbox {
  std::optional<mavlink::VehicleInfo> vehicle;
  std::optional<mavlink::VehiclePosition> position;
  std::optional<mavlink::GpsStatus> gps;
  double fix_since_s = 0.0;  ///< when the current 3-D fix began
  std::vector<mavlink::CommandAck> acks;
  std::vector<mavlink::CameraImageCaptured> images;
  std::optional<mavlink::StatusText> status_text;
  double status_text_s = 0.0;
  double last_frame_s = 0.0;
};

/// The channel to one autopilot over a ByteTransport (see the file comment). Not thread-safe.
class LinkChannel {
 public:
  /// Bytes read from the transport at a time: a UDP datagram of the largest size.
  static constexpr std::size_t kReceiveBufferSize = 65536;

  /// @throws std::invalid_argument from mavlink::LinkOptions::check().
  LinkChannel(mavlink::AnyTransport transport, mavlink::LinkOptions options, mavlink::Clock clock)
      : transport_(std::move(transport)),
        options_(std::move(options)),
        clock_(clock ? std::move(clock) : mavlink::Clock(&mavlink::steady_clock_s)),
        buffer_(kReceiveBufferSize) {
    options_.check();
  }

  [[nodiscard]] double now() const { return clock_(); }
  [[nodiscard]] const mavlink::LinkOptions& options() const { return options_; }
  [[nodiscard]] std::string description() const { return transport_.description(); }
  [[nodiscard]] const VehicleInbox& inbox() const { return in_; }
  [[nodiscard]] VehicleInbox& inbox() { return in_; }
  /// Our next HEARTBEAT at `t`, not at the next period (some links talk only to who talks).
  void announce_at(double t) { next_heartbeat_s_ = t; }

  /// Counts of frames, commands and retries.
  [[nodiscard]] mavlink::LinkStats stats() const {
    mavlink::LinkStats s = stats_;
    s.parse = parser_.stats();
    return s;
  }

  /// Runs the link until done() or deadline_s; false if the deadline came first.
  /// @throws mavlink::LinkLost once the vehicle was heard and is silent for mavlink::LinkOptions::link_timeout_s.
  template <typename Done>
  bool pump_until(double deadline_s, Done&& done, const char* step) {
    for (;;) {
      if (done()) return true;
      const double t = now();
      if (in_.vehicle && t - in_.last_frame_s >= options_.link_timeout_s) {
        if (drain() > 0) continue;  // frames that waited while the caller was busy
        throw_link_lost(step, t);
      }
      if (t >= deadline_s) return false;
      send_heartbeat_if_due(t);
      double until = std::min(deadline_s, next_heartbeat_s_);
      if (in_.vehicle) until = std::min(until, in_.last_frame_s + options_.link_timeout_s);
      receive_once(std::max(0.0, until - t));
    }
  }

  /// Reads what waited while the caller was busy, then throws mavlink::LinkLost if the vehicle has still
  /// been silent too long: every operation starts here, so that none sends to a lost link.
  void refresh(const char* step) {
    drain();
    const double t = now();
    if (in_.vehicle && t - in_.last_frame_s >= options_.link_timeout_s) throw_link_lost(step, t);
  }

  /// A COMMAND_LONG addressed to the autopilot.
  [[nodiscard]] mavlink::CommandLong command_long_to_vehicle() const {
    mavlink::CommandLong cmd;
    cmd.target_system = in_.vehicle->system_id;
    cmd.target_component = in_.vehicle->component_id;
    return cmd;
  }

  /// Sends `cmd` until it is acknowledged; see VehicleLink's class comment for the rules.
  /// @throws mavlink::VehicleLinkError: refused, no_ack; mavlink::LinkLost.
  template <typename Command>
  mavlink::CommandAck command(Command cmd, const char* step) {
    const std::uint16_t id = cmd.command;
    in_.acks.clear();
    const double started_s = now();
    bool temporarily_rejected = false;
    for (int attempt = 1; attempt <= options_.command_attempts; ++attempt) {
      if constexpr (std::is_same_v<Command, mavlink::CommandLong>) {
        cmd.confirmation = static_cast<std::uint8_t>(std::min(attempt - 1, 255));
      }
      send(cmd);
      ++stats_.commands_sent;
      if (attempt > 1) ++stats_.command_retries;
      if (const std::optional<mavlink::CommandAck> ack = await_ack(id, started_s, temporarily_rejected, step))
        return *ack;
    }
    if (temporarily_rejected) {
      throw mavlink::VehicleLinkError(mavlink::LinkFailure::no_ack, step,
                                      mavlink::command_name(id) + " was TEMPORARILY_REJECTED, " +
                                          std::to_string(options_.command_attempts) + " attempts in " +
                                          num(now() - started_s) + " s" + vehicle_says(started_s));
    }
    throw mavlink::VehicleLinkError(mavlink::LinkFailure::no_ack, step,
                                    "no COMMAND_ACK for " + mavlink::command_name(id) + " after " +
                                        std::to_string(options_.command_attempts) + " attempts, " +
                                        num(options_.ack_timeout_s) + " s each");
  }

  /// SET_MESSAGE_INTERVAL for `message_id`, acknowledged.
  void request_interval(std::uint32_t message_id, double interval_s, const char* step) {
    mavlink::CommandLong cmd = command_long_to_vehicle();
    cmd.command = mavlink::mav_cmd::kSetMessageInterval;
    cmd.param1 = static_cast<float>(message_id);
    cmd.param2 = static_cast<float>(interval_s * 1e6);
    command(cmd, step);
  }

  /// " (the vehicle says: ...)" for a warning or worse STATUSTEXT since `since_s`.
  [[nodiscard]] std::string vehicle_says(double since_s) const {
    if (!in_.status_text || in_.status_text_s < since_s ||
        in_.status_text->severity > mavlink::mav_severity::kWarning) {
      return {};
    }
    return " (the vehicle says: \"" + in_.status_text->text + "\")";
  }

  /// `x` to `decimals` digits after the point, for messages.
  static std::string num(double x, int decimals = 1) { return fixed_text(x, decimals); }

 private:
  // One attempt of command(): waits out its acknowledgement. The ack if accepted; nullopt if
  // this attempt's time ran out (after a TEMPORARILY_REJECTED, `temporarily_rejected` set).
  std::optional<mavlink::CommandAck> await_ack(std::uint16_t id, double started_s, bool& temporarily_rejected,
                                               const char* step) {
    const double sent_s = now();
    double deadline_s = sent_s + options_.ack_timeout_s;
    for (;;) {
      std::optional<mavlink::CommandAck> ack;
      if (!pump_until(
              deadline_s, [&] { return (ack = take_ack(id)).has_value(); }, step))
        return std::nullopt;
      if (ack->result == mavlink::mav_result::kAccepted) return ack;
      if (ack->result == mavlink::mav_result::kInProgress) {  // a final answer follows
        deadline_s = std::min(now() + options_.ack_timeout_s, sent_s + options_.in_progress_timeout_s);
        continue;
      }
      if (ack->result == mavlink::mav_result::kTemporarilyRejected) {  // try again once this attempt's time is up
        temporarily_rejected = true;
        pump_until(
            deadline_s, [] { return false; }, step);
        return std::nullopt;
      }
      throw mavlink::VehicleLinkError(mavlink::LinkFailure::refused, step,
                                      "the vehicle refused " + mavlink::command_name(id) + ": " +
                                          mavlink::result_name(ack->result) + vehicle_says(started_s));
    }
  }

  [[noreturn]] void throw_link_lost(const char* step, double t) const {
    throw mavlink::LinkLost(step, "no frame from the vehicle (system " + std::to_string(in_.vehicle->system_id) +
                                      ") for " + num(t - in_.last_frame_s) + " s on " + transport_.description() +
                                      ": the link is lost; the vehicle is left to its own failsafe");
  }

  // Reads what is waiting, without waiting; the bytes read.
  std::size_t drain() {
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
    while (const std::optional<mavlink::Frame> frame = parser_.next()) dispatch(*frame);
    return n;
  }

  void send_heartbeat_if_due(double t) {
    if (t < next_heartbeat_s_) return;
    mavlink::Heartbeat hb;
    hb.type = options_.heartbeat_type;
    hb.autopilot = mavlink::mav_autopilot::kInvalid;
    hb.base_mode = 0;
    hb.custom_mode = 0;
    hb.system_status = mavlink::mav_state::kActive;
    send(hb);
    ++stats_.heartbeats_sent;
    next_heartbeat_s_ += options_.heartbeat_period_s;
    if (next_heartbeat_s_ <= t) next_heartbeat_s_ = t + options_.heartbeat_period_s;
  }

  template <mavlink::MessageType M>
  void send(const M& msg) {
    transport_.send(mavlink::encode(msg, mavlink::FrameHeader{sequence_++, options_.system_id, options_.component_id}));
    ++stats_.frames_sent;
  }

  static bool is_autopilot(const mavlink::Heartbeat& hb) {
    return hb.autopilot != mavlink::mav_autopilot::kInvalid && hb.type != mavlink::mav_type::kGcs &&
           hb.type != mavlink::mav_type::kOnboardController && hb.type != mavlink::mav_type::kCamera &&
           hb.type != mavlink::mav_type::kGimbal;
  }

  // Whether `frame` is the vehicle's: the first autopilot heard (mavlink::LinkOptions::vehicle_system_id,
  // if set) is the vehicle; frames of other systems are dropped.
  bool from_vehicle(const mavlink::Frame& frame, const mavlink::Message& msg) {
    if (!in_.vehicle) {
      const auto* hb = std::get_if<mavlink::Heartbeat>(&msg);
      if (hb == nullptr || !is_autopilot(*hb)) return false;
      if (options_.vehicle_system_id != 0 && frame.system_id != options_.vehicle_system_id) return false;
      in_.vehicle = mavlink::VehicleInfo{};
      in_.vehicle->system_id = frame.system_id;
      in_.vehicle->component_id = frame.component_id;
    }
    return frame.system_id == in_.vehicle->system_id;
  }

  void dispatch(const mavlink::Frame& frame) {
    if (frame.system_id == options_.system_id && frame.component_id == options_.component_id) return;  // ours, echoed
    const mavlink::Message msg = mavlink::decode(frame);
    const double t = now();
    if (!from_vehicle(frame, msg)) return;
    in_.last_frame_s = t;
    ++stats_.frames_received;
    if (const auto* hb = std::get_if<mavlink::Heartbeat>(&msg)) {
      if (frame.component_id != in_.vehicle->component_id) return;  // a camera's, a gimbal's
      in_.vehicle->autopilot = hb->autopilot;
      in_.vehicle->type = hb->type;
      in_.vehicle->base_mode = hb->base_mode;
      in_.vehicle->custom_mode = hb->custom_mode;
      in_.vehicle->system_status = hb->system_status;
      in_.vehicle->received_s = t;
    } else if (const auto* gp = std::get_if<mavlink::GlobalPositionInt>(&msg)) {
      in_.position = position_of(*gp, t);
    } else if (const auto* gps = std::get_if<mavlink::GpsRawInt>(&msg)) {
      if (gps->fix_type >= mavlink::gps_fix_type::k3dFix &&
          (!in_.gps || in_.gps->fix_type < mavlink::gps_fix_type::k3dFix))
        in_.fix_since_s = t;
      in_.gps = mavlink::GpsStatus{gps->fix_type, gps->satellites_visible, t};
    } else if (const auto* ack = std::get_if<mavlink::CommandAck>(&msg)) {
      // The extension fields name the command's sender where the firmware fills them.
      if ((ack->target_system == 0 || ack->target_system == options_.system_id) &&
          (ack->target_component == 0 || ack->target_component == options_.component_id)) {
        in_.acks.push_back(*ack);
        ++stats_.acks_received;
      }
    } else if (const auto* image = std::get_if<mavlink::CameraImageCaptured>(&msg)) {
      in_.images.push_back(*image);
    } else if (const auto* text = std::get_if<mavlink::StatusText>(&msg)) {
      in_.status_text = *text;
      in_.status_text_s = t;
    }
  }

  static mavlink::VehiclePosition position_of(const mavlink::GlobalPositionInt& gp, double t) {
    mavlink::VehiclePosition p;
    p.lat_deg = gp.lat * 1e-7;
    p.lon_deg = gp.lon * 1e-7;
    p.alt_msl_m = gp.alt * 1e-3;
    p.rel_alt_m = gp.relative_alt * 1e-3;
    p.vn_mps = gp.vx * 1e-2;
    p.ve_mps = gp.vy * 1e-2;
    p.vd_mps = gp.vz * 1e-2;
    if (gp.hdg != std::numeric_limits<std::uint16_t>::max()) p.heading_deg = gp.hdg * 1e-2;
    p.time_boot_ms = gp.time_boot_ms;
    p.received_s = t;
    return p;
  }

  std::optional<mavlink::CommandAck> take_ack(std::uint16_t command) {
    const auto it = std::find_if(in_.acks.begin(), in_.acks.end(),
                                 [&](const mavlink::CommandAck& a) { return a.command == command; });
    if (it == in_.acks.end()) return std::nullopt;
    const mavlink::CommandAck ack = *it;
    in_.acks.erase(it);
    return ack;
  }

  mavlink::AnyTransport transport_;
  mavlink::LinkOptions options_;
  mavlink::Clock clock_;
  mavlink::Parser parser_;
  std::vector<std::uint8_t> buffer_;
  std::uint8_t sequence_ = 0;
  double next_heartbeat_s_ = -std::numeric_limits<double>::infinity();
  VehicleInbox in_;
  mavlink::LinkStats stats_;
};

}  // namespace adaptseg::detail
