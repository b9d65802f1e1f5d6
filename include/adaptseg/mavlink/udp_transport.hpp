#pragma once
/// @file
/// MAVLink over UDP (IPv4), as PX4 and ArduPilot SITL, companion computers and ground stations
/// speak it: a ByteTransport of POSIX sockets. CMake target adaptseg::mavlink (POSIX headers).
///
/// @code
/// // A ground station's end: listen where SITL sends (14550) and answer whoever sent.
/// auto udp = adaptseg::mavlink::UdpTransport::listen(14550);
/// // A companion's end: send to an autopilot's port (PX4 SITL's onboard link listens on 14580).
/// auto out = adaptseg::mavlink::UdpTransport::connect("127.0.0.1", 14580);
/// @endcode

#include <adaptseg/mavlink/detail/posix_fd.hpp>
#include <adaptseg/mavlink/transport.hpp>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/types.h>

#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>

namespace adaptseg::mavlink {

/// A UDP socket that speaks MAVLink with one peer, non-blocking, waits bounded by poll(2).
///
/// Two ways to open it:
/// - listen(port): binds the port and learns the peer from the datagrams it receives (the
///   sender of the latest one, as a ground station does on 14550 and pymavlink's `udpin:`);
///   until a datagram has come, send() has nowhere to go and drops the frame (counted in
///   unsent_frames());
/// - connect(host, port): sends to host:port from an ephemeral (or given) local port and
///   reads datagrams from anyone (the socket is not connect(2)ed, so an ICMP "port
///   unreachable" while the autopilot starts is no error).
///
/// One datagram per send() and per receive(). IPv4 only. Move-only; not thread-safe.
class UdpTransport {
 public:
  /// Binds `host:port` (`"0.0.0.0"`: every interface; port 0: an ephemeral port, see
  /// local_port()) and learns the peer from what arrives.
  /// @throws std::invalid_argument if `host` is not an IPv4 address or a name that resolves
  ///         to one; std::system_error if the socket cannot be made or bound (the port taken).
  [[nodiscard]] static UdpTransport listen(std::uint16_t port, const std::string& host = "0.0.0.0") {
    UdpTransport t(resolve(host, port, "UDP listen address"), std::nullopt);
    t.description_ = "udpin:" + host + ":" + std::to_string(t.local_port());
    return t;
  }

  /// Sends to `host:port` from `local_port` (0: ephemeral) and reads datagrams from anyone.
  /// @throws std::invalid_argument if `host` does not resolve to an IPv4 address, or `port`
  ///         is 0; std::system_error if the socket cannot be made or bound.
  [[nodiscard]] static UdpTransport connect(const std::string& host, std::uint16_t port, std::uint16_t local_port = 0) {
    if (port == 0) throw std::invalid_argument("UDP peer port must be 1..65535 (got 0)");
    UdpTransport t(resolve("0.0.0.0", local_port, "UDP local address"), resolve(host, port, "UDP peer"));
    t.description_ = "udpout:" + host + ":" + std::to_string(port);
    return t;
  }

  /// Sends `bytes` as one datagram to the peer; dropped (and counted) while no peer is known,
  /// or when the socket's send buffer is full (UDP may lose a datagram anyway).
  /// @throws std::system_error for any other failure of sendto(2).
  void send(std::span<const std::uint8_t> bytes) {
    if (!peer_) {
      ++unsent_frames_;
      return;
    }
    const ssize_t n = ::sendto(fd_.get(), bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&*peer_),
                               sizeof(sockaddr_in));
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == ENOBUFS || errno == EINTR || errno == ECONNREFUSED) {
        ++unsent_frames_;
        return;
      }
      detail::throw_errno(errno, "UDP send to " + peer());
    }
  }

  /// One datagram (truncated to `buffer`'s size), or 0 after `timeout_s` without one. In
  /// listen mode its sender becomes the peer.
  /// @throws std::system_error for a failure of poll(2) or recvfrom(2).
  std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) {
    if (!detail::wait_fd(fd_.get(), POLLIN, timeout_s, description_)) return 0;
    sockaddr_in from{};
    socklen_t from_length = sizeof(from);
    const ssize_t n =
        ::recvfrom(fd_.get(), buffer.data(), buffer.size(), 0, reinterpret_cast<sockaddr*>(&from), &from_length);
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR || errno == ECONNREFUSED) return 0;
      detail::throw_errno(errno, description_ + ": receive");
    }
    if (learn_peer_ && from.sin_family == AF_INET) peer_ = from;
    return static_cast<std::size_t>(n);
  }

  /// The local port the socket is bound to (the ephemeral one when 0 was asked for).
  [[nodiscard]] std::uint16_t local_port() const {
    sockaddr_in local{};
    socklen_t length = sizeof(local);
    if (::getsockname(fd_.get(), reinterpret_cast<sockaddr*>(&local), &length) != 0) return 0;
    return ntohs(local.sin_port);
  }

  /// Whether a peer is known (always in connect mode; after the first datagram in listen mode).
  [[nodiscard]] bool has_peer() const { return peer_.has_value(); }

  /// The peer as `"a.b.c.d:port"`, or `""` while none is known.
  [[nodiscard]] std::string peer() const {
    if (!peer_) return {};
    char text[INET_ADDRSTRLEN] = {};
    ::inet_ntop(AF_INET, &peer_->sin_addr, text, sizeof(text));
    return std::string(text) + ":" + std::to_string(ntohs(peer_->sin_port));
  }

  /// Frames send() dropped: no peer yet, or the send buffer full.
  [[nodiscard]] std::uint64_t unsent_frames() const { return unsent_frames_; }

  /// `"udpin:HOST:PORT"` or `"udpout:HOST:PORT"`, as open_transport() reads it.
  [[nodiscard]] std::string description() const { return description_; }

 private:
  UdpTransport(const sockaddr_in& local, std::optional<sockaddr_in> peer)
      : fd_(::socket(AF_INET, SOCK_DGRAM, 0)), peer_(peer), learn_peer_(!peer) {
    if (!fd_.valid()) detail::throw_errno(errno, "UDP socket");
    const int flags = ::fcntl(fd_.get(), F_GETFL, 0);
    if (flags < 0 || ::fcntl(fd_.get(), F_SETFL, flags | O_NONBLOCK) < 0) {
      detail::throw_errno(errno, "UDP socket: O_NONBLOCK");
    }
    if (::bind(fd_.get(), reinterpret_cast<const sockaddr*>(&local), sizeof(local)) != 0) {
      char text[INET_ADDRSTRLEN] = {};
      ::inet_ntop(AF_INET, &local.sin_addr, text, sizeof(text));
      detail::throw_errno(errno, "UDP bind to " + std::string(text) + ":" + std::to_string(ntohs(local.sin_port)));
    }
  }

  // host (a dotted quad or a name) and port as an IPv4 address.
  static sockaddr_in resolve(const std::string& host, std::uint16_t port, const std::string& what) {
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_port = htons(port);
    if (::inet_pton(AF_INET, host.c_str(), &address.sin_addr) == 1) return address;
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* found = nullptr;
    const int rc = ::getaddrinfo(host.c_str(), nullptr, &hints, &found);
    if (rc != 0 || found == nullptr) {
      throw std::invalid_argument(what + " '" + host + "' is no IPv4 address or name that resolves to one (" +
                                  ::gai_strerror(rc) + ")");
    }
    address.sin_addr = reinterpret_cast<const sockaddr_in*>(found->ai_addr)->sin_addr;
    ::freeaddrinfo(found);
    return address;
  }

  detail::FileDescriptor fd_;
  std::optional<sockaddr_in> peer_;
  bool learn_peer_ = true;
  std::uint64_t unsent_frames_ = 0;
  std::string description_;
};
static_assert(ByteTransport<UdpTransport>);

}  // namespace adaptseg::mavlink
