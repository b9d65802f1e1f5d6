#pragma once
/// @file
/// HOME_POSITION (#242, common.xml): where the vehicle returns to and lands. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <array>
#include <cstdint>
#include <string_view>

namespace adaptseg::mavlink {

/// HOME_POSITION (#242): the home position in WGS84 and in the local frame; sent on change
/// and when asked (mav_cmd::kRequestMessage). Members in the order of the definition (= wire
/// order).
struct HomePosition {
  static constexpr std::uint32_t kId = 242;                   ///< message id
  static constexpr std::string_view kName = "HOME_POSITION";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 104;              ///< published CRC_EXTRA

  std::int32_t latitude = 0;   ///< latitude, WGS84 [degE7]
  std::int32_t longitude = 0;  ///< longitude, WGS84 [degE7]
  std::int32_t altitude = 0;   ///< altitude above mean sea level [mm]
  float x = 0.0F;              ///< local x [m]
  float y = 0.0F;              ///< local y [m]
  float z = 0.0F;              ///< local z [m]
  /// Heading and slope of the ground at home, quaternion w, x, y, z (all NaN: unknown).
  std::array<float, 4> q{};
  float approach_x = 0.0F;      ///< local x of the end of the approach [m]
  float approach_y = 0.0F;      ///< local y of the end of the approach [m]
  float approach_z = 0.0F;      ///< local z of the end of the approach [m]
  std::uint64_t time_usec = 0;  ///< extension: timestamp [us] (since boot or UNIX epoch)

  friend bool operator==(const HomePosition&, const HomePosition&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("latitude", &HomePosition::latitude);
    v.field("longitude", &HomePosition::longitude);
    v.field("altitude", &HomePosition::altitude);
    v.field("x", &HomePosition::x);
    v.field("y", &HomePosition::y);
    v.field("z", &HomePosition::z);
    v.field("q", &HomePosition::q);
    v.field("approach_x", &HomePosition::approach_x);
    v.field("approach_y", &HomePosition::approach_y);
    v.field("approach_z", &HomePosition::approach_z);
    v.extensions();
    v.field("time_usec", &HomePosition::time_usec);
  }
};
static_assert(MessageType<HomePosition>);
static_assert(kBaseLength<HomePosition> == 52 && kFullLength<HomePosition> == 60);

}  // namespace adaptseg::mavlink
