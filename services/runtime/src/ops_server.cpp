#include "fleet/service/ops_server.hpp"

#include <fcntl.h>
#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstring>
#include <list>
#include <vector>

#include "fleet/service/process_metrics.hpp"

namespace fleet::service {
namespace {

using Clock = std::chrono::steady_clock;

void setNonBlocking(int fd) {
  ::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL, 0) | O_NONBLOCK);
}

std::string httpAnswer(int status, const std::string& body, const char* type) {
  const char* reason = status == 200   ? "OK"
                       : status == 404 ? "Not Found"
                       : status == 405 ? "Method Not Allowed"
                       : status == 431 ? "Request Header Fields Too Large"
                       : status == 400 ? "Bad Request"
                                       : "Service Unavailable";
  return "HTTP/1.1 " + std::to_string(status) + " " + reason + "\r\nContent-Type: " + type +
         "\r\nContent-Length: " + std::to_string(body.size()) +
         "\r\nCache-Control: no-store\r\nConnection: close\r\n\r\n" + body;
}

struct Connection {
  int fd = -1;
  Clock::time_point deadline;
  std::string in;
  std::string out;
  std::size_t sent = 0;
  bool writing = false;
};

}  // namespace

OpsServer::OpsServer(const metrics::Registry& registry, const Health& health, OpsLimits limits)
    : registry_(registry), health_(health), limits_(limits) {}

OpsServer::~OpsServer() {
  stop();
}

std::optional<std::string> OpsServer::start(const OpsSettings& s) {
  if (s.port < 0) {
    return std::nullopt;
  }
  const std::string where = s.host + ":" + std::to_string(s.port);
  if (s.port > 65535) {
    return "metrics port " + std::to_string(s.port) + " is out of range (0-65535)";
  }
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = AI_PASSIVE;
  addrinfo* found = nullptr;
  if (const int rc = ::getaddrinfo(s.host.c_str(), std::to_string(s.port).c_str(), &hints, &found); rc != 0) {
    return "cannot listen on " + where + " for /metrics: " + ::gai_strerror(rc);
  }
  int err = 0;
  for (addrinfo* a = found; a != nullptr && listenFd_ < 0; a = a->ai_next) {
    const int fd = ::socket(a->ai_family, a->ai_socktype | SOCK_CLOEXEC, a->ai_protocol);
    if (fd < 0) {
      err = errno;
      continue;
    }
    int yes = 1;
    ::setsockopt(fd, SOL_SOCKET, SO_REUSEADDR, &yes, sizeof(yes));  // never SO_REUSEPORT
    if (::bind(fd, a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd, 128) != 0) {
      err = errno;
      ::close(fd);
      continue;
    }
    listenFd_ = fd;
  }
  ::freeaddrinfo(found);
  if (listenFd_ < 0) {
    return "cannot listen on " + where + " for /metrics" +
           (err != 0 ? std::string(": ") + std::strerror(err) : std::string());
  }
  setNonBlocking(listenFd_);
  sockaddr_storage bound{};
  socklen_t len = sizeof(bound);
  ::getsockname(listenFd_, reinterpret_cast<sockaddr*>(&bound), &len);
  port_ = ntohs(bound.ss_family == AF_INET6 ? reinterpret_cast<sockaddr_in6*>(&bound)->sin6_port
                                            : reinterpret_cast<sockaddr_in*>(&bound)->sin_port);
  if (::pipe2(wakeFd_, O_CLOEXEC | O_NONBLOCK) != 0) {
    ::close(listenFd_);
    listenFd_ = -1;
    return "cannot start the ops port: " + std::string(std::strerror(errno));
  }
  thread_ = std::thread([this] { serve(); });
  return std::nullopt;
}

void OpsServer::stop() {
  if (thread_.joinable()) {
    const char c = 0;
    [[maybe_unused]] const auto n = ::write(wakeFd_[1], &c, 1);
    thread_.join();
  }
  for (int* fd : {&listenFd_, &wakeFd_[0], &wakeFd_[1]}) {
    if (*fd >= 0) {
      ::close(*fd);
      *fd = -1;
    }
  }
}

std::string OpsServer::answer(const std::string& head) const {
  const auto lineEnd = head.find("\r\n");
  const std::string line = head.substr(0, lineEnd);
  const auto sp1 = line.find(' ');
  const auto sp2 = sp1 == std::string::npos ? sp1 : line.find(' ', sp1 + 1);
  if (sp2 == std::string::npos) {
    return httpAnswer(400, "malformed request line\n", "text/plain; charset=utf-8");
  }
  const std::string method = line.substr(0, sp1);
  std::string path = line.substr(sp1 + 1, sp2 - sp1 - 1);
  path = path.substr(0, path.find('?'));
  if (method != "GET") {
    return httpAnswer(405, "GET only\n", "text/plain; charset=utf-8");
  }
  if (path == "/metrics") {
    return httpAnswer(200, registry_.exposition() + processMetricsText(),
                      "text/plain; version=0.0.4; charset=utf-8");
  }
  if (path == "/livez" || path == "/readyz") {
    const auto a = path == "/livez" ? health_.liveness() : health_.readiness();
    return httpAnswer(a.ok ? 200 : 503, a.text, "text/plain; charset=utf-8");
  }
  return httpAnswer(404, "not found\n", "text/plain; charset=utf-8");
}

void OpsServer::serve() {
  std::list<Connection> conns;  // oldest first
  std::vector<pollfd> fds;
  std::vector<Connection*> order;
  auto close = [&](std::list<Connection>::iterator it) {
    ::close(it->fd);
    return conns.erase(it);
  };
  for (;;) {
    const auto now = Clock::now();
    for (auto it = conns.begin(); it != conns.end();) {
      if (it->deadline <= now) {
        ++timedOut_;
        it = close(it);
      } else {
        ++it;
      }
    }
    fds.assign({{wakeFd_[0], POLLIN, 0}, {listenFd_, POLLIN, 0}});
    order.clear();
    auto wait = std::chrono::milliseconds(1000);
    for (auto& c : conns) {
      fds.push_back({c.fd, static_cast<short>(c.writing ? POLLOUT : POLLIN), 0});
      order.push_back(&c);
      wait = std::min(wait, std::chrono::ceil<std::chrono::milliseconds>(c.deadline - now));
    }
    if (::poll(fds.data(), fds.size(), static_cast<int>(std::max<std::int64_t>(wait.count(), 1))) < 0) {
      if (errno == EINTR) {
        continue;
      }
      return;
    }
    if (fds[0].revents != 0) {
      break;
    }
    std::vector<Connection*> done;
    for (std::size_t i = 2; i < fds.size(); ++i) {
      if (fds[i].revents == 0) {
        continue;
      }
      auto& c = *order[i - 2];
      if (!c.writing) {
        char buf[2048];
        const auto n = ::recv(c.fd, buf, sizeof buf, 0);
        if (n <= 0) {
          if (n == 0 || (errno != EAGAIN && errno != EINTR)) {
            done.push_back(&c);
          }
          continue;
        }
        c.in.append(buf, static_cast<std::size_t>(n));
        const auto end = c.in.find("\r\n\r\n");
        if (end == std::string::npos && c.in.size() <= limits_.maxHeaderBytes) {
          continue;
        }
        c.out = end == std::string::npos || end > limits_.maxHeaderBytes
                    ? httpAnswer(431, "request head too large\n", "text/plain; charset=utf-8")
                    : answer(c.in.substr(0, end));
        c.writing = true;
        c.deadline = Clock::now() + std::chrono::milliseconds(limits_.writeTimeoutMs);
      }
      const auto n = ::send(c.fd, c.out.data() + c.sent, c.out.size() - c.sent, MSG_NOSIGNAL);
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) {
        continue;
      }
      if (n < 0 || (c.sent += static_cast<std::size_t>(n)) == c.out.size()) {
        done.push_back(&c);  // answered (or gone): close; a client reads to the close
      }
    }
    if (!done.empty()) {
      for (auto it = conns.begin(); it != conns.end();) {
        it = std::find(done.begin(), done.end(), &*it) != done.end() ? close(it) : std::next(it);
      }
    }
    if (fds[1].revents == 0) {
      continue;
    }
    for (;;) {
      const int fd = ::accept4(listenFd_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) {
        break;  // EAGAIN: all taken; EMFILE and the like: the next turn tries again
      }
      int yes = 1;
      ::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &yes, sizeof(yes));
      if (static_cast<int>(conns.size()) >= limits_.maxConnections) {
        // Full: the connection that has waited longest for its head goes (it is the slowest).
        auto victim =
            std::find_if(conns.begin(), conns.end(), [](const Connection& c) { return !c.writing; });
        if (victim == conns.end()) {
          victim = conns.begin();
        }
        ++evicted_;
        close(victim);
      }
      conns.push_back(
          {fd, Clock::now() + std::chrono::milliseconds(limits_.headerTimeoutMs), {}, {}, 0, false});
    }
  }
  for (auto& c : conns) {
    ::close(c.fd);
  }
}

}  // namespace fleet::service
