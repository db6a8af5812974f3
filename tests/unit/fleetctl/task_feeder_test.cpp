// The load test's task stage alone: what falls due, and what the poster does with each answer of
// a stand-in WMS adapter on 127.0.0.1.
#include "task_feeder.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <set>
#include <thread>

namespace fleet::ctl {
namespace {

using nlohmann::json;

TaskFeeder::Source generatedAt(double perMin, int maxTasks = 0) {
  TaskFeeder::Source s;
  s.pickups = {"P-1", "P-2"};
  s.dropoffs = {"D-1"};
  s.ratePerMin = perMin;
  s.maxTasks = maxTasks;
  s.endS = 600;
  return s;
}

TEST(TaskFeeder, GeneratedTasksFallDueAtTheirRateUpToTheCap) {
  TaskFeeder f(generatedAt(60), [](const std::string&) {});
  f.due(0.0);
  EXPECT_EQ(f.generated(), 1);  // the first at once
  f.due(9.5);
  EXPECT_EQ(f.generated(), 10);
  f.due(9.9);
  EXPECT_EQ(f.generated(), 10);
  EXPECT_EQ(f.pending(), 10u);
  TaskFeeder capped(generatedAt(60, 4), [](const std::string&) {});
  capped.due(100.0);
  EXPECT_EQ(capped.generated(), 4);
}

TEST(TaskFeeder, ListTasksFallDueAtTheirTimeButNotAtOrAfterTheEnd) {
  TaskFeeder::Source s;
  s.fromList = true;
  s.endS = 30;
  for (double at : {0.0, 5.0, 5.0, 20.0, 30.0, 40.0}) {
    ScenarioTask t;
    t.id = "t" + std::to_string(s.list.size());
    t.atS = at;
    t.pickup = "P-1";
    t.dropoff = "D-1";
    s.list.push_back(t);
  }
  TaskFeeder f(s, [](const std::string&) {});
  f.due(4.9);
  EXPECT_EQ(f.generated(), 1);
  f.due(5.0);
  EXPECT_EQ(f.generated(), 3);
  f.due(1000.0);
  EXPECT_EQ(f.generated(), 4);  // 30 and 40 are at or after the end
}

/// Answers each task of a batch by its id: "refuse" 400, "busy" 503 the first time, the rest 201;
/// the batch with "drop" gets no answer for it at all.
struct StandInAdapter {
  httplib::Server server;
  std::thread thread;
  int port = 0;
  std::atomic<int> posts{0};
  std::set<std::string> seen;
  std::mutex mu;
  StandInAdapter() {
    server.Post("/v1/tasks", [this](const httplib::Request& req, httplib::Response& res) {
      ++posts;
      json results = json::array();
      std::lock_guard<std::mutex> lock(mu);
      for (const auto& t : json::parse(req.body)) {
        const std::string id = t["id"];
        const bool again = !seen.insert(id).second;
        if (id.find("drop") != std::string::npos && !again) {
          continue;
        }
        int status = 201;
        if (id.find("refuse") != std::string::npos) {
          status = 400;
        } else if (id.find("busy") != std::string::npos && !again) {
          status = 503;
        }
        results.push_back({{"id", id}, {"status", status}});
      }
      res.set_content(json{{"results", results}}.dump(), "application/json");
    });
    port = server.bind_to_any_port("127.0.0.1");
    thread = std::thread([this] { server.listen_after_bind(); });
  }
  ~StandInAdapter() {
    server.stop();
    thread.join();
  }
};

TEST(TaskFeeder, AcknowledgedGoToTheLedgerRefusedAreDroppedTheRestAreSentAgain) {
  StandInAdapter adapter;
  ASSERT_GT(adapter.port, 0);
  TaskFeeder::Source s;
  s.fromList = true;
  s.endS = 100;
  for (const char* id : {"ok-1", "refuse-1", "busy-1", "drop-1", "ok-2"}) {
    ScenarioTask t;
    t.id = id;
    t.pickup = "P-1";
    t.dropoff = "D-1";
    s.list.push_back(t);
  }
  std::vector<std::string> said;
  TaskFeeder f(s, [&](const std::string& line) { said.push_back(line); });
  f.due(1.0);
  httplib::Client http("127.0.0.1", adapter.port);
  f.submit(http);
  EXPECT_EQ(f.acknowledged(), 2u);
  EXPECT_EQ(f.refused(), 1);
  EXPECT_EQ(f.pending(), 2u);  // busy-1 and drop-1
  ASSERT_EQ(said.size(), 1u);
  EXPECT_NE(said[0].find("task refuse-1 refused"), std::string::npos);
  f.submit(http);
  EXPECT_EQ(f.acknowledged(), 4u);
  EXPECT_EQ(f.pending(), 0u);
  EXPECT_EQ(f.postErrors(), 0);
  // An adapter that does not answer: the tasks stay pending and the error is counted.
  f.due(1.0);
  TaskFeeder g(s, [](const std::string&) {});
  g.due(1.0);
  httplib::Client closed("127.0.0.1", 1);
  g.submit(closed);
  EXPECT_EQ(g.postErrors(), 1);
  EXPECT_EQ(g.pending(), 5u);
  EXPECT_EQ(g.acknowledged(), 0u);
}

TEST(TaskFeeder, ThePosterStopsWhenTold) {
  StandInAdapter adapter;
  TaskFeeder f(generatedAt(600), [](const std::string&) {});
  httplib::Client http("127.0.0.1", adapter.port);
  std::atomic<bool> stop{false};
  std::thread poster([&] { f.run(http, stop); });
  f.due(10.0);
  for (int i = 0; i < 100 && f.acknowledged() < 101; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  stop = true;
  poster.join();
  EXPECT_EQ(f.acknowledged(), 101u);
  EXPECT_EQ(f.pending(), 0u);
}

}  // namespace
}  // namespace fleet::ctl
