// The service manager's notification protocol as a service speaks it: datagrams on the socket named
// by NOTIFY_SOCKET (a path or an abstract name), READY=1 at the loop's first refresh, WATCHDOG=1
// when a watchdog is asked for, STOPPING=1 when the service goes; nothing without NOTIFY_SOCKET.

#include "fleet/service/systemd_notify.hpp"

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "fleet/service/service_ops.hpp"

using namespace fleet;

namespace {

/// A datagram socket standing in for systemd's notification socket, bound at `name` (a path, or
/// "@..." for the abstract namespace) and named by NOTIFY_SOCKET while it lives.
class FakeManager {
 public:
  explicit FakeManager(const std::string& name) {
    fd_ = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC | SOCK_NONBLOCK, 0);
    sockaddr_un addr{};
    addr.sun_family = AF_UNIX;
    name.copy(addr.sun_path, sizeof(addr.sun_path) - 1);
    if (name[0] == '@') {
      addr.sun_path[0] = '\0';
    } else {
      path_ = name;
    }
    const auto len = static_cast<socklen_t>(offsetof(sockaddr_un, sun_path) + name.size());
    EXPECT_EQ(::bind(fd_, reinterpret_cast<sockaddr*>(&addr), len), 0) << name;
    ::setenv("NOTIFY_SOCKET", name.c_str(), 1);
  }
  ~FakeManager() {
    ::unsetenv("NOTIFY_SOCKET");
    ::close(fd_);
    if (!path_.empty()) {
      std::filesystem::remove(path_);
    }
  }
  /// Every datagram received so far (sendto has returned, so they are queued).
  std::vector<std::string> received() {
    std::vector<std::string> out;
    char buf[512];
    for (ssize_t n; (n = ::recv(fd_, buf, sizeof buf, 0)) >= 0;) {
      out.emplace_back(buf, static_cast<std::size_t>(n));
    }
    return out;
  }

 private:
  int fd_ = -1;
  std::string path_;
};

std::string tempSocketPath() {
  return (std::filesystem::temp_directory_path() / ("fleet-notify-" + std::to_string(::getpid()))).string();
}

}  // namespace

TEST(SystemdNotify, NothingWithoutNotifySocket) {
  ::unsetenv("NOTIFY_SOCKET");
  EXPECT_EQ(service::notifyServiceManager("READY=1"), "");
}

TEST(SystemdNotify, SendsToAPathAndToAnAbstractName) {
  {
    FakeManager m(tempSocketPath());
    EXPECT_EQ(service::notifyServiceManager("READY=1"), "");
    EXPECT_EQ(m.received(), std::vector<std::string>{"READY=1"});
  }
  {
    FakeManager m("@fleet-notify-test-" + std::to_string(::getpid()));
    EXPECT_EQ(service::notifyServiceManager("STATUS=x\nWATCHDOG=1"), "");
    EXPECT_EQ(m.received(), std::vector<std::string>{"STATUS=x\nWATCHDOG=1"});
  }
}

TEST(SystemdNotify, ABadSocketIsAnErrorNamingIt) {
  ::setenv("NOTIFY_SOCKET", "relative/path", 1);
  EXPECT_NE(service::notifyServiceManager("READY=1").find("relative/path"), std::string::npos);
  ::setenv("NOTIFY_SOCKET", "/nonexistent/fleet-notify", 1);
  EXPECT_NE(service::notifyServiceManager("READY=1").find("/nonexistent/fleet-notify"), std::string::npos);
  ::unsetenv("NOTIFY_SOCKET");
}

TEST(SystemdNotify, WatchdogPeriodFromTheEnvironmentForThisProcessOnly) {
  ::unsetenv("WATCHDOG_PID");
  ::unsetenv("WATCHDOG_USEC");
  EXPECT_FALSE(service::watchdogPeriod().has_value());
  ::setenv("WATCHDOG_USEC", "30000000", 1);
  EXPECT_EQ(service::watchdogPeriod(), std::chrono::seconds(30));
  ::setenv("WATCHDOG_PID", std::to_string(::getpid()).c_str(), 1);
  EXPECT_EQ(service::watchdogPeriod(), std::chrono::seconds(30));
  ::setenv("WATCHDOG_PID", std::to_string(::getpid() + 1).c_str(), 1);
  EXPECT_FALSE(service::watchdogPeriod().has_value());
  ::unsetenv("WATCHDOG_PID");
  for (const char* bad : {"", "abc", "-5", "0", "12x"}) {
    ::setenv("WATCHDOG_USEC", bad, 1);
    EXPECT_FALSE(service::watchdogPeriod().has_value()) << bad;
  }
  ::unsetenv("WATCHDOG_USEC");
}

TEST(SystemdNotify, AServiceSaysReadyAtItsFirstTurnPetsTheWatchdogAndSaysStopping) {
  FakeManager m(tempSocketPath());
  ::setenv("WATCHDOG_USEC", "30000000", 1);
  {
    service::ServiceOps ops("unit_test");
    EXPECT_TRUE(m.received().empty());  // not ready before its loop turns
    ops.refresh();
    EXPECT_EQ(m.received(), (std::vector<std::string>{"READY=1", "WATCHDOG=1"}));
    ops.refresh();  // within the second: nothing more
    EXPECT_TRUE(m.received().empty());
  }
  EXPECT_EQ(m.received(), std::vector<std::string>{"STOPPING=1"});
  ::unsetenv("WATCHDOG_USEC");
  {
    service::ServiceOps ops("unit_test");
    ops.refresh();
    ops.stopping();
    ops.stopping();
  }
  EXPECT_EQ(m.received(), (std::vector<std::string>{"READY=1", "STOPPING=1"}));  // no watchdog asked for
}
