#pragma once
/// @file
/// COMMAND_LONG (#76, common.xml): a command with seven float parameters. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// COMMAND_LONG (#76): a MAV_CMD and its seven parameters; answered by COMMAND_ACK. A sender
/// that gets no ACK sends it again with `confirmation` incremented. Members in the order of
/// the definition; fields() gives the wire order.
struct CommandLong {
  static constexpr std::uint32_t kId = 76;                   ///< message id
  static constexpr std::string_view kName = "COMMAND_LONG";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 152;             ///< published CRC_EXTRA

  std::uint8_t target_system = 0;     ///< system id of the target
  std::uint8_t target_component = 0;  ///< component id of the target (mav_component::)
  std::uint16_t command = 0;          ///< MAV_CMD (mav_cmd::)
  std::uint8_t confirmation = 0;      ///< 0 the first time, then +1 per retransmission
  float param1 = 0.0F;                ///< parameter 1 (command specific; NaN: unchanged where allowed)
  float param2 = 0.0F;                ///< parameter 2
  float param3 = 0.0F;                ///< parameter 3
  float param4 = 0.0F;                ///< parameter 4
  float param5 = 0.0F;                ///< parameter 5
  float param6 = 0.0F;                ///< parameter 6
  float param7 = 0.0F;                ///< parameter 7

  friend bool operator==(const CommandLong&, const CommandLong&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("param1", &CommandLong::param1);
    v.field("param2", &CommandLong::param2);
    v.field("param3", &CommandLong::param3);
    v.field("param4", &CommandLong::param4);
    v.field("param5", &CommandLong::param5);
    v.field("param6", &CommandLong::param6);
    v.field("param7", &CommandLong::param7);
    v.field("command", &CommandLong::command);
    v.field("target_system", &CommandLong::target_system);
    v.field("target_component", &CommandLong::target_component);
    v.field("confirmation", &CommandLong::confirmation);
  }
};
static_assert(MessageType<CommandLong>);
static_assert(kBaseLength<CommandLong> == 33 && kFullLength<CommandLong> == 33);

}  // namespace adaptseg::mavlink
