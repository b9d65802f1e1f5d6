#pragma once
/// @file
/// MAVLink framing (mavlink.io, "Packet serialization"): the frame a Parser yields, and
/// encode(), which writes a message into a MAVLink 2 frame. CMake target adaptseg::mavlink.
///
/// A MAVLink 2 frame is: 0xFD, payload length, incompat flags, compat flags, sequence, system
/// id, component id, message id (3 bytes, little-endian), the payload with its trailing zero
/// bytes removed (but never its first byte), and the checksum (crc.hpp) of everything after
/// the start byte followed by the message's CRC_EXTRA; with the incompat flag 0x01 a 13-byte
/// signature follows. A MAVLink 1 frame is: 0xFE, payload length, sequence, system id,
/// component id, message id (1 byte), the payload, the checksum.
///
/// @code
/// using namespace adaptseg::mavlink;
/// CommandLong arm{.target_system = 1, .target_component = mav_component::kAutopilot1,
///                 .command = mav_cmd::kComponentArmDisarm, .param1 = 1.0F};
/// const std::vector<std::uint8_t> bytes = encode(arm, {.sequence = 7, .system_id = 1,
///                                                       .component_id = mav_component::kOnboardComputer});
/// @endcode

#include <adaptseg/mavlink/crc.hpp>
#include <adaptseg/mavlink/detail/wire.hpp>
#include <adaptseg/mavlink/enums.hpp>
#include <adaptseg/mavlink/message_type.hpp>

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace adaptseg::mavlink {

inline constexpr std::uint8_t kStartV2 = 0xFD;             ///< start byte of a MAVLink 2 frame
inline constexpr std::uint8_t kStartV1 = 0xFE;             ///< start byte of a MAVLink 1 frame
inline constexpr std::size_t kHeaderLengthV2 = 10;         ///< start byte to message id, MAVLink 2 [bytes]
inline constexpr std::size_t kHeaderLengthV1 = 6;          ///< start byte to message id, MAVLink 1 [bytes]
inline constexpr std::size_t kChecksumLength = 2;          ///< [bytes]
inline constexpr std::size_t kSignatureLength = 13;        ///< link id, 6-byte timestamp, 6-byte signature [bytes]
inline constexpr std::uint8_t kIncompatFlagSigned = 0x01;  ///< MAVLINK_IFLAG_SIGNED: a signature follows
/// The longest frame: a signed MAVLink 2 frame with a 255-byte payload [bytes].
inline constexpr std::size_t kMaxFrameLength = kHeaderLengthV2 + kMaxPayloadLength + kChecksumLength + kSignatureLength;

/// MAVLink protocol version of a frame.
enum class ProtocolVersion : std::uint8_t {
  v1 = 1,  ///< start byte 0xFE, 8-bit message ids, no truncation, no extensions
  v2 = 2,  ///< start byte 0xFD
};

/// What the sender of a frame chooses: its sequence number and its address.
struct FrameHeader {
  std::uint8_t sequence = 0;   ///< per-sender counter, +1 per frame, wraps at 255
  std::uint8_t system_id = 1;  ///< the sender's system (a companion shares its autopilot's, usually 1)
  std::uint8_t component_id = mav_component::kOnboardComputer;  ///< the sender's component
  friend bool operator==(const FrameHeader&, const FrameHeader&) = default;
};

/// The signature of a signed MAVLink 2 frame, as received; the codec does not verify it.
struct FrameSignature {
  std::uint8_t link_id = 0;                 ///< the sender's link
  std::uint64_t timestamp = 0;              ///< [10 us since 2015-01-01 00:00 UTC], 48 bits
  std::array<std::uint8_t, 6> signature{};  ///< first 6 bytes of SHA-256(key, frame, link id, timestamp)
  friend bool operator==(const FrameSignature&, const FrameSignature&) = default;
};

/// One frame the Parser accepted: a known message id, checksum verified (its payload may be
/// longer than our message's: decode() ignores the rest). The payload is zero-extended: bytes past `payload_length` are
/// zero, so a truncated MAVLink 2 payload (or a MAVLink 1 one, without extensions) reads as the full message with
/// zeros. decode() (message.hpp) turns it into a Message.
struct Frame {
  ProtocolVersion version = ProtocolVersion::v2;  ///< MAVLink 1 or 2
  std::uint8_t incompat_flags = 0;                ///< MAVLink 2 incompat flags (0, or kIncompatFlagSigned)
  std::uint8_t compat_flags = 0;                  ///< MAVLink 2 compat flags (ignored)
  std::uint8_t sequence = 0;                      ///< the sender's sequence number
  std::uint8_t system_id = 0;                     ///< the sender's system id
  std::uint8_t component_id = 0;                  ///< the sender's component id
  std::uint32_t message_id = 0;                   ///< message id (24 bits)
  std::uint8_t payload_length = 0;                ///< payload bytes on the wire [bytes]
  PayloadBuffer payload{};                        ///< the payload, zero after `payload_length`
  std::uint16_t checksum = 0;                     ///< the frame's checksum (verified)
  std::optional<FrameSignature> signature;        ///< present if the frame was signed (not verified)

  /// The payload bytes as received (`payload_length` of them).
  [[nodiscard]] std::span<const std::uint8_t> wire_payload() const { return {payload.data(), payload_length}; }
  /// Sequence number and sender: what encode() needs to write the frame's message again.
  [[nodiscard]] FrameHeader header() const { return {sequence, system_id, component_id}; }
  friend bool operator==(const Frame&, const Frame&) = default;
};

/// Length of `payload` once MAVLink 2 truncation removed its trailing zero bytes: the first
/// byte stays, so an all-zero payload keeps 1 byte (mavlink.io, "Payload truncation").
[[nodiscard]] inline std::size_t truncated_length(std::span<const std::uint8_t> payload) {
  std::size_t n = payload.size();
  while (n > 1 && payload[n - 1] == 0) --n;
  return n;
}

/// `msg` as an unsigned MAVLink 2 frame from `header`, its payload truncated.
/// @throws std::invalid_argument naming the field (`STATUSTEXT.text`) if a text field is
///         longer than its `char[N]` or contains a NUL byte.
template <MessageType M>
[[nodiscard]] std::vector<std::uint8_t> encode(const M& msg, const FrameHeader& header) {
  const PayloadBuffer payload = encode_payload(msg);
  const std::size_t length = truncated_length(std::span<const std::uint8_t>(payload.data(), kFullLength<M>));
  std::vector<std::uint8_t> out(kHeaderLengthV2 + length + kChecksumLength);
  out[0] = kStartV2;
  out[1] = static_cast<std::uint8_t>(length);
  out[2] = 0;  // incompat flags: unsigned
  out[3] = 0;  // compat flags
  out[4] = header.sequence;
  out[5] = header.system_id;
  out[6] = header.component_id;
  out[7] = static_cast<std::uint8_t>(M::kId & 0xFFu);
  out[8] = static_cast<std::uint8_t>((M::kId >> 8) & 0xFFu);
  out[9] = static_cast<std::uint8_t>((M::kId >> 16) & 0xFFu);
  std::copy_n(payload.begin(), length, out.begin() + static_cast<std::ptrdiff_t>(kHeaderLengthV2));
  std::uint16_t crc = crc_calculate(std::span<const std::uint8_t>(out.data() + 1, kHeaderLengthV2 - 1 + length));
  crc = crc_accumulate(M::kCrcExtra, crc);
  detail::put_le(out.data() + kHeaderLengthV2 + length, crc);
  return out;
}

}  // namespace adaptseg::mavlink
