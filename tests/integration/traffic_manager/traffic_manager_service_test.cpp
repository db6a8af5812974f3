// The traffic_manager process over DDS: a robot that reports itself is placed and released nodes;
// killed and started again, the new incarnation learns the robot from its last (transient-local)
// report and releases from the node it reported, under a new epoch; a report of a node never
// released is refused and the robot is held where it was.

#include <gtest/gtest.h>

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
