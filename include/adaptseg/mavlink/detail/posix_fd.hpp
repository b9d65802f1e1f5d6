#pragma once
/// @file
/// A POSIX file descriptor that closes itself, errno as std::system_error, and a bounded wait
/// for a descriptor to become readable or writable (poll(2)). Leaf internals of the transports
/// of adaptseg::mavlink (CMake target adaptseg::mavlink; POSIX headers only).

#include <poll.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cmath>
#include <string>
#include <system_error>
#include <utility>

namespace adaptseg::detail {

/// Owns a file descriptor (a socket, a tty): closed by the destructor; move-only.
class FileDescriptor {
 public:
  FileDescriptor() = default;
  explicit FileDescriptor(int fd) : fd_(fd) {}
  FileDescriptor(const FileDescriptor&) = delete;
  FileDescriptor& operator=(const FileDescriptor&) = delete;
  FileDescriptor(FileDescriptor&& other) noexcept : fd_(std::exchange(other.fd_, -1)) {}
  FileDescriptor& operator=(FileDescriptor&& other) noexcept {
    if (this != &other) {
      reset();
      fd_ = std::exchange(other.fd_, -1);
    }
    return *this;
  }
  ~FileDescriptor() { reset(); }

  [[nodiscard]] int get() const { return fd_; }
  [[nodiscard]] bool valid() const { return fd_ >= 0; }
  void reset() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }

 private:
  int fd_ = -1;
};

/// Throws std::system_error for `err` (an errno value); its what() is "<what>: <strerror>".
[[noreturn]] inline void throw_errno(int err, const std::string& what) {
  throw std::system_error(err, std::generic_category(), what);
}

/// Waits at most `timeout_s` (0: just looks) until `fd` has one of `events` (POLLIN, POLLOUT).
/// True if it has; false on timeout or when a signal interrupted the wait (the caller's loop
/// reads its clock again). An error or hang-up on the descriptor counts as ready, so that the
/// read or write that follows reports it.
/// @throws std::system_error if poll itself fails.
inline bool wait_fd(int fd, short events, double timeout_s, const std::string& what) {
  pollfd p{};
  p.fd = fd;
  p.events = events;
  int timeout_ms = 0;
  if (timeout_s > 0.0) {
    const double ms = std::ceil(timeout_s * 1000.0);
    timeout_ms = ms >= static_cast<double>(INT_MAX) ? INT_MAX : static_cast<int>(ms);
  }
  const int n = ::poll(&p, 1, timeout_ms);
  if (n < 0) {
    if (errno == EINTR) return false;
    throw_errno(errno, what + ": poll");
  }
  return n > 0;
}

}  // namespace adaptseg::detail
