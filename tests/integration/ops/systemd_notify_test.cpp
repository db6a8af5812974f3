// A real service under a stand-in for systemd's notification socket, as a Type=notify unit with
// WatchdogSec= runs it: READY=1 once its loop turns, WATCHDOG=1 again and again from that loop,
// STOPPING=1 on SIGTERM, then exit 0.

#include <gtest/gtest.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "test_process.hpp"

using namespace std::chrono_literals;
namespace fs = std::filesystem;

namespace {

/// The next datagram on `fd`, or "" when none comes within `timeout`.
std::string receive(int fd, std::chrono::seconds timeout) {
  timeval tv{static_cast<time_t>(timeout.count()), 0};
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof(tv));
  char buf[512];
  const auto n = ::recv(fd, buf, sizeof buf, 0);
  return n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : std::string();
}

}  // namespace

TEST(OpsSystemd, AServiceSaysReadyPetsTheWatchdogFromItsLoopAndSaysStopping) {
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  const auto dir = fs::temp_directory_path() / ("fleet-ops-notify-" + domain);
  fs::remove_all(dir);
  fs::create_directories(dir);
  const auto socketPath = (dir / "notify").string();
  const int fd = ::socket(AF_UNIX, SOCK_DGRAM | SOCK_CLOEXEC, 0);
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  socketPath.copy(addr.sun_path, sizeof(addr.sun_path) - 1);
  ASSERT_EQ(::bind(fd, reinterpret_cast<sockaddr*>(&addr), sizeof(addr)), 0) << socketPath;
  std::ofstream(dir / "manager.json") << nlohmann::json{
      {"db", (dir / "fleet.db").string()},
      {"stations", FLEET_SOURCE_DIR
       "/sim/scenarios/one_robot.json"}}.dump();
  fleet::test::ChildProcess manager(
      FLEET_BINARY_DIR "/services/fleet_manager/fleet_manager",
      {"--config", (dir / "manager.json").string(), "--log-level", "warn"},
      {{"FLEET_DDS_DOMAIN", domain}, {"NOTIFY_SOCKET", socketPath}, {"WATCHDOG_USEC", "3000000"}});
  EXPECT_EQ(receive(fd, 30s), "READY=1");
  // Deadlines, not thresholds: the watchdog is petted once a second while the loop turns.
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(receive(fd, 30s), "WATCHDOG=1") << i;
  }
  manager.kill(SIGTERM);
  std::string m;
  while ((m = receive(fd, 30s)) == "WATCHDOG=1") {
    // one sent before the signal may come first
  }
  EXPECT_EQ(m, "STOPPING=1");
  EXPECT_EQ(manager.wait(30s), 0);
  ::close(fd);
  fs::remove_all(dir);
}
