#pragma once
/// @file
/// The streaming MAVLink parser: bytes in, in whatever chunks they arrive (UDP datagrams,
/// serial reads), checked frames out. CMake target adaptseg::mavlink.
///
/// Bad input is counted in ParseStats, never thrown, and never stops the stream: the parser
/// looks for the next start byte after garbage, a corrupted frame, a cut one or one it cannot
/// check, and holds at most one frame's bytes while it waits for the rest.

#include <adaptseg/mavlink/crc.hpp>
#include <adaptseg/mavlink/detail/wire.hpp>
#include <adaptseg/mavlink/frame.hpp>
#include <adaptseg/mavlink/message.hpp>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <vector>

namespace adaptseg::mavlink {

/// What a Parser saw. Every byte fed is in exactly one of: an accepted frame, a skipped
/// frame (`skipped_bytes`), `dropped_bytes`, or Parser::pending().
struct ParseStats {
  std::uint64_t bytes_fed = 0;        ///< bytes given to Parser::feed()
  std::uint64_t frames_ok = 0;        ///< frames accepted (known id, checksum verified)
  std::uint64_t signed_frames = 0;    ///< of frames_ok, frames that carried a signature (not verified)
  std::uint64_t mavlink1_frames = 0;  ///< of frames_ok, MAVLink 1 frames
  /// Frames of a known id whose checksum failed (corrupted, cut short by the next frame, or a
  /// start byte inside other data): their start byte is dropped, the rest read again.
  std::uint64_t crc_errors = 0;
  /// Of frames_ok, frames of a payload longer than our definition of the message (a sender
  /// whose definitions have extension fields ours lack): accepted, the extra bytes ignored, as
  /// MAVLink 2 receivers must (the checksum's CRC_EXTRA covers the base fields only).
  std::uint64_t longer_payloads = 0;
  /// Frames of an id the codec does not know (their checksum cannot be checked without its
  /// CRC_EXTRA): skipped whole when the byte after them is a start byte.
  std::uint64_t unknown_ids = 0;
  /// MAVLink 2 frames with an incompat flag other than signing (which a receiver must not
  /// handle): their start byte is dropped.
  std::uint64_t incompatible_flags = 0;
  std::uint64_t skipped_bytes = 0;  ///< bytes of the frames counted in unknown_ids
  std::uint64_t dropped_bytes = 0;  ///< bytes in no frame: garbage and the start bytes of rejected frames

  friend bool operator==(const ParseStats&, const ParseStats&) = default;
};

/// Splits a byte stream into MAVLink frames and checks them.
///
/// Accepted: MAVLink 2 frames (truncated payloads zero-extended, payloads longer than the
/// message's with the extra bytes ignored; signed frames with their signature skipped,
/// unverified: a link that needs authenticity must check Frame::signature itself) and MAVLink
/// 1 frames, of the ids of Message, whose checksum (with the message's CRC_EXTRA) is right.
/// Everything else is counted in stats() and passed over (ParseStats says how).
///
/// A candidate frame is held until all its bytes have arrived (and, for an unknown id, one
/// more): after a cut frame the next good one comes out once the cut frame's declared length
/// has been received (at most kMaxFrameLength bytes). Not thread-safe; one parser per link.
///
/// @code
/// adaptseg::mavlink::Parser parser;
/// parser.feed(datagram);
/// while (const auto frame = parser.next()) handle(adaptseg::mavlink::decode(*frame));
/// @endcode
class Parser {
 public:
  /// Appends received bytes (any chunking: a frame may span calls, a call may hold many frames).
  void feed(std::span<const std::uint8_t> bytes) {
    if (start_ > 0) {
      buffer_.erase(buffer_.begin(), buffer_.begin() + static_cast<std::ptrdiff_t>(start_));
      start_ = 0;
    }
    buffer_.insert(buffer_.end(), bytes.begin(), bytes.end());
    stats_.bytes_fed += bytes.size();
  }

  /// The next accepted frame of the bytes fed so far, or nullopt when they hold no complete
  /// one (feed more). Call until nullopt after each feed(); between feeds the parser holds at
  /// most kMaxFrameLength bytes.
  [[nodiscard]] std::optional<Frame> next() {
    while (start_ < buffer_.size()) {
      const std::uint8_t* p = buffer_.data() + start_;
      const std::size_t available = buffer_.size() - start_;
      if (p[0] != kStartV2 && p[0] != kStartV1) {
        const auto* stx = std::find_if(p, p + available, [](std::uint8_t b) { return b == kStartV2 || b == kStartV1; });
        drop(static_cast<std::size_t>(stx - p));
        continue;
      }
      const bool v2 = p[0] == kStartV2;
      const std::size_t header_length = v2 ? kHeaderLengthV2 : kHeaderLengthV1;
      if (available < header_length) return std::nullopt;
      const std::size_t payload_length = p[1];
      const std::uint8_t incompat = v2 ? p[2] : 0;
      if ((incompat & ~kIncompatFlagSigned) != 0) {
        ++stats_.incompatible_flags;
        drop(1);
        continue;
      }
      const std::uint32_t id = v2 ? static_cast<std::uint32_t>(p[7] | (p[8] << 8) | (p[9] << 16)) : p[5];
      const bool is_signed = (incompat & kIncompatFlagSigned) != 0;
      const std::size_t checked_length = header_length + payload_length;  // start byte to end of payload
      const std::size_t frame_length = checked_length + kChecksumLength + (is_signed ? kSignatureLength : 0);
      const MessageInfo* info = find_message_info(id);
      if (info == nullptr) {
        // Without the CRC_EXTRA the checksum says nothing: a frame is believed when the next
        // byte starts another one, so that a start byte in garbage does not swallow good frames.
        if (available <= frame_length) return std::nullopt;
        if (p[frame_length] == kStartV2 || p[frame_length] == kStartV1) {
          ++stats_.unknown_ids;
          skip(frame_length);
        } else {
          drop(1);
        }
        continue;
      }
      if (available < frame_length) return std::nullopt;
      std::uint16_t crc = crc_calculate(std::span<const std::uint8_t>(p + 1, checked_length - 1));
      crc = crc_accumulate(info->crc_extra, crc);
      const auto received = detail::get_le<std::uint16_t>(p + checked_length);
      if (crc != received) {
        ++stats_.crc_errors;
        drop(1);
        continue;
      }
      if (payload_length > info->full_length) ++stats_.longer_payloads;
      Frame frame = decode(p, v2, header_length, payload_length, id, received);
      if (!v2) ++stats_.mavlink1_frames;
      ++stats_.frames_ok;
      start_ += frame_length;
      return frame;
    }
    return std::nullopt;
  }

  /// Counts of what the parser accepted and rejected since construction (or reset()).
  [[nodiscard]] const ParseStats& stats() const { return stats_; }

  /// Bytes held, waiting for the rest of a frame (or for next() to be called).
  [[nodiscard]] std::size_t pending() const { return buffer_.size() - start_; }

  /// Forgets the bytes held and the counts (a link reconnected).
  void reset() {
    buffer_.clear();
    start_ = 0;
    stats_ = {};
  }

 private:
  /// The frame at `p`, checked (version `v2`, its header and payload lengths, message `id`, the
  /// checksum `received`): its header fields, payload and signature.
  [[nodiscard]] Frame decode(const std::uint8_t* p, bool v2, std::size_t header_length, std::size_t payload_length,
                             std::uint32_t id, std::uint16_t received) {
    const std::uint8_t incompat = v2 ? p[2] : 0;
    Frame frame;
    frame.version = v2 ? ProtocolVersion::v2 : ProtocolVersion::v1;
    frame.incompat_flags = incompat;
    frame.compat_flags = v2 ? p[3] : 0;
    frame.sequence = v2 ? p[4] : p[2];
    frame.system_id = v2 ? p[5] : p[3];
    frame.component_id = v2 ? p[6] : p[4];
    frame.message_id = id;
    frame.payload_length = static_cast<std::uint8_t>(payload_length);
    std::copy_n(p + header_length, payload_length, frame.payload.begin());
    frame.checksum = received;
    if ((incompat & kIncompatFlagSigned) != 0) {
      const std::uint8_t* s = p + header_length + payload_length + kChecksumLength;
      FrameSignature sig;
      sig.link_id = s[0];
      for (std::size_t i = 6; i-- > 0;) sig.timestamp = (sig.timestamp << 8) | s[1 + i];
      std::copy_n(s + 7, sig.signature.size(), sig.signature.begin());
      frame.signature = sig;
      ++stats_.signed_frames;
    }
    return frame;
  }

  void drop(std::size_t n) {
    start_ += n;
    stats_.dropped_bytes += n;
  }
  void skip(std::size_t n) {
    start_ += n;
    stats_.skipped_bytes += n;
  }

  std::vector<std::uint8_t> buffer_;  // bytes fed, from start_ on not yet consumed
  std::size_t start_ = 0;
  ParseStats stats_;
};

}  // namespace adaptseg::mavlink
