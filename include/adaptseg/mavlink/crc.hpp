#pragma once
/// @file
/// The MAVLink checksum: CRC-16/MCRF4XX (the X.25 CRC as MAVLink computes it: polynomial
/// 0x1021 reflected, initial value 0xFFFF, no final XOR), from the mavlink.io serialization
/// page ("CRC", "CRC_EXTRA calculation"). CMake target adaptseg::mavlink.
///
/// A frame's checksum covers every byte after the start byte up to the end of the payload,
/// then the message's CRC_EXTRA byte (crc_extra_of()), so that two ends whose definitions of a
/// message differ reject each other's frames.
///
/// @code
/// const std::array<std::uint8_t, 9> digits{'1', '2', '3', '4', '5', '6', '7', '8', '9'};
/// const std::uint16_t crc = adaptseg::mavlink::crc_calculate(digits);  // 0x6F91
/// @endcode

#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace adaptseg::mavlink {

/// The checksum before the first byte.
inline constexpr std::uint16_t kCrcInit = 0xFFFF;

/// The checksum `crc` extended by one byte (MAVLink's `crc_accumulate`).
[[nodiscard]] constexpr std::uint16_t crc_accumulate(std::uint8_t byte, std::uint16_t crc) {
  std::uint8_t tmp = static_cast<std::uint8_t>(byte ^ static_cast<std::uint8_t>(crc & 0xFFu));
  tmp = static_cast<std::uint8_t>(tmp ^ static_cast<std::uint8_t>(tmp << 4));
  return static_cast<std::uint16_t>((crc >> 8) ^ (tmp << 8) ^ (tmp << 3) ^ (tmp >> 4));
}

/// The checksum `crc` extended by `bytes`.
[[nodiscard]] constexpr std::uint16_t crc_calculate(std::span<const std::uint8_t> bytes, std::uint16_t crc = kCrcInit) {
  for (const std::uint8_t b : bytes) crc = crc_accumulate(b, crc);
  return crc;
}

/// The checksum `crc` extended by the characters of `text` (how the CRC_EXTRA reads names).
[[nodiscard]] constexpr std::uint16_t crc_calculate(std::string_view text, std::uint16_t crc = kCrcInit) {
  for (const char c : text) crc = crc_accumulate(static_cast<std::uint8_t>(c), crc);
  return crc;
}

}  // namespace adaptseg::mavlink
