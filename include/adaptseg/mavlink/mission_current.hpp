#pragma once
/// @file
/// MISSION_CURRENT (#42, common.xml): the mission item the vehicle flies to. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// MISSION_CURRENT (#42): the current item's sequence number, and (extensions) the mission's
/// size, state and the ids of the plans on board. Members in the order of the definition (=
/// wire order).
struct MissionCurrent {
  static constexpr std::uint32_t kId = 42;                      ///< message id
  static constexpr std::string_view kName = "MISSION_CURRENT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 28;                 ///< published CRC_EXTRA

  std::uint16_t seq = 0;              ///< sequence number of the current item
  std::uint16_t total = 0;            ///< extension: items in the mission (UINT16_MAX: unknown)
  std::uint8_t mission_state = 0;     ///< extension: MISSION_STATE (0: unknown)
  std::uint8_t mission_mode = 0;      ///< extension: 1 in a mission mode, 2 not, 0 unknown
  std::uint32_t mission_id = 0;       ///< extension: id of the mission plan on board (0: unknown)
  std::uint32_t fence_id = 0;         ///< extension: id of the fence plan on board
  std::uint32_t rally_points_id = 0;  ///< extension: id of the rally point plan on board

  friend bool operator==(const MissionCurrent&, const MissionCurrent&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("seq", &MissionCurrent::seq);
    v.extensions();
    v.field("total", &MissionCurrent::total);
    v.field("mission_state", &MissionCurrent::mission_state);
    v.field("mission_mode", &MissionCurrent::mission_mode);
    v.field("mission_id", &MissionCurrent::mission_id);
    v.field("fence_id", &MissionCurrent::fence_id);
    v.field("rally_points_id", &MissionCurrent::rally_points_id);
  }
};
static_assert(MessageType<MissionCurrent>);
static_assert(kBaseLength<MissionCurrent> == 2 && kFullLength<MissionCurrent> == 18);

}  // namespace adaptseg::mavlink
