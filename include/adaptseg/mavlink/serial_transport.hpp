#pragma once
/// @file
/// MAVLink over a serial device (a telemetry radio, a flight controller's USB or TELEM port
/// wired to a companion computer): a ByteTransport of POSIX termios calls. CMake target
/// adaptseg::mavlink (POSIX headers).
///
/// @code
/// adaptseg::mavlink::SerialTransport serial("/dev/ttyACM0", 57600);
/// @endcode

#include <adaptseg/mavlink/detail/posix_fd.hpp>
#include <adaptseg/mavlink/transport.hpp>

#include <fcntl.h>
#include <sys/types.h>
#include <termios.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstddef>
#include <cstdint>
#include <span>
#include <stdexcept>
#include <string>
#include <utility>

namespace adaptseg::mavlink {

/// A serial device in raw mode: 8 data bits, no parity, one stop bit, no flow control, no
/// modem control lines, at one of the baud rates of baud_rates(). Non-blocking; waits bounded by
/// poll(2). Move-only; not thread-safe.
class SerialTransport {
 public:
  /// Opens `device` (`/dev/ttyUSB0`, `/dev/ttyACM0`, `/dev/serial0`) at `baud` and flushes
  /// what it held.
  /// @throws std::invalid_argument if `baud` is not one of baud_rates();
  ///         std::system_error naming the device if it cannot be opened or is no terminal.
  SerialTransport(std::string device, int baud) : device_(std::move(device)), baud_(baud) {
    const speed_t speed = speed_of(baud);
    fd_ = detail::FileDescriptor(::open(device_.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK));
    if (!fd_.valid()) detail::throw_errno(errno, "serial device " + device_);
    termios tio{};
    if (::tcgetattr(fd_.get(), &tio) != 0) detail::throw_errno(errno, "serial device " + device_ + ": tcgetattr");
    // Raw mode, spelled out in POSIX flags (cfmakeraw is not POSIX).
    tio.c_iflag &=
        ~static_cast<tcflag_t>(IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL | IXON | IXOFF | IXANY);
    tio.c_oflag &= ~static_cast<tcflag_t>(OPOST);
    tio.c_lflag &= ~static_cast<tcflag_t>(ECHO | ECHONL | ICANON | ISIG | IEXTEN);
    tio.c_cflag &= ~static_cast<tcflag_t>(CSIZE | PARENB | CSTOPB);
    tio.c_cflag |= static_cast<tcflag_t>(CS8 | CLOCAL | CREAD);
#ifdef CRTSCTS
    tio.c_cflag &= ~static_cast<tcflag_t>(CRTSCTS);
#endif
    tio.c_cc[VMIN] = 0;
    tio.c_cc[VTIME] = 0;
    if (::cfsetispeed(&tio, speed) != 0 || ::cfsetospeed(&tio, speed) != 0) {
      detail::throw_errno(errno, "serial device " + device_ + ": baud rate " + std::to_string(baud));
    }
    if (::tcsetattr(fd_.get(), TCSANOW, &tio) != 0) {
      detail::throw_errno(errno, "serial device " + device_ + ": tcsetattr");
    }
    ::tcflush(fd_.get(), TCIOFLUSH);
  }

  /// Writes all of `bytes`, waiting up to kWriteTimeoutS for room in the device's buffer.
  /// @throws std::system_error if the device fails or stays full.
  void send(std::span<const std::uint8_t> bytes) {
    std::size_t done = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_.get(), bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && errno == EINTR) continue;
      if (n < 0 && errno != EAGAIN && errno != EWOULDBLOCK) detail::throw_errno(errno, description() + ": write");
      if (!detail::wait_fd(fd_.get(), POLLOUT, kWriteTimeoutS, description())) {
        detail::throw_errno(ETIMEDOUT, description() + ": write");
      }
    }
  }

  /// What the device holds (up to `buffer`'s size), or 0 after `timeout_s` without a byte.
  /// @throws std::system_error if the device fails (unplugged: EIO).
  std::size_t receive(std::span<std::uint8_t> buffer, double timeout_s) {
    if (!detail::wait_fd(fd_.get(), POLLIN, timeout_s, description())) return 0;
    const ssize_t n = ::read(fd_.get(), buffer.data(), buffer.size());
    if (n < 0) {
      if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR) return 0;
      detail::throw_errno(errno, description() + ": read");
    }
    return static_cast<std::size_t>(n);
  }

  /// `"serial:DEVICE:BAUD"`, as open_transport() reads it.
  [[nodiscard]] std::string description() const { return "serial:" + device_ + ":" + std::to_string(baud_); }

  /// The baud rates accepted (those POSIX and Linux name).
  [[nodiscard]] static std::span<const int> baud_rates() { return kBaudRates; }

  /// Longest wait for room in the device's write buffer [s].
  static constexpr double kWriteTimeoutS = 1.0;

 private:
  static constexpr std::array kBaudRates{9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600, 1500000};

  static speed_t speed_of(int baud) {
    switch (baud) {
      case 9600: return B9600;
      case 19200: return B19200;
      case 38400: return B38400;
#ifdef B57600
      case 57600: return B57600;
#endif
#ifdef B115200
      case 115200: return B115200;
#endif
#ifdef B230400
      case 230400: return B230400;
#endif
#ifdef B460800
      case 460800: return B460800;
#endif
#ifdef B500000
      case 500000: return B500000;
#endif
#ifdef B921600
      case 921600: return B921600;
#endif
#ifdef B1500000
      case 1500000: return B1500000;
#endif
      default: break;
    }
    std::string known;
    for (const int b : kBaudRates) known += (known.empty() ? "" : ", ") + std::to_string(b);
    throw std::invalid_argument("serial baud rate must be one of " + known + " (got " + std::to_string(baud) + ")");
  }

  std::string device_;
  int baud_ = 0;
  detail::FileDescriptor fd_;
};
static_assert(ByteTransport<SerialTransport>);

}  // namespace adaptseg::mavlink
