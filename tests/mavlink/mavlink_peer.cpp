// adaptseg::mavlink's side of the live cross-check with node-mavlink (CTest mavlink:node_peer,
// run by run_node_peer.sh; node_peer.mjs is the other side).
//
//   adaptseg_mavlink_peer write FILE [N]  N random frames per message, encoded by adaptseg, in
//                                         the line format of frame_lines.hpp
//   adaptseg_mavlink_peer check FILE      decode the frames node-mavlink wrote, as one stream in
//                                         random chunks: every frame found, header and every
//                                         field as the line says, and encoding them again
//                                         gives node-mavlink's bytes
//   adaptseg_mavlink_peer constants FILE  the named constants, "MAV_CMD_DO_REPOSITION 192"
// Exit 0 if all is well, 1 with one line per problem otherwise.

#include "frame_lines.hpp"

#include <adaptseg/mavlink.hpp>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <random>
#include <string>
#include <utility>
#include <vector>

namespace {

namespace mv = adaptseg::mavlink;
namespace t = adaptseg::mavlink::test;

void write_random(std::ofstream& out, std::mt19937_64& rng, int count, std::uint8_t& seq) {
  t::for_each_message_type([&](auto tag) {
    using M = typename decltype(tag)::type;
    for (int i = 0; i < count; ++i) {
      // The first all zeros (a 1-byte payload), then few, some or most fields zero.
      const double zero_p = i == 0 ? 1.0 : std::array{0.0, 0.3, 0.8}[static_cast<std::size_t>(i % 3)];
      const mv::Message msg = t::random_message<M>(rng, zero_p);
      const mv::FrameHeader h{seq++, static_cast<std::uint8_t>(rng()), static_cast<std::uint8_t>(rng())};
      out << t::to_line(msg, h, mv::encode(msg, h)) << '\n';
    }
  });
}

int write(const std::string& file, int count) {
  std::ofstream out(file);
  out << "# Frames encoded by adaptseg::mavlink (adaptseg_mavlink_peer write); line format: frame_lines.hpp\n";
  std::mt19937_64 rng(20261127);
  std::uint8_t seq = 0;
  write_random(out, rng, count, seq);
  if (!out) {
    std::cerr << "mavlink_peer: cannot write " << file << '\n';
    return 1;
  }
  std::cout << "mavlink_peer: " << file << ": " << count * static_cast<int>(std::variant_size_v<mv::Message>)
            << " frames written by adaptseg::mavlink\n";
  return 0;
}

int check(const std::string& file) {
  const std::vector<t::FrameLine> lines = t::read_lines(file);
  std::vector<std::uint8_t> stream;
  for (const auto& l : lines) stream.insert(stream.end(), l.bytes.begin(), l.bytes.end());
  mv::Parser parser;
  std::vector<mv::Frame> frames;
  std::mt19937_64 rng(7);
  for (std::size_t at = 0; at < stream.size();) {
    const std::size_t n = std::min(stream.size() - at, std::uniform_int_distribution<std::size_t>(1, 64)(rng));
    parser.feed(std::span<const std::uint8_t>(stream.data() + at, n));
    at += n;
    while (auto f = parser.next()) frames.push_back(std::move(*f));
  }
  int problems = 0;
  const auto problem = [&](const std::string& text) {
    if (++problems <= 50) std::cerr << "mavlink_peer: " << text << '\n';
  };
  const mv::ParseStats& s = parser.stats();
  const std::uint64_t rejected = s.crc_errors + s.unknown_ids + s.incompatible_flags + s.dropped_bytes;
  if (frames.size() != lines.size() || rejected != 0) {
    problem(file + ": " + std::to_string(lines.size()) + " frames written, " + std::to_string(frames.size()) +
            " accepted (checksum errors " + std::to_string(s.crc_errors) + ", unknown ids " +
            std::to_string(s.unknown_ids) + ", dropped bytes " + std::to_string(s.dropped_bytes) + ")");
  }
  int identical = 0, zero_payload = 0, signed_frames = 0, v1_frames = 0;
  for (std::size_t i = 0; i < std::min(frames.size(), lines.size()); ++i) {
    const mv::Frame& f = frames[i];
    const t::FrameLine& line = lines[i];
    const std::string where = "line " + std::to_string(line.line_number) + " (" + line.name + ")";
    if (f.header() != line.header) problem(where + ": header differs");
    const mv::Message msg = mv::decode(f);
    for (const std::string& p : t::compare(msg, line)) problem(where + ": " + p);
    if (f.signature) {
      ++signed_frames;
      const std::vector<std::uint8_t> tail(line.bytes.end() - 13, line.bytes.end());
      if (f.signature->link_id != tail[0] ||
          !std::equal(f.signature->signature.begin(), f.signature->signature.end(), tail.begin() + 7)) {
        problem(where + ": signature fields differ from the frame's last 13 bytes");
      }
      continue;  // adaptseg does not sign: nothing to compare bytes with
    }
    if (f.version == mv::ProtocolVersion::v1) {
      ++v1_frames;
      continue;  // adaptseg writes MAVLink 2 only
    }
    const std::vector<std::uint8_t> ours = mv::encode(msg, f.header());
    if (ours == line.bytes) {
      ++identical;
    } else if (line.bytes[1] == 0 && ours[1] == 1 && ours[10] == 0) {
      ++zero_payload;  // node-mavlink sends an all-zero payload with length 0, MAVLink 2 keeps one byte
    } else {
      problem(where + ": adaptseg encodes " + t::to_hex(ours) + ", node-mavlink wrote " + t::to_hex(line.bytes));
    }
  }
  std::cout << "mavlink_peer: " << file << ": " << frames.size() << " of " << lines.size()
            << " node-mavlink frames decoded, every field checked (" << signed_frames << " signed, " << v1_frames
            << " MAVLink 1); " << identical << " byte-identical when adaptseg encodes them again, " << zero_payload
            << " all-zero payloads (node-mavlink: length 0, adaptseg: 1)\n";
  if (problems > 0) std::cerr << "mavlink_peer: " << problems << " problem(s)\n";
  return problems == 0 ? 0 : 1;
}

int constants(const std::string& file) {
  const std::vector<std::pair<const char*, long>> table = {
      {"MAV_CMD_NAV_WAYPOINT", mv::mav_cmd::kNavWaypoint},
      {"MAV_CMD_NAV_RETURN_TO_LAUNCH", mv::mav_cmd::kNavReturnToLaunch},
      {"MAV_CMD_NAV_LAND", mv::mav_cmd::kNavLand},
      {"MAV_CMD_NAV_TAKEOFF", mv::mav_cmd::kNavTakeoff},
      {"MAV_CMD_DO_SET_MODE", mv::mav_cmd::kDoSetMode},
      {"MAV_CMD_DO_REPOSITION", mv::mav_cmd::kDoReposition},
      {"MAV_CMD_DO_DIGICAM_CONTROL", mv::mav_cmd::kDoDigicamControl},
      {"MAV_CMD_COMPONENT_ARM_DISARM", mv::mav_cmd::kComponentArmDisarm},
      {"MAV_CMD_SET_MESSAGE_INTERVAL", mv::mav_cmd::kSetMessageInterval},
      {"MAV_CMD_REQUEST_MESSAGE", mv::mav_cmd::kRequestMessage},
      {"MAV_CMD_IMAGE_START_CAPTURE", mv::mav_cmd::kImageStartCapture},
      {"MAV_RESULT_ACCEPTED", mv::mav_result::kAccepted},
      {"MAV_RESULT_TEMPORARILY_REJECTED", mv::mav_result::kTemporarilyRejected},
      {"MAV_RESULT_DENIED", mv::mav_result::kDenied},
      {"MAV_RESULT_UNSUPPORTED", mv::mav_result::kUnsupported},
      {"MAV_RESULT_FAILED", mv::mav_result::kFailed},
      {"MAV_RESULT_IN_PROGRESS", mv::mav_result::kInProgress},
      {"MAV_RESULT_CANCELLED", mv::mav_result::kCancelled},
      {"MAV_RESULT_COMMAND_LONG_ONLY", mv::mav_result::kCommandLongOnly},
      {"MAV_RESULT_COMMAND_INT_ONLY", mv::mav_result::kCommandIntOnly},
      {"MAV_RESULT_COMMAND_UNSUPPORTED_MAV_FRAME", mv::mav_result::kCommandUnsupportedMavFrame},
      {"MAV_FRAME_GLOBAL", mv::mav_frame::kGlobal},
      {"MAV_FRAME_GLOBAL_RELATIVE_ALT", mv::mav_frame::kGlobalRelativeAlt},
      {"MAV_FRAME_GLOBAL_INT", mv::mav_frame::kGlobalInt},
      {"MAV_FRAME_GLOBAL_RELATIVE_ALT_INT", mv::mav_frame::kGlobalRelativeAltInt},
      {"GPS_FIX_TYPE_NO_GPS", mv::gps_fix_type::kNoGps},
      {"GPS_FIX_TYPE_NO_FIX", mv::gps_fix_type::kNoFix},
      {"GPS_FIX_TYPE_2D_FIX", mv::gps_fix_type::k2dFix},
      {"GPS_FIX_TYPE_3D_FIX", mv::gps_fix_type::k3dFix},
      {"GPS_FIX_TYPE_DGPS", mv::gps_fix_type::kDgps},
      {"GPS_FIX_TYPE_RTK_FLOAT", mv::gps_fix_type::kRtkFloat},
      {"GPS_FIX_TYPE_RTK_FIXED", mv::gps_fix_type::kRtkFixed},
      {"GPS_FIX_TYPE_STATIC", mv::gps_fix_type::kStatic},
      {"GPS_FIX_TYPE_PPP", mv::gps_fix_type::kPpp},
      {"MAV_MODE_FLAG_CUSTOM_MODE_ENABLED", mv::mav_mode_flag::kCustomModeEnabled},
      {"MAV_MODE_FLAG_TEST_ENABLED", mv::mav_mode_flag::kTestEnabled},
      {"MAV_MODE_FLAG_AUTO_ENABLED", mv::mav_mode_flag::kAutoEnabled},
      {"MAV_MODE_FLAG_GUIDED_ENABLED", mv::mav_mode_flag::kGuidedEnabled},
      {"MAV_MODE_FLAG_STABILIZE_ENABLED", mv::mav_mode_flag::kStabilizeEnabled},
      {"MAV_MODE_FLAG_HIL_ENABLED", mv::mav_mode_flag::kHilEnabled},
      {"MAV_MODE_FLAG_MANUAL_INPUT_ENABLED", mv::mav_mode_flag::kManualInputEnabled},
      {"MAV_MODE_FLAG_SAFETY_ARMED", mv::mav_mode_flag::kSafetyArmed},
      {"MAV_TYPE_GENERIC", mv::mav_type::kGeneric},
      {"MAV_TYPE_FIXED_WING", mv::mav_type::kFixedWing},
      {"MAV_TYPE_QUADROTOR", mv::mav_type::kQuadrotor},
      {"MAV_TYPE_HELICOPTER", mv::mav_type::kHelicopter},
      {"MAV_TYPE_GCS", mv::mav_type::kGcs},
      {"MAV_TYPE_HEXAROTOR", mv::mav_type::kHexarotor},
      {"MAV_TYPE_OCTOROTOR", mv::mav_type::kOctorotor},
      {"MAV_TYPE_ONBOARD_CONTROLLER", mv::mav_type::kOnboardController},
      {"MAV_TYPE_GIMBAL", mv::mav_type::kGimbal},
      {"MAV_TYPE_CAMERA", mv::mav_type::kCamera},
      {"MAV_AUTOPILOT_GENERIC", mv::mav_autopilot::kGeneric},
      {"MAV_AUTOPILOT_ARDUPILOTMEGA", mv::mav_autopilot::kArduPilotMega},
      {"MAV_AUTOPILOT_INVALID", mv::mav_autopilot::kInvalid},
      {"MAV_AUTOPILOT_PX4", mv::mav_autopilot::kPx4},
      {"MAV_STATE_UNINIT", mv::mav_state::kUninit},
      {"MAV_STATE_BOOT", mv::mav_state::kBoot},
      {"MAV_STATE_CALIBRATING", mv::mav_state::kCalibrating},
      {"MAV_STATE_STANDBY", mv::mav_state::kStandby},
      {"MAV_STATE_ACTIVE", mv::mav_state::kActive},
      {"MAV_STATE_CRITICAL", mv::mav_state::kCritical},
      {"MAV_STATE_EMERGENCY", mv::mav_state::kEmergency},
      {"MAV_STATE_POWEROFF", mv::mav_state::kPoweroff},
      {"MAV_STATE_FLIGHT_TERMINATION", mv::mav_state::kFlightTermination},
      {"MAV_LANDED_STATE_UNDEFINED", mv::mav_landed_state::kUndefined},
      {"MAV_LANDED_STATE_ON_GROUND", mv::mav_landed_state::kOnGround},
      {"MAV_LANDED_STATE_IN_AIR", mv::mav_landed_state::kInAir},
      {"MAV_LANDED_STATE_TAKEOFF", mv::mav_landed_state::kTakeoff},
      {"MAV_LANDED_STATE_LANDING", mv::mav_landed_state::kLanding},
      {"MAV_VTOL_STATE_UNDEFINED", mv::mav_vtol_state::kUndefined},
      {"MAV_VTOL_STATE_TRANSITION_TO_FW", mv::mav_vtol_state::kTransitionToFw},
      {"MAV_VTOL_STATE_TRANSITION_TO_MC", mv::mav_vtol_state::kTransitionToMc},
      {"MAV_VTOL_STATE_MC", mv::mav_vtol_state::kMc},
      {"MAV_VTOL_STATE_FW", mv::mav_vtol_state::kFw},
      {"MAV_SEVERITY_EMERGENCY", mv::mav_severity::kEmergency},
      {"MAV_SEVERITY_ALERT", mv::mav_severity::kAlert},
      {"MAV_SEVERITY_CRITICAL", mv::mav_severity::kCritical},
      {"MAV_SEVERITY_ERROR", mv::mav_severity::kError},
      {"MAV_SEVERITY_WARNING", mv::mav_severity::kWarning},
      {"MAV_SEVERITY_NOTICE", mv::mav_severity::kNotice},
      {"MAV_SEVERITY_INFO", mv::mav_severity::kInfo},
      {"MAV_SEVERITY_DEBUG", mv::mav_severity::kDebug},
      {"MAV_COMP_ID_ALL", mv::mav_component::kAll},
      {"MAV_COMP_ID_AUTOPILOT1", mv::mav_component::kAutopilot1},
      {"MAV_COMP_ID_CAMERA", mv::mav_component::kCamera},
      {"MAV_COMP_ID_MISSIONPLANNER", mv::mav_component::kMissionPlanner},
      {"MAV_COMP_ID_ONBOARD_COMPUTER", mv::mav_component::kOnboardComputer},
      {"POSITION_TARGET_TYPEMASK_X_IGNORE", mv::position_target_typemask::kXIgnore},
      {"POSITION_TARGET_TYPEMASK_Y_IGNORE", mv::position_target_typemask::kYIgnore},
      {"POSITION_TARGET_TYPEMASK_Z_IGNORE", mv::position_target_typemask::kZIgnore},
      {"POSITION_TARGET_TYPEMASK_VX_IGNORE", mv::position_target_typemask::kVxIgnore},
      {"POSITION_TARGET_TYPEMASK_VY_IGNORE", mv::position_target_typemask::kVyIgnore},
      {"POSITION_TARGET_TYPEMASK_VZ_IGNORE", mv::position_target_typemask::kVzIgnore},
      {"POSITION_TARGET_TYPEMASK_AX_IGNORE", mv::position_target_typemask::kAxIgnore},
      {"POSITION_TARGET_TYPEMASK_AY_IGNORE", mv::position_target_typemask::kAyIgnore},
      {"POSITION_TARGET_TYPEMASK_AZ_IGNORE", mv::position_target_typemask::kAzIgnore},
      {"POSITION_TARGET_TYPEMASK_FORCE_SET", mv::position_target_typemask::kForceSet},
      {"POSITION_TARGET_TYPEMASK_YAW_IGNORE", mv::position_target_typemask::kYawIgnore},
      {"POSITION_TARGET_TYPEMASK_YAW_RATE_IGNORE", mv::position_target_typemask::kYawRateIgnore},
  };
  std::ofstream out(file);
  for (const auto& [name, value] : table) out << name << ' ' << value << '\n';
  std::cout << "mavlink_peer: " << table.size() << " constants written\n";
  return out ? 0 : 1;
}

}  // namespace

int main(int argc, char** argv) {
  const std::vector<std::string> args(argv + 1, argv + argc);
  try {
    if (args.size() >= 2 && args[0] == "write") return write(args[1], args.size() > 2 ? std::stoi(args[2]) : 40);
    if (args.size() == 2 && args[0] == "check") return check(args[1]);
    if (args.size() == 2 && args[0] == "constants") return constants(args[1]);
  } catch (const std::exception& e) {
    std::cerr << "mavlink_peer: " << e.what() << '\n';
    return 1;
  }
  std::cerr << "usage: adaptseg_mavlink_peer write FILE [N] | check FILE | constants FILE\n";
  return 2;
}
