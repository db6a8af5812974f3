// The people a robot sees, as its agent publishes them (services/robot_agent/people_report.hpp):
// a few times a second of the agent's clock and not every cycle, in the map frame with the velocity
// when the person was tracked, the nearest kept when there are more than the topic holds, nothing
// while the robot does not know; and through the node, for every hosted robot at its own phase.

#include "people_report.hpp"

#include <gtest/gtest.h>

#include "agent_node.hpp"
#include "agent_world.hpp"

using namespace fleet;
using namespace fleet::agent;

namespace {

constexpr std::int64_t kMs = 1'000'000;

Perception seeing(std::vector<Person> people) {
  Perception p;
  p.valid = true;
  p.pose = {1.0, 1.0, 0.0};
  p.people = std::move(people);
  return p;
}

}  // namespace

TEST(PeopleReport, EveryPeriodOfTheAgentsClockNotEveryCycle) {
  PeopleReport report(250 * kMs);
  const auto seen = seeing({{{2.0, 3.0}, {0.5, 0.0}, 0.25, true}});
  int sent = 0;
  for (std::int64_t t = 0; t < 2000 * kMs; t += 50 * kMs) {  // 20 Hz cycles for 2 s
    if (auto r = report.due("r1", t, seen, false)) {
      ++sent;
      EXPECT_EQ(r->robot_id, "r1");
      EXPECT_EQ(r->stamp_ns, t);
    }
  }
  EXPECT_EQ(sent, 8);
}

TEST(PeopleReport, CarriesMapFramePositionsAndOnlyMeasuredVelocities) {
  PeopleReport report;
  const auto r = report.due(
      "r1", 0, seeing({{{2.0, 3.0}, {0.5, -0.25}, 0.3, true}, {{4.0, 1.0}, {}, 0.25, false}}), false);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->people.size(), 2U);
  EXPECT_FLOAT_EQ(r->people[0].x, 2.0F);
  EXPECT_FLOAT_EQ(r->people[0].y, 3.0F);
  EXPECT_FLOAT_EQ(r->people[0].vx, 0.5F);
  EXPECT_FLOAT_EQ(r->people[0].vy, -0.25F);
  EXPECT_FLOAT_EQ(r->people[0].r, 0.3F);
  EXPECT_TRUE(r->people[0].velocity_known);
  EXPECT_FALSE(r->people[1].velocity_known);
}

TEST(PeopleReport, NobodySeenIsSaidButNothingWhileTheRobotDoesNotKnow) {
  PeopleReport report(100 * kMs);
  const auto empty = report.due("r1", 0, seeing({}), false);
  ASSERT_TRUE(empty);
  EXPECT_TRUE(empty->people.empty());
  EXPECT_FALSE(report.due("r1", 100 * kMs, seeing({}), true)) << "sensor stream lost";
  EXPECT_FALSE(report.due("r1", 200 * kMs, Perception{}, false)) << "no reading yet";
  EXPECT_TRUE(report.due("r1", 300 * kMs, seeing({}), false));
}

TEST(PeopleReport, TheNearestAreKeptWhenMoreAreSeenThanTheTopicHolds) {
  std::vector<Person> crowd;
  for (std::size_t i = 0; i < msg::kMaxPeopleSeen + 20; ++i) {
    crowd.push_back({{1.0 + 0.5 * static_cast<double>(msg::kMaxPeopleSeen + 20 - i), 1.0}, {}, 0.25, false});
  }
  PeopleReport report;
  const auto r = report.due("r1", 0, seeing(crowd), false);
  ASSERT_TRUE(r);
  ASSERT_EQ(r->people.size(), msg::kMaxPeopleSeen);
  for (const auto& p : r->people) {
    EXPECT_LE(p.x, 1.0F + 0.5F * static_cast<float>(msg::kMaxPeopleSeen) + 1e-3F);
  }
}

TEST(PeopleReport, TheNodeReportsEachRobotsPeopleAtItsOwnPhase) {
  World w;
  w.map = std::make_shared<const planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (const auto& [id, y] : {std::pair{"r1", 2.0}, std::pair{"r2", 7.0}}) {
    World::Robot r;
    r.id = id;
    r.start = {1.0, y, 0.0};
    w.robots.push_back(r);
  }
  w.dt = 0.05;
  w.name = "floor";
  Settings s;
  s.threads = 1;
  auto node = std::move(AgentNode::create(w, s)).value();
  std::map<std::string, std::vector<msg::PeopleSeen>> sent;
  for (std::int64_t k = 0; k < 40; ++k) {  // 2 s at 20 Hz
    std::vector<msg::SensorFrame> frames;
    for (const auto& [id, y] : {std::pair{"r1", 2.0}, std::pair{"r2", 7.0}}) {
      msg::SensorFrame f;
      f.robot_id = id;
      f.stamp_ns = k * 50 * kMs;
      f.seq = static_cast<std::uint32_t>(k);
      f.compass_valid = true;
      f.range_max = 8.0F;
      f.battery = 0.9F;
      f.detections = {{msg::SourceKind::Human, 2.0F, 0.5F, 0.25F},
                      {msg::SourceKind::Robot, 0.0F, 4.0F, 0.3F}};
      frames.push_back(f);
    }
    node->onFrames(frames);
    for (const auto& o : node->step(k * 50 * kMs, 0.05)) {
      if (o.people) {
        sent[o.people->robot_id].push_back(*o.people);
      }
    }
  }
  ASSERT_EQ(sent["r1"].size(), 8U);
  ASSERT_EQ(sent["r2"].size(), 8U);
  EXPECT_NE(sent["r1"][0].stamp_ns, sent["r2"][0].stamp_ns) << "not in one burst";
  const auto& last = sent["r2"].back();
  ASSERT_EQ(last.people.size(), 1U) << "robots seen are not people";
  EXPECT_NEAR(last.people[0].x, 3.0, 0.05);  // 2 m ahead of (1, 7), 0.5 m to its left
  EXPECT_NEAR(last.people[0].y, 7.5, 0.05);
}
