#pragma once
/// @file
/// STATUSTEXT (#253, common.xml): a text message for the operator. CMake target
/// adaptseg::mavlink.

#include <adaptseg/mavlink/message_type.hpp>

#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace adaptseg::mavlink {

/// STATUSTEXT (#253): a severity and up to 50 bytes of text (a longer text goes in chunks of
/// the same `id`, `chunk_seq` 0, 1, ...; this struct is one chunk). Members in the order of
/// the definition (= wire order).
///
/// encode() throws std::invalid_argument naming `STATUSTEXT.text` for a text over 50 bytes or
/// with a NUL byte; decoding ends the text at its first NUL (a 50-byte text has none).
struct StatusText {
  static constexpr std::uint32_t kId = 253;                ///< message id
  static constexpr std::string_view kName = "STATUSTEXT";  ///< name in the definitions
  static constexpr std::uint8_t kCrcExtra = 83;            ///< published CRC_EXTRA
  static constexpr std::size_t kTextLength = 50;           ///< bytes of `text` on the wire

  std::uint8_t severity = 0;   ///< MAV_SEVERITY (mav_severity::)
  std::string text;            ///< at most kTextLength bytes, no NUL (usually ASCII)
  std::uint16_t id = 0;        ///< extension: id of a text in chunks (0: a single chunk)
  std::uint8_t chunk_seq = 0;  ///< extension: this chunk's index in the text

  friend bool operator==(const StatusText&, const StatusText&) = default;

  /// The fields in wire order (message_type.hpp).
  template <typename V>
  static constexpr void fields(V& v) {
    v.field("severity", &StatusText::severity);
    v.text("text", &StatusText::text, kTextLength);
    v.extensions();
    v.field("id", &StatusText::id);
    v.field("chunk_seq", &StatusText::chunk_seq);
  }
};
static_assert(MessageType<StatusText>);
static_assert(kBaseLength<StatusText> == 51 && kFullLength<StatusText> == 54);

}  // namespace adaptseg::mavlink
