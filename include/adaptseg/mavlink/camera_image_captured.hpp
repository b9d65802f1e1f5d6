#pragma once
/// @file
/// CAMERA_IMAGE_CAPTURED (#263, common.xml): a camera took an image. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace adaptseg::mavlink {

/// CAMERA_IMAGE_CAPTURED (#263): where and when an image was taken, its index and file
/// (MAVLink 2 only: its id does not fit MAVLink 1). Members in the order of the definition;
/// fields() gives the wire order.
///
/// encode() throws std::invalid_argument naming `CAMERA_IMAGE_CAPTURED.file_url` for a URL
/// over 205 bytes or with a NUL byte.
struct CameraImageCaptured {
  static constexpr std::uint32_t kId = 263;                           ///< message id
  static constexpr std::string_view kName = "CAMERA_IMAGE_CAPTURED";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 133;                      ///< published CRC_EXTRA
  static constexpr std::size_t kFileUrlLength = 205;                  ///< bytes of `file_url` on the wire

  std::uint32_t time_boot_ms = 0;  ///< time since boot [ms]
  std::uint64_t time_utc = 0;      ///< UTC time of capture [us since UNIX epoch] (0: unknown)
  std::uint8_t camera_id = 0;      ///< deprecated (0); the sender's component id names the camera
  std::int32_t lat = 0;            ///< latitude where the image was taken, WGS84 [degE7]
  std::int32_t lon = 0;            ///< longitude [degE7]
  std::int32_t alt = 0;            ///< altitude above mean sea level [mm]
  std::int32_t relative_alt = 0;   ///< altitude above ground [mm]
  std::array<float, 4> q{};        ///< camera orientation quaternion w, x, y, z (1, 0, 0, 0: no rotation)
  std::int32_t image_index = 0;    ///< zero-based index of this image
  std::int8_t capture_result = 0;  ///< 1 captured, 0 failed
  std::string file_url;            ///< URL of the image file (at most kFileUrlLength bytes, no NUL)

  friend bool operator==(const CameraImageCaptured&, const CameraImageCaptured&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("time_utc", &CameraImageCaptured::time_utc);
    v.field("time_boot_ms", &CameraImageCaptured::time_boot_ms);
    v.field("lat", &CameraImageCaptured::lat);
    v.field("lon", &CameraImageCaptured::lon);
    v.field("alt", &CameraImageCaptured::alt);
    v.field("relative_alt", &CameraImageCaptured::relative_alt);
    v.field("q", &CameraImageCaptured::q);
    v.field("image_index", &CameraImageCaptured::image_index);
    v.field("camera_id", &CameraImageCaptured::camera_id);
    v.field("capture_result", &CameraImageCaptured::capture_result);
    v.text("file_url", &CameraImageCaptured::file_url, kFileUrlLength);
  }
};
static_assert(MessageType<CameraImageCaptured>);
static_assert(kBaseLength<CameraImageCaptured> == 255 && kFullLength<CameraImageCaptured> == 255);

}  // namespace adaptseg::mavlink
