#pragma once
/// @file
/// COMMAND_ACK (#77, common.xml): the answer to a COMMAND_LONG or COMMAND_INT. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// COMMAND_ACK (#77): the command answered and its MAV_RESULT; a long-running command may
/// first answer mav_result::kInProgress with `progress`. Members in the order of the
/// definition (= wire order).
struct CommandAck {
  static constexpr std::uint32_t kId = 77;                  ///< message id
  static constexpr std::string_view kName = "COMMAND_ACK";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 143;            ///< published CRC_EXTRA

  std::uint16_t command = 0;          ///< MAV_CMD answered (mav_cmd::)
  std::uint8_t result = 0;            ///< MAV_RESULT (mav_result::)
  std::uint8_t progress = 0;          ///< extension: progress with kInProgress [%] (UINT8_MAX: unknown)
  std::int32_t result_param2 = 0;     ///< extension: command-specific detail of the result
  std::uint8_t target_system = 0;     ///< extension: system id of the command's sender
  std::uint8_t target_component = 0;  ///< extension: component id of the command's sender

  friend bool operator==(const CommandAck&, const CommandAck&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("command", &CommandAck::command);
    v.field("result", &CommandAck::result);
    v.extensions();
    v.field("progress", &CommandAck::progress);
    v.field("result_param2", &CommandAck::result_param2);
    v.field("target_system", &CommandAck::target_system);
    v.field("target_component", &CommandAck::target_component);
  }
};
static_assert(MessageType<CommandAck>);
static_assert(kBaseLength<CommandAck> == 3 && kFullLength<CommandAck> == 10);

}  // namespace adaptseg::mavlink
