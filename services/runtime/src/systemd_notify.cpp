#include "fleet/service/systemd_notify.hpp"

#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <cstdlib>
#include <cstring>

namespace fleet::service {
namespace {

std::optional<long long> envNumber(const char* name) {
  const char* v = std::getenv(name);
  if (v == nullptr || *v == '\0') {
    return std::nullopt;
  }
  long long n = 0;
  const auto* end = v + std::strlen(v);
  const auto [p, ec] = std::from_chars(v, end, n);
  if (ec != std::errc() || p != end) {
    return std::nullopt;
  }
  return n;
}

}  // namespace

std::string notifyServiceManager(std::string_view state) {
  const char* path = std::getenv("NOTIFY_SOCKET");
  if (path == nullptr || *path == '\0') {
    return {};
  }
  const std::size_t len = std::strlen(path);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if ((path[0] != '/' && path[0] != '@') || len >= sizeof(addr.sun_path)) {
    return "NOTIFY_SOCKET '" + std::string(path) + "' is not an absolute path or an abstract name (@...)";
  }
  std::memcpy(addr.sun_path, path, len);
  if (path[0] == '@') {
    addr.sun_path[0] = '\0';
  }
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  if (fd < 0) {
    return "cannot open a socket for NOTIFY_SOCKET: " + std::string(std::strerror(errno));
  }
  const auto addrLen = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + len);
  const auto sent = ::sendto(fd, state.data(), state.size(), MSG_NOSIGNAL,
                             reinterpret_cast<const sockaddr*>(&addr), addrLen);
  const int err = errno;
  ::close(fd);
  if (sent != static_cast<ssize_t>(state.size())) {
    return "cannot notify the service manager at " + std::string(path) + ": " + std::strerror(err);
  }
  return {};
}

std::optional<std::chrono::microseconds> watchdogPeriod() {
  const auto usec = envNumber("WATCHDOG_USEC");
  if (!usec || *usec <= 0) {
    return std::nullopt;
  }
  if (const auto pid = envNumber("WATCHDOG_PID"); pid && *pid != static_cast<long long>(::getpid())) {
    return std::nullopt;  // meant for another process (a parent that started this one)
  }
  return std::chrono::microseconds(*usec);
}

}  // namespace fleet::service
