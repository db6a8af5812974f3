// Two WMS adapters as processes on one PostgreSQL database (the managers' store and the adapters'
// event log), as behind a load balancer: a task posted on one and retried on the other is one
// task; either reads it; both number the events alike, so a client that read a stream on one
// resumes on the other with nothing missed or repeated; a restarted adapter lists the tasks it
// had; and webhooks made on one are listed on the other.

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <regex>
#include <string>
#include <thread>
#include <vector>

#include "postgres_server.hpp"
#include "test_process.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;
using nlohmann::json;

namespace {

const std::string kBin = FLEET_BINARY_DIR;
const std::string kScenario = FLEET_SOURCE_DIR "/sim/scenarios/one_robot.json";

httplib::Client client(int port) {
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(2s);
  c.set_read_timeout(10s);
  return c;
}

bool waitHealthy(int port, std::chrono::seconds limit) {
  const auto end = std::chrono::steady_clock::now() + limit;
  while (std::chrono::steady_clock::now() < end) {
    if (auto r = client(port).Get("/v1/health"); r && r->status == 200) {
      return true;
    }
    std::this_thread::sleep_for(100ms);
  }
  return false;
}

/// The ids of the event stream's `id:` lines after `since`, until `n` are read or 10 s pass.
std::vector<std::int64_t> streamIds(int port, std::int64_t since, std::size_t n, bool header = false) {
  auto c = client(port);
  std::string text;
  std::vector<std::int64_t> ids;
  const std::regex line(R"((?:^|\n)id: (\d+)\n)");
  const auto end = std::chrono::steady_clock::now() + 10s;
  httplib::Headers h;
  std::string path = "/v1/events";
  if (header) {
    h.emplace("Last-Event-ID", std::to_string(since));
  } else {
    path += "?since=" + std::to_string(since);
  }
  c.Get(path, h, [&](const char* data, std::size_t len) {
    text.append(data, len);
    ids.clear();
    for (auto it = std::sregex_iterator(text.begin(), text.end(), line); it != std::sregex_iterator(); ++it) {
      ids.push_back(std::stoll((*it)[1]));
    }
    return ids.size() < n && std::chrono::steady_clock::now() < end;
  });
  return ids;
}

struct Adapter {
  int port = fleet::test::freePort();
  std::unique_ptr<fleet::test::ChildProcess> process;
  void start(const std::string& eventsLog, const std::vector<std::pair<std::string, std::string>>& env,
             const fs::path& config) {
    process = std::make_unique<fleet::test::ChildProcess>(
        kBin + "/services/wms_adapter/wms_adapter",
        std::vector<std::string>{"--config", config.string(), "--stations", kScenario, "--port",
                                 std::to_string(port), "--events-log", eventsLog, "--log-level", "warn"},
        env);
  }
};

TEST(AdapterReplicas, OneTaskOneEventNumberingAndAStreamResumedOnEither) {
  fleet::test::PostgresServer server;
  ASSERT_TRUE(server.ok()) << "the PostgreSQL test server did not start: " << server.error();
  const std::string domain = std::to_string(fleet::test::uniqueDomain());
  const auto dir = fs::temp_directory_path() / ("fleet-adapter-replicas-" + domain);
  fs::remove_all(dir);
  fs::create_directories(dir);
  std::ofstream(dir / "manager.json") << json{{"store", server.url()}, {"stations", kScenario}}.dump();
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  fleet::test::ChildProcess manager(
      kBin + "/services/fleet_manager/fleet_manager",
      std::vector<std::string>{"--config", (dir / "manager.json").string(), "--log-level", "warn"}, env);
  // Webhooks may deliver to this machine's loopback (the allow-list).
  std::ofstream(dir / "adapter.json") << json{{"webhooks", {{"allow", {"http://127.0.0.1:9/hooks"}}}}}.dump();
  Adapter a, b;
  a.start(server.url(), env, dir / "adapter.json");
  b.start(server.url(), env, dir / "adapter.json");
  ASSERT_TRUE(waitHealthy(a.port, 30s));
  ASSERT_TRUE(waitHealthy(b.port, 30s));

  // Posted on a, retried on b (its answer lost, say): one task.
  const json task = {{"id", "rep-1"}, {"kind", "transport"}, {"pickup", "P-1"}, {"dropoff", "D-1"}};
  auto first = client(a.port).Post("/v1/tasks", task.dump(), "application/json");
  ASSERT_TRUE(first);
  EXPECT_EQ(first->status, 201) << first->body;
  auto retry = client(b.port).Post("/v1/tasks", task.dump(), "application/json");
  ASSERT_TRUE(retry);
  EXPECT_EQ(retry->status, 200) << retry->body;
  EXPECT_EQ(json::parse(retry->body).value("result", ""), "duplicate");
  auto other = json(task);
  other["dropoff"] = "D-2";
  auto conflict = client(b.port).Post("/v1/tasks", other.dump(), "application/json");
  ASSERT_TRUE(conflict);
  EXPECT_EQ(conflict->status, 409) << "the same id with another body, on the other replica";
  for (const char* id : {"rep-2", "rep-3"}) {
    auto t = task;
    t["id"] = id;
    auto r =
        client(id == std::string("rep-2") ? b.port : a.port).Post("/v1/tasks", t.dump(), "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 201) << r->body;
  }
  // Either reads each.
  for (int port : {a.port, b.port}) {
    for (const char* id : {"rep-1", "rep-2", "rep-3"}) {
      auto r = client(port).Get(std::string("/v1/tasks/") + id);
      ASSERT_TRUE(r);
      EXPECT_EQ(r->status, 200) << id << " on port " << port << ": " << r->body;
    }
  }
  // The same numbering on both; a stream read on a resumes on b after its last id.
  const auto onA = streamIds(a.port, 0, 3);
  ASSERT_EQ(onA.size(), 3u);
  EXPECT_EQ(streamIds(b.port, 0, 3), onA);
  EXPECT_EQ(streamIds(b.port, onA[1], 1, true), std::vector<std::int64_t>{onA[2]});
  // The manager's next transitions (a cancel) carry on on either, in the same order.
  auto cancelled = client(a.port).Delete("/v1/tasks/rep-2");
  ASSERT_TRUE(cancelled);
  EXPECT_LT(cancelled->status, 300) << cancelled->body;
  const auto more = streamIds(a.port, onA[2], 1);
  ASSERT_EQ(more.size(), 1u);
  EXPECT_EQ(streamIds(b.port, onA[2], 1), more);

  // A webhook made on b is listed on a (within its next look at the store).
  const json hook = {{"url", "http://127.0.0.1:9/hooks"}};
  auto made = client(b.port).Post("/v1/webhooks", hook.dump(), "application/json");
  ASSERT_TRUE(made);
  ASSERT_EQ(made->status, 201) << made->body;
  const std::string hookId = json::parse(made->body).value("id", "");
  bool listed = false;
  for (int i = 0; i < 50 && !listed; ++i) {
    auto r = client(a.port).Get("/v1/webhooks/" + hookId);
    listed = r && r->status == 200;
    std::this_thread::sleep_for(100ms);
  }
  EXPECT_TRUE(listed) << "the webhook made on b is not listed on a";
  auto del = client(a.port).Delete("/v1/webhooks/" + hookId);
  ASSERT_TRUE(del);
  EXPECT_EQ(del->status, 200) << del->body;

  // a restarts: it lists the tasks it had, from the log.
  a.process->kill(SIGKILL);
  a.process->wait(10s);
  a.start(server.url(), env, dir / "adapter.json");
  ASSERT_TRUE(waitHealthy(a.port, 30s));
  auto list = client(a.port).Get("/v1/tasks");
  ASSERT_TRUE(list);
  ASSERT_EQ(list->status, 200);
  std::set<std::string> ids;
  for (const auto& t : json::parse(list->body).value("tasks", json::array())) {
    ids.insert(t.value("id", ""));
  }
  EXPECT_EQ(ids, (std::set<std::string>{"rep-1", "rep-2", "rep-3"}));
  EXPECT_EQ(streamIds(a.port, 0, 4), streamIds(b.port, 0, 4));
  fs::remove_all(dir);
}

TEST(AdapterReplicas, AnUnreachableEventDatabaseIsRetriedAndNamedUntilItComes) {
  const auto dir = fs::temp_directory_path() / ("fleet-adapter-nodb-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  const std::string url = "postgresql://fleet:secret@/postgres?host=" + (dir / "sock").string();
  const int port = fleet::test::freePort();
  const std::string cmd = "exec '" + kBin + "/services/wms_adapter/wms_adapter' --stations '" + kScenario +
                          "' --port " + std::to_string(port) + " --events-log '" + url + "' > '" +
                          (dir / "adapter.log").string() + "' 2>&1";
  fleet::test::ChildProcess adapter("/bin/sh", {"-c", cmd},
                                    {{"FLEET_DDS_DOMAIN", std::to_string(fleet::test::uniqueDomain())}});
  std::this_thread::sleep_for(4s);
  EXPECT_EQ(adapter.wait(0ms), -1) << "the adapter gave up instead of retrying";
  auto r = client(port).Get("/v1/health");
  EXPECT_FALSE(r) << "serving without its event log";
  std::ifstream in(dir / "adapter.log");
  std::string log;
  std::getline(in, log, '\0');
  EXPECT_NE(log.find("events.log postgresql://fleet:***@"), std::string::npos) << log;
  EXPECT_NE(log.find("trying again in 2 s"), std::string::npos) << log;
  EXPECT_EQ(log.find("secret"), std::string::npos) << "the password in the log: " << log;
  adapter.kill(SIGTERM);
  EXPECT_EQ(adapter.wait(10s), 0) << "stopped while waiting: exit 0";
  fs::remove_all(dir);
}

}  // namespace
