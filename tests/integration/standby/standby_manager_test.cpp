// Standby fleet managers as processes on one PostgreSQL store: exactly one is active (/readyz 200,
// fleet_manager_active 1), kill -9 of it makes the other active within 5 s with the next epoch,
// and every acknowledged task is there, once.

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fleet_stack.hpp"
#include "postgres_server.hpp"
#include "test_process.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

const std::string kBin = FLEET_BINARY_DIR;
const std::string kScenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";

std::optional<int> status(int port, const std::string& path, std::string* body = nullptr) {
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(1s);
  c.set_read_timeout(2s);
  auto r = c.Get(path);
  if (!r) {
    return std::nullopt;
  }
  if (body != nullptr) {
    *body = r->body;
  }
  return r->status;
}

bool has(int port, const std::string& line) {
  std::string body;
  return status(port, "/metrics", &body) == 200 && body.find(line + "\n") != std::string::npos;
}

TEST(StandbyManager, OneIsActiveAndAStandbyTakesOverWithinFiveSecondsOfAKill) {
  fleet::test::PostgresServer server;
  ASSERT_TRUE(server.ok()) << "the PostgreSQL test server did not start: " << server.error();
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto dir = fs::temp_directory_path() / ("fleet-standby-" + domain);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "manager.json")
      << nlohmann::json{{"store", server.url()}, {"stations", kScenario}}.dump();
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  const int ops[2] = {fleet::test::freePort(), fleet::test::freePort()};
  std::unique_ptr<fleet::test::ChildProcess> managers[2];
  for (int i = 0; i < 2; ++i) {
    managers[i] = std::make_unique<fleet::test::ChildProcess>(
        kBin + "/services/fleet_manager/fleet_manager",
        std::vector<std::string>{"--config", (dir / "manager.json").string(), "--metrics-port",
                                 std::to_string(ops[i]), "--log-level", "warn"},
        env);
    if (i == 0) {
      // The first is active before the second starts.
      const auto end = std::chrono::steady_clock::now() + 30s;
      while (status(ops[0], "/readyz") != 200 && std::chrono::steady_clock::now() < end) {
        std::this_thread::sleep_for(100ms);
      }
      ASSERT_EQ(status(ops[0], "/readyz"), 200);
    }
  }
  const auto end = std::chrono::steady_clock::now() + 20s;
  while (!has(ops[1], "fleet_manager_active 0") && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_TRUE(has(ops[1], "fleet_manager_active 0"));
  EXPECT_EQ(status(ops[1], "/readyz"), 503) << "the standby is not ready";
  EXPECT_TRUE(has(ops[0], "fleet_manager_active 1"));
  EXPECT_TRUE(has(ops[0], "fleet_manager_lease_epoch 1"));

  fleet::test::TaskClient client;
  for (const char* id : {"s-1", "s-2", "s-3"}) {
    auto ack = client.submit(fleet::test::transportTask(id, "P-1", "D-1"), 30s);
    ASSERT_TRUE(ack) << id;
    ASSERT_EQ(ack->result, fleet::msg::AckResult::Stored) << id << ": " << ack->detail;
  }

  managers[0]->kill(SIGKILL);
  const auto killed = std::chrono::steady_clock::now();
  while (status(ops[1], "/readyz") != 200 && std::chrono::steady_clock::now() - killed < 10s) {
    std::this_thread::sleep_for(50ms);
  }
  const double took = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  EXPECT_LT(took, 5.0) << "takeover after " << took << " s";
  std::cout << "takeover after " << took << " s\n";
  EXPECT_TRUE(has(ops[1], "fleet_manager_lease_epoch 2"));
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (!has(ops[1], "fleet_manager_tasks{state=\"queued\"} 3") &&
         std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(200ms);
  }
  EXPECT_TRUE(has(ops[1], "fleet_manager_tasks{state=\"queued\"} 3")) << "every acknowledged task, once";
  auto again = client.submit(fleet::test::transportTask("s-1", "P-1", "D-1"), 30s);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->result, fleet::msg::AckResult::Duplicate) << "the retry finds the stored task";
  auto next = client.submit(fleet::test::transportTask("s-4", "P-1", "D-1"), 30s);
  ASSERT_TRUE(next);
  EXPECT_EQ(next->result, fleet::msg::AckResult::Stored);
  managers[1]->kill(SIGTERM);
  EXPECT_EQ(managers[1]->wait(10s), 0);
  fs::remove_all(dir);
}

// A hung active manager (SIGSTOP) stops renewing: the standby takes over; once it runs again the
// old one finds its lease lapsed, publishes nothing, and stands by.
TEST(StandbyManager, AHungActiveManagerIsReplacedAndStandsByWhenItResumes) {
  fleet::test::PostgresServer server;
  ASSERT_TRUE(server.ok()) << "the PostgreSQL test server did not start: " << server.error();
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  const auto dir = fs::temp_directory_path() / ("fleet-standby-hung-" + domain);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "manager.json")
      << nlohmann::json{{"store", server.url()}, {"stations", kScenario}}.dump();
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  const int ops[2] = {fleet::test::freePort(), fleet::test::freePort()};
  std::unique_ptr<fleet::test::ChildProcess> managers[2];
  auto waitUntil = [](auto&& cond, std::chrono::seconds within) {
    const auto end = std::chrono::steady_clock::now() + within;
    while (!cond() && std::chrono::steady_clock::now() < end) {
      std::this_thread::sleep_for(50ms);
    }
    return cond();
  };
  for (int i = 0; i < 2; ++i) {
    managers[i] = std::make_unique<fleet::test::ChildProcess>(
        kBin + "/services/fleet_manager/fleet_manager",
        std::vector<std::string>{"--config", (dir / "manager.json").string(), "--metrics-port",
                                 std::to_string(ops[i]), "--log-level", "warn"},
        env);
    if (i == 0) {
      ASSERT_TRUE(waitUntil([&] { return status(ops[0], "/readyz") == 200; }, 30s));
    }
  }
  ASSERT_TRUE(waitUntil([&] { return has(ops[1], "fleet_manager_active 0"); }, 20s));
  managers[0]->kill(SIGSTOP);
  const auto stopped = std::chrono::steady_clock::now();
  EXPECT_TRUE(waitUntil([&] { return status(ops[1], "/readyz") == 200; }, 10s));
  EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - stopped).count(), 5.0);
  EXPECT_TRUE(has(ops[1], "fleet_manager_lease_epoch 2"));
  managers[0]->kill(SIGCONT);
  EXPECT_TRUE(waitUntil([&] { return has(ops[0], "fleet_manager_active 0"); }, 10s))
      << "the resumed one stands by";
  EXPECT_EQ(status(ops[0], "/readyz"), 503);
  EXPECT_TRUE(has(ops[0], "fleet_manager_lease_epoch 0"));
  EXPECT_TRUE(has(ops[1], "fleet_manager_active 1")) << "exactly one active";
  for (auto& m : managers) {
    m->kill(SIGTERM);
    EXPECT_EQ(m->wait(10s), 0);
  }
  fs::remove_all(dir);
}

}  // namespace
