#pragma once
/// @file
/// The byte transport a VehicleLink talks through: the ByteTransport concept, and AnyTransport,
/// which holds any model of it (UdpTransport, SerialTransport, a test's fake), so that a program
/// chooses the transport at run time (open_transport()). CMake target adaptseg::mavlink.

#include <concepts>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <utility>

namespace adaptseg::mavlink {

/// Sends bytes as they are given: one call carries one whole MAVLink frame, and a datagram
/// transport sends it as one datagram.
template <typename T>
concept SendsBytes = requires(T& t, std::span<const std::uint8_t> bytes) {
  { t.send(bytes) } -> std::same_as<void>;
};

/// Receives what has arrived, waiting a bounded time: the link's only blocking call, so that
/// its clock, its heartbeats and its timeouts stay in its own hands.
template <typename T>
concept ReceivesBytes = requires(T& t, std::span<std::uint8_t> buffer, double timeout_s) {
  { t.receive(buffer, timeout_s) } -> std::same_as<std::size_t>;
};

/// A byte transport to an autopilot: the plug point of VehicleLink.
///
/// Required:
/// - `void send(std::span<const std::uint8_t> bytes)`: sends `bytes` (one whole frame) or
///   drops them as the medium may (UDP loses datagrams; a UDP listener that has heard no peer
///   yet has nowhere to send); never sends part of them on a datagram medium. Throws
///   std::system_error for a failure of the medium (a serial device unplugged).
/// - `std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s)`: copies bytes
///   that arrived into `buffer` and returns how many (at most `buffer.size()`; one datagram per
///   call on a datagram medium, any number of bytes on a stream); waits at most `timeout_s`
///   seconds (0: does not wait) for the first of them and returns 0 if none came. May return 0
///   early (a signal): the caller keeps its own clock. Throws std::system_error for a failure
///   of the medium.
///
/// Optional: `std::string description() const`, what error messages name it by
/// (`"udpin:0.0.0.0:14550"`).
///
/// Models are move-only resources owned by one link; not thread-safe.
template <typename T>
concept ByteTransport = SendsBytes<T> && ReceivesBytes<T> && std::movable<T>;

/// Any ByteTransport, chosen at run time: VehicleLink holds one. Move-only; owns its transport.
class AnyTransport {
 public:
  /// Takes `transport` over.
  template <typename T>
  requires(!std::same_as<std::remove_cvref_t<T>, AnyTransport>) &&
      ByteTransport<T> AnyTransport(T transport)  // NOLINT(google-explicit-constructor): a transport is an AnyTransport
      : impl_(std::make_unique<Model<T>>(std::move(transport))) {}

  AnyTransport(AnyTransport&&) noexcept = default;
  AnyTransport& operator=(AnyTransport&&) noexcept = default;
  AnyTransport(const AnyTransport&) = delete;
  AnyTransport& operator=(const AnyTransport&) = delete;
  ~AnyTransport() = default;

  /// ByteTransport::send of the transport held.
  void send(std::span<const std::uint8_t> bytes) { impl_->send(bytes); }
  /// ByteTransport::receive of the transport held.
  std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) { return impl_->receive(buffer, timeout_s); }
  /// The transport's description(), or `"transport"` if it has none.
  [[nodiscard]] std::string description() const { return impl_->description(); }

 private:
  struct Concept {
    virtual ~Concept() = default;
    virtual void send(std::span<const std::uint8_t> bytes) = 0;
    virtual std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) = 0;
    [[nodiscard]] virtual std::string description() const = 0;
  };
  template <typename T>
  struct Model final : Concept {
    explicit Model(T t) : transport(std::move(t)) {}
    void send(std::span<const std::uint8_t> bytes) override { transport.send(bytes); }
    std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) override {
      return transport.receive(buffer, timeout_s);
    }
    [[nodiscard]] std::string description() const override {
      if constexpr (requires(const T& t) {
                      { t.description() } -> std::convertible_to<std::string>;
                    }) {
        return transport.description();
      } else {
        return "transport";
      }
    }
    T transport;
  };
  std::unique_ptr<Concept> impl_;
};
static_assert(ByteTransport<AnyTransport>);

}  // namespace adaptseg::mavlink
