#pragma once
/// @file
/// What a MAVLink message type is to this codec: its identity (id, name, CRC_EXTRA) and one
/// list of its fields in wire order, from which its payload lengths, its CRC_EXTRA and its
/// encoding and decoding all follow. CMake target adaptseg::mavlink.
///
/// The field list (`M::fields(v)`, a static member template) calls, for each field in the
/// order of the wire (mavlink.io, "Serialization": the fields of the XML definition sorted by
/// the size of their type, largest first, stable; then the extension fields in the order of
/// the definition):
///
///   - `v.field("name", &M::member)` for a number (`std::uint8_t` ... `std::int64_t`, `float`,
///     `double`) or a `std::array` of numbers;
///   - `v.text("name", &M::member, N)` for a `char[N]` field held as a `std::string` of at most
///     N bytes (N bytes on the wire: the text, then zeros; no terminator when it fills them);
///   - `v.extensions()` once, before the first extension field (MAVLink 2 only fields: a
///     MAVLink 1 sender leaves them out, a MAVLink 2 receiver reads zeros for what is missing).
///
/// The names are those of the XML definition: the CRC_EXTRA is computed from them
/// (crc_extra_of()), and MessageType requires it to equal the published `M::kCrcExtra`, so
/// a field missing, misspelt, of another type or out of order does not compile.

#include <adaptseg/mavlink/crc.hpp>
#include <adaptseg/mavlink/detail/wire.hpp>

#include <algorithm>
#include <array>
#include <concepts>
#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace adaptseg::mavlink {

/// The largest payload of a MAVLink frame [bytes].
inline constexpr std::size_t kMaxPayloadLength = 255;

/// A payload: the bytes on the wire, zero-extended to the largest payload.
using PayloadBuffer = std::array<std::uint8_t, kMaxPayloadLength>;

}  // namespace adaptseg::mavlink

namespace adaptseg::detail {

/// Field-list visitor: the CRC_EXTRA (mavlink.io, "CRC_EXTRA calculation": the message name
/// and a space, then for each field before the extensions its type, a space, its name, a
/// space and, for an array, its length as one byte; the two bytes of the CRC XORed).
struct CrcExtraVisitor {
  std::uint16_t crc = mavlink::kCrcInit;
  bool in_extensions = false;

  constexpr void add(std::string_view type, std::string_view name, std::size_t count) {
    if (in_extensions) return;
    crc = mavlink::crc_calculate(type, crc);
    crc = mavlink::crc_calculate(" ", crc);
    crc = mavlink::crc_calculate(name, crc);
    crc = mavlink::crc_calculate(" ", crc);
    if (count > 0) crc = mavlink::crc_accumulate(static_cast<std::uint8_t>(count), crc);
  }
  template <typename M, WireFieldType T>
  constexpr void field(std::string_view name, T M::*) {
    add(WireScalar<typename WireField<T>::Element>::name, name, WireField<T>::count);
  }
  template <typename M>
  constexpr void text(std::string_view name, std::string M::*, std::size_t length) {
    add("char", name, length);
  }
  constexpr void extensions() { in_extensions = true; }
};

/// Field-list visitor: payload lengths [bytes] and whether the base fields are in wire order.
struct LayoutVisitor {
  std::size_t base_length = 0;   ///< bytes of the fields before the extensions
  std::size_t total_length = 0;  ///< bytes of all fields
  std::size_t last_size = 8;     ///< element size of the previous base field
  bool in_wire_order = true;
  bool in_extensions = false;
  int extension_marks = 0;

  constexpr void add(std::size_t element_size, std::size_t count) {
    const std::size_t bytes = element_size * (count == 0 ? 1 : count);
    total_length += bytes;
    if (in_extensions) return;
    base_length += bytes;
    if (element_size > last_size) in_wire_order = false;
    last_size = element_size;
  }
  template <typename M, WireFieldType T>
  constexpr void field(std::string_view, T M::*) {
    add(sizeof(typename WireField<T>::Element), WireField<T>::count);
  }
  template <typename M>
  constexpr void text(std::string_view, std::string M::*, std::size_t length) {
    add(1, length);
  }
  constexpr void extensions() {
    in_extensions = true;
    ++extension_marks;
  }
};

template <typename M>
constexpr LayoutVisitor layout_of() {
  LayoutVisitor v;
  M::fields(v);
  return v;
}

}  // namespace adaptseg::detail

namespace adaptseg::mavlink {

/// Has a MAVLink identity: `kId` (the message id, 24 bits), `kName` (its name in the
/// definitions, `"HEARTBEAT"`), `kCrcExtra` (its published CRC_EXTRA).
template <typename M>
concept HasMessageIdentity = requires {
  { M::kId } -> std::convertible_to<std::uint32_t>;
  { M::kName } -> std::convertible_to<std::string_view>;
  { M::kCrcExtra } -> std::convertible_to<std::uint8_t>;
};

/// Has a field list (this file's header says what it calls).
template <typename M>
concept HasFieldList = requires(detail::LayoutVisitor& layout, detail::CrcExtraVisitor& crc) {
  M::fields(layout);
  M::fields(crc);
};

/// The CRC_EXTRA of M computed from its name and field list.
template <HasFieldList M>
requires HasMessageIdentity<M>
[[nodiscard]] constexpr std::uint8_t crc_extra_of() {
  detail::CrcExtraVisitor v;
  v.crc = crc_calculate(std::string_view(M::kName));
  v.crc = crc_calculate(" ", v.crc);
  M::fields(v);
  return static_cast<std::uint8_t>((v.crc & 0xFFu) ^ (v.crc >> 8));
}

/// A MAVLink message this codec encodes and decodes: an identity and a field list that agree
/// with the published definition (its computed CRC_EXTRA is the published one, its base fields
/// are in wire order, at most one extension mark, a payload of 1 to 255 bytes), a value type
/// with `==`. Each message's header checks `static_assert(MessageType<...>)`.
template <typename M>
concept MessageType = HasMessageIdentity<M> && HasFieldList<M> && std::regular<M> &&
                      (M::kId < (1u << 24)) &&                // 24-bit id
                      (crc_extra_of<M>() == M::kCrcExtra) &&  // the published field list
                      detail::layout_of<M>().in_wire_order
                      &&  // sorted by type size
                      (detail::layout_of<M>().extension_marks <= 1) && (detail::layout_of<M>().base_length >= 1) &&
                      (detail::layout_of<M>().total_length <= kMaxPayloadLength);

/// Payload length of M without its extension fields [bytes] (a MAVLink 1 payload).
template <MessageType M>
inline constexpr std::size_t kBaseLength = detail::layout_of<M>().base_length;

/// Payload length of M with its extension fields [bytes] (an untruncated MAVLink 2 payload).
template <MessageType M>
inline constexpr std::size_t kFullLength = detail::layout_of<M>().total_length;

}  // namespace adaptseg::mavlink

namespace adaptseg::detail {

/// Field-list visitor: writes a message's fields into a zeroed payload buffer.
template <typename Msg>
struct EncodeVisitor {
  const Msg& msg;
  mavlink::PayloadBuffer& out;
  std::size_t offset = 0;

  template <WireFieldType T>
  void field(std::string_view, T Msg::*member) {
    const T& value = msg.*member;
    if constexpr (WireField<T>::count == 0) {
      put_le(out.data() + offset, value);
      offset += sizeof(T);
    } else {
      for (const auto& element : value) {
        put_le(out.data() + offset, element);
        offset += sizeof(element);
      }
    }
  }
  void text(std::string_view name, std::string Msg::*member, std::size_t length) {
    const std::string& value = msg.*member;
    if (value.size() > length) {
      throw std::invalid_argument(std::string(Msg::kName) + "." + std::string(name) + " must be at most " +
                                  std::to_string(length) + " bytes (got " + std::to_string(value.size()) + ")");
    }
    if (value.find('\0') != std::string::npos) {
      throw std::invalid_argument(std::string(Msg::kName) + "." + std::string(name) +
                                  " must not contain a NUL byte (got one at byte " + std::to_string(value.find('\0')) +
                                  ")");
    }
    std::copy(value.begin(), value.end(), out.begin() + static_cast<std::ptrdiff_t>(offset));
    offset += length;
  }
  void extensions() {}
};

/// Field-list visitor: reads a message's fields from a zero-extended payload buffer.
template <typename Msg>
struct DecodeVisitor {
  Msg& msg;
  const mavlink::PayloadBuffer& in;
  std::size_t offset = 0;

  template <WireFieldType T>
  void field(std::string_view, T Msg::*member) {
    T& value = msg.*member;
    if constexpr (WireField<T>::count == 0) {
      value = get_le<T>(in.data() + offset);
      offset += sizeof(T);
    } else {
      for (auto& element : value) {
        element = get_le<std::remove_reference_t<decltype(element)>>(in.data() + offset);
        offset += sizeof(element);
      }
    }
  }
  void text(std::string_view, std::string Msg::*member, std::size_t length) {
    const auto* begin = in.data() + offset;
    const auto* end = std::find(begin, begin + length, std::uint8_t{0});
    (msg.*member).assign(begin, end);
    offset += length;
  }
  void extensions() {}
};

}  // namespace adaptseg::detail

namespace adaptseg::mavlink {

/// The payload of `msg`, untruncated (kFullLength<M> bytes, zeros after).
/// @throws std::invalid_argument naming the field if a text field is longer than its `char[N]`
///         or contains a NUL byte.
template <MessageType M>
[[nodiscard]] PayloadBuffer encode_payload(const M& msg) {
  PayloadBuffer out{};
  detail::EncodeVisitor<M> v{msg, out};
  M::fields(v);
  return out;
}

/// The message in `payload` (zero-extended: bytes a MAVLink 2 sender truncated read as zeros).
/// A text field ends at its first zero byte.
template <MessageType M>
[[nodiscard]] M decode_payload(const PayloadBuffer& payload) {
  M msg{};
  detail::DecodeVisitor<M> v{msg, payload};
  M::fields(v);
  return msg;
}

}  // namespace adaptseg::mavlink
