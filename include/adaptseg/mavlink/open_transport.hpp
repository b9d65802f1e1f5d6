#pragma once
/// @file
/// open_transport(): a transport from the connection string a user gives a program
/// (`udpin:14550`, `udpout:127.0.0.1:14580`, `serial:/dev/ttyACM0:57600`). CMake target
/// adaptseg::mavlink (POSIX headers).

#include <adaptseg/mavlink/serial_transport.hpp>
#include <adaptseg/mavlink/transport.hpp>
#include <adaptseg/mavlink/udp_transport.hpp>

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace adaptseg::detail {

// "1".."65535" (or "0" where allowed) as a port; nullopt-like -1 otherwise.
inline int parse_port(std::string_view text, bool allow_zero) {
  if (text.empty() || text.size() > 5) return -1;
  int value = 0;
  for (const char c : text) {
    if (c < '0' || c > '9') return -1;
    value = value * 10 + (c - '0');
  }
  if (value > 65535 || (value == 0 && !allow_zero)) return -1;
  return value;
}

inline bool all_digits(std::string_view text) {
  if (text.empty() || text.size() > 9) return false;
  for (const char c : text) {
    if (c < '0' || c > '9') return false;
  }
  return true;
}

}  // namespace adaptseg::detail

namespace adaptseg::mavlink {

/// The forms open_transport() reads, for help texts and error messages.
inline constexpr std::string_view kTransportForms =
    "udpin:[HOST:]PORT (listen, answer the sender), udpout:HOST:PORT (send to), serial:DEVICE[:BAUD] (57600 if "
    "left out)";

/// Opens the transport `spec` names:
/// - `udpin:PORT` or `udpin:HOST:PORT`: UdpTransport::listen (HOST `0.0.0.0` if left out; PORT
///   0: an ephemeral port), as a ground station listens on 14550 for SITL;
/// - `udpout:HOST:PORT`: UdpTransport::connect, as a companion sends to PX4 SITL's 14580;
/// - `serial:DEVICE` or `serial:DEVICE:BAUD`: SerialTransport (57600 baud if left out).
/// @throws std::invalid_argument naming `spec` and the forms if it is none of them (or a port,
///         a host, a baud rate is bad); std::system_error if the socket or device cannot be opened.
[[nodiscard]] inline AnyTransport open_transport(std::string_view spec) {
  const auto bad = [&](std::string_view why) {
    return std::invalid_argument("connection '" + std::string(spec) + "': " + std::string(why) + "; use " +
                                 std::string(kTransportForms));
  };
  const std::size_t colon = spec.find(':');
  if (colon == std::string_view::npos) throw bad("no scheme");
  const std::string_view scheme = spec.substr(0, colon);
  const std::string_view rest = spec.substr(colon + 1);
  if (scheme == "udpin" || scheme == "udpout") {
    const std::size_t last = rest.rfind(':');
    const std::string_view host = last == std::string_view::npos ? std::string_view{} : rest.substr(0, last);
    const std::string_view port_text = last == std::string_view::npos ? rest : rest.substr(last + 1);
    const int port = detail::parse_port(port_text, scheme == "udpin");
    if (port < 0) throw bad("the port must be a number in " + std::string(scheme == "udpin" ? "0" : "1") + "..65535");
    if (scheme == "udpin") {
      return UdpTransport::listen(static_cast<std::uint16_t>(port), host.empty() ? "0.0.0.0" : std::string(host));
    }
    if (host.empty()) throw bad("udpout needs HOST:PORT");
    return UdpTransport::connect(std::string(host), static_cast<std::uint16_t>(port));
  }
  if (scheme == "serial") {
    if (rest.empty()) throw bad("no device");
    const std::size_t last = rest.rfind(':');
    if (last != std::string_view::npos && detail::all_digits(rest.substr(last + 1))) {
      return SerialTransport(std::string(rest.substr(0, last)), std::stoi(std::string(rest.substr(last + 1))));
    }
    return SerialTransport(std::string(rest), 57600);
  }
  throw bad("unknown scheme '" + std::string(scheme) + "'");
}

}  // namespace adaptseg::mavlink
