#pragma once
/// @file
/// MISSION_ITEM_REACHED (#46, common.xml): the vehicle reached a mission item. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// MISSION_ITEM_REACHED (#46): sent once when the vehicle reaches a mission item.
struct MissionItemReached {
  static constexpr std::uint32_t kId = 46;                           ///< message id
  static constexpr std::string_view kName = "MISSION_ITEM_REACHED";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 11;                      ///< published CRC_EXTRA

  std::uint16_t seq = 0;  ///< sequence number of the item reached

  friend bool operator==(const MissionItemReached&, const MissionItemReached&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("seq", &MissionItemReached::seq);
  }
};
static_assert(MessageType<MissionItemReached>);
static_assert(kBaseLength<MissionItemReached> == 2 && kFullLength<MissionItemReached> == 2);

}  // namespace adaptseg::mavlink
