#pragma once
/// @file
/// EXTENDED_SYS_STATE (#245, common.xml): landed state and VTOL state. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// EXTENDED_SYS_STATE (#245): whether the vehicle is on the ground, taking off, in the air or
/// landing (mav_landed_state::), and a VTOL's configuration (mav_vtol_state::).
struct ExtendedSysState {
  static constexpr std::uint32_t kId = 245;                        ///< message id
  static constexpr std::string_view kName = "EXTENDED_SYS_STATE";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 130;                   ///< published CRC_EXTRA

  std::uint8_t vtol_state = 0;    ///< MAV_VTOL_STATE (mav_vtol_state::)
  std::uint8_t landed_state = 0;  ///< MAV_LANDED_STATE (mav_landed_state::)

  friend bool operator==(const ExtendedSysState&, const ExtendedSysState&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("vtol_state", &ExtendedSysState::vtol_state);
    v.field("landed_state", &ExtendedSysState::landed_state);
  }
};
static_assert(MessageType<ExtendedSysState>);
static_assert(kBaseLength<ExtendedSysState> == 2 && kFullLength<ExtendedSysState> == 2);

}  // namespace adaptseg::mavlink
