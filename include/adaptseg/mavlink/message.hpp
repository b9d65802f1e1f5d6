#pragma once
/// @file
/// The messages this codec knows, as one variant, and decode(), which turns a frame into one.
/// CMake target adaptseg::mavlink.
///
/// @code
/// using namespace adaptseg::mavlink;
/// Parser parser;
/// parser.feed(bytes);                      // a UDP datagram, a serial read: any chunk
/// while (const std::optional<Frame> frame = parser.next()) {
///   const Message msg = decode(*frame);
///   if (const auto* hb = std::get_if<Heartbeat>(&msg)) {
///     const bool px4 = hb->autopilot == mav_autopilot::kPx4;
///   }
/// }
/// @endcode

#include <adaptseg/mavlink/camera_image_captured.hpp>
#include <adaptseg/mavlink/command_ack.hpp>
#include <adaptseg/mavlink/command_int.hpp>
#include <adaptseg/mavlink/command_long.hpp>
#include <adaptseg/mavlink/extended_sys_state.hpp>
#include <adaptseg/mavlink/frame.hpp>
#include <adaptseg/mavlink/global_position_int.hpp>
#include <adaptseg/mavlink/gps_raw_int.hpp>
#include <adaptseg/mavlink/heartbeat.hpp>
#include <adaptseg/mavlink/home_position.hpp>
#include <adaptseg/mavlink/message_type.hpp>
#include <adaptseg/mavlink/mission_current.hpp>
#include <adaptseg/mavlink/mission_item_reached.hpp>
#include <adaptseg/mavlink/position_target_global_int.hpp>
#include <adaptseg/mavlink/set_position_target_global_int.hpp>
#include <adaptseg/mavlink/status_text.hpp>
#include <adaptseg/mavlink/sys_status.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <variant>
#include <vector>

namespace adaptseg::mavlink {

/// Every message the codec encodes and decodes (docs/mavlink.md lists them); a frame of any
/// other id is skipped by the Parser and counted (ParseStats::unknown_ids).
using Message = std::variant<Heartbeat, SysStatus, GpsRawInt, GlobalPositionInt, MissionCurrent, MissionItemReached,
                             CommandInt, CommandLong, CommandAck, SetPositionTargetGlobalInt, PositionTargetGlobalInt,
                             HomePosition, ExtendedSysState, StatusText, CameraImageCaptured>;

/// What the Parser needs to know of a message id to check a frame.
struct MessageInfo {
  std::uint32_t id = 0;         ///< message id
  std::string_view name;        ///< name in the definitions
  std::uint8_t crc_extra = 0;   ///< CRC_EXTRA
  std::size_t base_length = 0;  ///< payload without extensions [bytes]
  std::size_t full_length = 0;  ///< payload with extensions: the longest accepted [bytes]
};

}  // namespace adaptseg::mavlink

namespace adaptseg::detail {

template <typename... Ms>
constexpr std::array<mavlink::MessageInfo, sizeof...(Ms)> mavlink_message_infos(const std::variant<Ms...>*) {
  return {
      mavlink::MessageInfo{Ms::kId, Ms::kName, Ms::kCrcExtra, mavlink::kBaseLength<Ms>, mavlink::kFullLength<Ms>}...};
}

inline constexpr auto kMavlinkMessageInfos = mavlink_message_infos(static_cast<const mavlink::Message*>(nullptr));

constexpr bool mavlink_ids_unique() {
  for (std::size_t i = 0; i < kMavlinkMessageInfos.size(); ++i) {
    for (std::size_t j = i + 1; j < kMavlinkMessageInfos.size(); ++j) {
      if (kMavlinkMessageInfos[i].id == kMavlinkMessageInfos[j].id) return false;
    }
  }
  return true;
}
static_assert(mavlink_ids_unique(), "two alternatives of mavlink::Message share a message id");

template <typename... Ms>
mavlink::Message mavlink_decode_known(std::uint32_t id, const mavlink::PayloadBuffer& payload,
                                      const std::variant<Ms...>*) {
  std::optional<mavlink::Message> out;
  (void)((id == Ms::kId ? (out.emplace(std::in_place_type<Ms>, mavlink::decode_payload<Ms>(payload)), true) : false) ||
         ...);
  return std::move(*out);  // the caller checked that the id is known
}

}  // namespace adaptseg::detail

namespace adaptseg::mavlink {

/// The MessageInfo of message id `id`, or nullptr if Message has no such message.
[[nodiscard]] constexpr const MessageInfo* find_message_info(std::uint32_t id) {
  for (const MessageInfo& info : detail::kMavlinkMessageInfos) {
    if (info.id == id) return &info;
  }
  return nullptr;
}

/// The message a frame carries, read from its zero-extended payload; bytes beyond the message's
/// full length (extension fields our definitions lack) are ignored. Never throws for a frame
/// the Parser yielded.
/// @throws std::invalid_argument for a frame built otherwise whose message id is not one of
///         Message's.
[[nodiscard]] inline Message decode(const Frame& frame) {
  const MessageInfo* info = find_message_info(frame.message_id);
  if (info == nullptr) {
    throw std::invalid_argument("decode: message id " + std::to_string(frame.message_id) +
                                " is not one adaptseg::mavlink knows");
  }
  PayloadBuffer payload{};  // zero-extended whatever the frame holds past its length
  const auto wire = frame.wire_payload();
  std::copy_n(wire.begin(), std::min(wire.size(), info->full_length), payload.begin());
  return detail::mavlink_decode_known(frame.message_id, payload, static_cast<const Message*>(nullptr));
}

/// The message held by `msg` as a MAVLink 2 frame (encode() of the alternative).
/// @throws std::invalid_argument as encode() does.
[[nodiscard]] inline std::vector<std::uint8_t> encode(const Message& msg, const FrameHeader& header) {
  return std::visit([&](const auto& m) { return encode(m, header); }, msg);
}

/// The name of the message `msg` holds (`"HEARTBEAT"`).
[[nodiscard]] inline std::string_view message_name(const Message& msg) {
  return std::visit([](const auto& m) { return std::decay_t<decltype(m)>::kName; }, msg);
}

}  // namespace adaptseg::mavlink
