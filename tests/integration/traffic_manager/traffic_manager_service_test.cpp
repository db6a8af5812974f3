// The traffic_manager process over DDS: a robot that reports itself is placed and released nodes;
// killed and started again, the new incarnation learns the robot from its last (transient-local)
// report and releases from the node it reported, under a new epoch; a report of a node never
// released is refused and the robot is held where it was.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <optional>
#include <thread>

#include "fleet/site/site_loader.hpp"
#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

const char* kSite = FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.site.json";

std::optional<msg::TrafficRelease> nextRelease(transport::Reader<msg::TrafficRelease>& in,
                                               std::chrono::seconds within, std::uint32_t notEpoch = 0) {
  const auto deadline = std::chrono::steady_clock::now() + within;
  while (std::chrono::steady_clock::now() < deadline) {
    in.waitForData(100ms);
    for (auto& m : in.take()) {
      if (m.robot_id == "r1" && m.epoch != notEpoch && m.base.size() >= 2)
        return m;
    }
  }
  return std::nullopt;
}

}  // namespace

TEST(TrafficManagerService, PlacesReleasesAndComesBackAfterARestart) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const auto site = site::loadSite(kSite);
  Pose2 park;
  for (const auto& s : site.stations) {
    if (s.name == "PARK-1")
      park = s.pose;
  }
  const std::vector<std::string> args = {"--site", kSite, "--log-level", "warn"};
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  auto service = std::make_unique<test::ChildProcess>(
      FLEET_BINARY_DIR "/services/traffic_manager/traffic_manager", args, env);

  transport::Participant p;
  transport::Writer<msg::TrafficProgress> progress(p);
  transport::Reader<msg::TrafficRelease> releases(p);
  msg::TrafficProgress me;
  me.robot_id = "r1";
  me.pose = park;
  me.has_goal = true;
  me.goal_station = "P-1";
  me.follows = true;
  progress.write(me);

  const auto first = nextRelease(releases, 30s);
  ASSERT_TRUE(first) << "no release within 30 s";
  EXPECT_GT(first->seq, 0U);
  const auto& n = first->base[1];

  // The robot drives to base[1] and says so.
  me.epoch = first->epoch;
  me.node = n.node;
  me.pose = {n.x, n.y, 0};
  progress.write(me);

  // A restart: the new incarnation hears the last report (transient-local) and starts from there.
  service.reset();
  service = std::make_unique<test::ChildProcess>(FLEET_BINARY_DIR "/services/traffic_manager/traffic_manager",
                                                 args, env);
  const auto again = nextRelease(releases, 30s, first->epoch);
  ASSERT_TRUE(again) << "no release from the restarted traffic manager within 30 s";
  EXPECT_NE(again->epoch, first->epoch);
  EXPECT_EQ(again->base.front().node, n.node);
}

// Closures over DDS (what the WMS adapter's PUT/DELETE /v1/traffic/closures send): the traffic
// manager closes the area, publishes the roadmap again with a higher revision and the closed
// nodes, refuses a closure naming a node off the roadmap (and changes nothing), and reopens.
TEST(TrafficManagerService, AppliesClosuresAndPublishesTheRoadmapAgain) {
  const std::string domain = std::to_string(test::uniqueDomain());
  setenv("FLEET_DDS_DOMAIN", domain.c_str(), 1);
  const std::vector<std::string> args = {"--site", kSite, "--log-level", "warn"};
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", domain}};
  test::ChildProcess service(FLEET_BINARY_DIR "/services/traffic_manager/traffic_manager", args, env);
  transport::Participant p;
  transport::Writer<msg::TrafficClosure> closures(p);
  transport::Reader<msg::Roadmap> roadmaps(p);
  // The roadmap with at least `revision`, within 30 s.
  auto roadmapAt = [&](std::uint32_t revision) -> std::optional<msg::Roadmap> {
    const auto deadline = std::chrono::steady_clock::now() + 30s;
    while (std::chrono::steady_clock::now() < deadline) {
      roadmaps.waitForData(100ms);
      for (auto& m : roadmaps.take()) {
        if (m.revision >= revision)
          return m;
      }
    }
    return std::nullopt;
  };
  const auto first = roadmapAt(0);
  ASSERT_TRUE(first) << "no roadmap within 30 s";
  ASSERT_EQ(std::count(first->open.begin(), first->open.end(), false), 0);
  const auto nodes = static_cast<std::int32_t>(first->nodes.size());

  msg::TrafficClosure bad;
  bad.closure_id = "bad";
  bad.nodes = {nodes + 5};
  closures.write(bad);
  msg::TrafficClosure c;
  c.closure_id = "aisle";
  c.area = {{4.0, 0.0}, {6.0, 0.0}, {6.0, 20.0}, {4.0, 20.0}};
  c.reason = "test";
  closures.write(c);
  const auto closed = roadmapAt(1);
  ASSERT_TRUE(closed) << "the roadmap was not published again within 30 s";
  EXPECT_EQ(closed->revision, 1U) << "the bad closure changed nothing";
  EXPECT_EQ(closed->epoch, first->epoch);
  std::size_t shut = 0;
  for (std::size_t v = 0; v < closed->nodes.size(); ++v) {
    if (!closed->open[v]) {
      ++shut;
      EXPECT_GE(closed->nodes[v].x, 4.0 - 1.0) << "node " << v << " is closed far from the area";
      EXPECT_LE(closed->nodes[v].x, 6.0 + 1.0) << "node " << v << " is closed far from the area";
    }
  }
  EXPECT_GT(shut, 0U);

  c.active = false;
  c.area.clear();
  closures.write(c);
  const auto reopened = roadmapAt(2);
  ASSERT_TRUE(reopened);
  EXPECT_EQ(std::count(reopened->open.begin(), reopened->open.end(), false), 0);
  EXPECT_EQ(service.wait(std::chrono::milliseconds(0)), -1) << "the traffic manager exited";
}
