#pragma once
/// @file
/// Little-endian encoding of MAVLink's field types, whatever the host's byte order, and each
/// type's name and size as the MAVLink definitions spell them (the CRC_EXTRA is computed from
/// the names). Leaf internals of adaptseg::mavlink (CMake target adaptseg::mavlink).

#include <array>
#include <bit>
#include <cstddef>
#include <cstdint>
#include <string_view>
#include <type_traits>

namespace adaptseg::detail {

/// A MAVLink scalar type: its name in the XML definitions (`uint8_t`, `float`, ...) and size [bytes].
template <typename T>
struct WireScalar;

template <>
struct WireScalar<std::uint8_t> {
  static constexpr std::string_view name = "uint8_t";
};
template <>
struct WireScalar<std::int8_t> {
  static constexpr std::string_view name = "int8_t";
};
template <>
struct WireScalar<std::uint16_t> {
  static constexpr std::string_view name = "uint16_t";
};
template <>
struct WireScalar<std::int16_t> {
  static constexpr std::string_view name = "int16_t";
};
template <>
struct WireScalar<std::uint32_t> {
  static constexpr std::string_view name = "uint32_t";
};
template <>
struct WireScalar<std::int32_t> {
  static constexpr std::string_view name = "int32_t";
};
template <>
struct WireScalar<std::uint64_t> {
  static constexpr std::string_view name = "uint64_t";
};
template <>
struct WireScalar<std::int64_t> {
  static constexpr std::string_view name = "int64_t";
};
template <>
struct WireScalar<float> {
  static constexpr std::string_view name = "float";
};
template <>
struct WireScalar<double> {
  static constexpr std::string_view name = "double";
};

/// A field's C++ type as MAVLink sees it: a scalar, or an array of `count` scalars.
template <typename T>
struct WireField {
  using Element = T;
  static constexpr std::size_t count = 0;  // 0: not an array (the CRC_EXTRA adds no length byte)
};
template <typename T, std::size_t N>
struct WireField<std::array<T, N>> {
  using Element = T;
  static constexpr std::size_t count = N;
};

/// True for the types a message field may have: the scalars above and std::array of them.
template <typename T>
concept WireFieldType = requires {
  WireScalar<typename WireField<T>::Element>::name;
};

/// Unsigned integer of the same size as T (float -> uint32_t, int16_t -> uint16_t, ...).
template <typename T>
using WireBits =
    std::conditional_t<sizeof(T) == 1, std::uint8_t,
                       std::conditional_t<sizeof(T) == 2, std::uint16_t,
                                          std::conditional_t<sizeof(T) == 4, std::uint32_t, std::uint64_t>>>;

/// Writes `value` little-endian at `out` (sizeof(T) bytes).
template <typename T>
constexpr void put_le(std::uint8_t* out, T value) {
  auto bits = std::bit_cast<WireBits<T>>(value);
  for (std::size_t i = 0; i < sizeof(T); ++i) {
    out[i] = static_cast<std::uint8_t>(bits & 0xFFu);
    bits = static_cast<WireBits<T>>(bits >> 8);  // the shift of a 1-byte type: int, narrowed back
  }
}

/// Reads a little-endian T at `in` (sizeof(T) bytes).
template <typename T>
constexpr T get_le(const std::uint8_t* in) {
  WireBits<T> bits = 0;
  for (std::size_t i = sizeof(T); i-- > 0;) {
    bits = static_cast<WireBits<T>>((static_cast<std::uint64_t>(bits) << 8) | in[i]);
  }
  return std::bit_cast<T>(bits);
}

}  // namespace adaptseg::detail
