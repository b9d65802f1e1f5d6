#pragma once
/// @file
/// COMMAND_INT (#75, common.xml): a command with a position in integers. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// COMMAND_INT (#75): a MAV_CMD whose parameters 5 and 6 are a latitude and longitude
/// [degE7] in `frame` (a float of COMMAND_LONG holds degrees only to 0.4 to 1.7 m); the form of
/// positional commands such as mav_cmd::kDoReposition. Answered by COMMAND_ACK. Members in the
/// order of the definition; fields() gives the wire order.
struct CommandInt {
  static constexpr std::uint32_t kId = 75;                  ///< message id
  static constexpr std::string_view kName = "COMMAND_INT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 158;            ///< published CRC_EXTRA

  std::uint8_t target_system = 0;     ///< system id of the target
  std::uint8_t target_component = 0;  ///< component id of the target (mav_component::)
  std::uint8_t frame = 0;             ///< MAV_FRAME of x, y, z (mav_frame::)
  std::uint16_t command = 0;          ///< MAV_CMD (mav_cmd::)
  std::uint8_t current = 0;           ///< unused (0)
  std::uint8_t autocontinue = 0;      ///< unused (0)
  float param1 = 0.0F;                ///< parameter 1 (command specific; NaN: unchanged where allowed)
  float param2 = 0.0F;                ///< parameter 2
  float param3 = 0.0F;                ///< parameter 3
  float param4 = 0.0F;                ///< parameter 4
  std::int32_t x = 0;                 ///< parameter 5: latitude [degE7] (or local x [m * 1e4])
  std::int32_t y = 0;                 ///< parameter 6: longitude [degE7] (or local y [m * 1e4])
  float z = 0.0F;                     ///< parameter 7: altitude [m] in `frame`

  friend bool operator==(const CommandInt&, const CommandInt&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("param1", &CommandInt::param1);
    v.field("param2", &CommandInt::param2);
    v.field("param3", &CommandInt::param3);
    v.field("param4", &CommandInt::param4);
    v.field("x", &CommandInt::x);
    v.field("y", &CommandInt::y);
    v.field("z", &CommandInt::z);
    v.field("command", &CommandInt::command);
    v.field("target_system", &CommandInt::target_system);
    v.field("target_component", &CommandInt::target_component);
    v.field("frame", &CommandInt::frame);
    v.field("current", &CommandInt::current);
    v.field("autocontinue", &CommandInt::autocontinue);
  }
};
static_assert(MessageType<CommandInt>);
static_assert(kBaseLength<CommandInt> == 35 && kFullLength<CommandInt> == 35);

}  // namespace adaptseg::mavlink
