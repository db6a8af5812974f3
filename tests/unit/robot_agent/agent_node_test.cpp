// The robot agent's node without DDS: plain messages in, the hosted robots' messages out. Orders
// reach the robot they name and come back as its task status; samples that fail the edge checks are
// refused with the topic and reason (a refused order for a hosted robot is answered with a failed
// status naming why); releases and frames for robots hosted elsewhere are ignored.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <optional>

#include "agent_node.hpp"
#include "agent_settings.hpp"
#include "agent_world.hpp"

using namespace fleet;

namespace {

constexpr double kDt = 0.1;
constexpr std::int64_t kStepNs = 100'000'000;

/// An open 10 m x 10 m floor with the robots at the given starts.
agent::World floorWith(const std::vector<std::pair<std::string, Pose2>>& robots) {
  agent::World w;
  w.map = std::make_shared<const planning::OccupancyGrid>(40, 40, 0.25, Vec2{0, 0});
  for (const auto& [id, start] : robots) {
    agent::World::Robot r;
    r.id = id;
    r.start = start;
    w.robots.push_back(r);
  }
  w.dt = kDt;
  w.name = "floor";
  return w;
}

std::unique_ptr<agent::AgentNode> nodeOn(const agent::World& w, agent::Settings s = {}) {
  s.threads = 1;
  auto n = agent::AgentNode::create(w, s);
  EXPECT_TRUE(n) << n.error().message;
  return std::move(n).value();
}

/// A robot standing still where it started, as its driver would report it.
msg::SensorFrame standing(const std::string& robot, std::uint32_t seq, double heading = 0.0) {
  msg::SensorFrame f;
  f.robot_id = robot;
  f.seq = seq;
  f.compass_valid = true;
  f.compass = heading;
  f.range_max = 8.0f;
  f.battery = 0.9f;
  return f;
}

msg::TaskAssignment order(const std::string& robot, const std::string& task) {
  msg::TaskAssignment a;
  a.robot_id = robot;
  a.task_id = task;
  a.revision = 4;
  a.goals.push_back({{5.0, 1.0, 0.0}, "P-1", msg::GoalAction::Load, 1.0});
  return a;
}

/// A robot on the open floor at (1, 5), its first node there.
std::unique_ptr<agent::AgentNode> reservedNode() {
  return nodeOn(floorWith({{"r1", {1.0, 5.0, 0.0}}}), agent::Settings{});
}

msg::TrafficRelease release(const std::string& robot, std::vector<msg::RouteNode> base) {
  msg::TrafficRelease r;
  r.robot_id = robot;
  r.epoch = 1;
  r.seq = 1;
  r.base = std::move(base);
  return r;
}

/// Steps the node `cycles` times with a standing frame for each hosted robot; the statuses of `robot`.
std::vector<msg::TaskStatus> run(agent::AgentNode& n, const std::string& robot, int cycles) {
  std::vector<msg::TaskStatus> seen;
  for (int k = 0; k < cycles; ++k) {
    std::vector<msg::SensorFrame> frames;
    for (std::size_t i = 0; i < n.size(); ++i) {
      frames.push_back(standing(n.agent(i).id(), static_cast<std::uint32_t>(n.cycles())));
    }
    n.onFrames(frames);
    const auto& outs = n.step(static_cast<std::int64_t>(n.cycles()) * kStepNs, kDt);
    for (const auto& o : outs) {
      if (o.status && o.status->robot_id == robot) {
        seen.push_back(*o.status);
      }
    }
  }
  return seen;
}

}  // namespace

TEST(AgentNode, AnOrderForAHostedRobotComesBackAsItsTaskStatus) {
  auto node = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}, {"r2", {1.0, 8.0, 0.0}}}));
  node->onAssignments({order("r1", "t1")});
  const auto r1 = run(*node, "r1", 3);
  ASSERT_FALSE(r1.empty());
  EXPECT_EQ(r1.front().task_id, "t1");
  EXPECT_EQ(r1.front().revision, 4u);
  EXPECT_EQ(r1.front().state, msg::TaskState::EnRoute);
  EXPECT_TRUE(node->find("r1")->busy());
  EXPECT_FALSE(node->find("r2")->busy()) << "the order names r1 only";
  EXPECT_TRUE(node->takeRefusals().empty());
  // Outputs in robot order, each command numbered with its cycle.
  ASSERT_EQ(node->outputs().size(), 2u);
  EXPECT_EQ(node->outputs()[0].state.robot_id, "r1");
  EXPECT_EQ(node->outputs()[1].state.robot_id, "r2");
  EXPECT_EQ(node->outputs()[0].command.seq, 2u);
  EXPECT_EQ(node->cycles(), 3u);
}

TEST(AgentNode, AMalformedOrderForAHostedRobotIsRefusedAndReportedFailedNamingWhy) {
  auto node = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}}));
  auto bad = order("r1", "t-bad");
  bad.goals[0].pose.x = std::numeric_limits<double>::quiet_NaN();
  node->onAssignments({bad});
  const auto refusals = node->takeRefusals();
  ASSERT_EQ(refusals.size(), 1u);
  EXPECT_EQ(refusals[0].key.rfind("TaskAssignment:", 0), 0u) << refusals[0].key;
  EXPECT_NE(refusals[0].message.find("goals[].pose"), std::string::npos) << refusals[0].message;
  EXPECT_EQ(node->rejections().total(), 1u);
  const auto r1 = run(*node, "r1", 3);
  ASSERT_EQ(r1.size(), 1u);
  EXPECT_EQ(r1[0].task_id, "t-bad");
  EXPECT_EQ(r1[0].state, msg::TaskState::Failed);
  EXPECT_NE(r1[0].error.find("goals[].pose"), std::string::npos) << r1[0].error;
  EXPECT_FALSE(node->find("r1")->busy());
}

TEST(AgentNode, AMalformedOrderForARobotHostedElsewhereIsRefusedWithoutAReport) {
  auto node = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}}));
  auto bad = order("r7", "t7");
  bad.goals.clear();  // a task with nowhere to go
  node->onAssignments({bad});
  const auto refusals = node->takeRefusals();
  ASSERT_EQ(refusals.size(), 1u);
  EXPECT_EQ(refusals[0].key, "TaskAssignment:structure");
  EXPECT_NE(refusals[0].message.find("has no goals"), std::string::npos) << refusals[0].message;
  EXPECT_TRUE(run(*node, "r1", 3).empty());
  EXPECT_TRUE(run(*node, "r7", 1).empty());
}

TEST(AgentNode, AMalformedSensorFrameIsRefusedAndNotFused) {
  auto node = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}}));
  auto f = standing("r1", 0);
  f.ds_left = std::numeric_limits<double>::infinity();
  node->onFrames({f});
  const auto refusals = node->takeRefusals();
  ASSERT_EQ(refusals.size(), 1u);
  EXPECT_EQ(refusals[0].key.rfind("SensorFrame:", 0), 0u) << refusals[0].key;
  EXPECT_NE(refusals[0].message.find("ds_left"), std::string::npos) << refusals[0].message;
  (void)node->step(0, kDt);
  EXPECT_EQ(node->agent(0).pose().x, 1.0) << "the frame's odometry never reached the estimate";
  EXPECT_EQ(node->agent(0).framesRejected(), 0u) << "refused at the edge, before the localizer";
}

TEST(AgentNode, AReleaseForARobotHostedElsewhereIsIgnored) {
  auto node = reservedNode();
  auto r = release("r9", {{0, 1.0, 5.0}, {1, 1.5, 5.0}});
  node->onReleases({r});
  EXPECT_TRUE(node->takeRefusals().empty()) << "a well-formed release for another robot is no error";
  const auto* r1 = node->find("r1");
  EXPECT_EQ(r1->releases().accepted, 0u);
  EXPECT_EQ(r1->releases().ignored(), 0u) << "never offered to r1";
  EXPECT_EQ(r1->trafficNode(), -1);
  // The same release for r1 is taken.
  r.robot_id = "r1";
  node->onReleases({r});
  EXPECT_EQ(r1->releases().accepted, 1u);
  EXPECT_EQ(node->statsJson()["traffic"]["releases_taken"], 1);
}

TEST(AgentNode, AMalformedReleaseIsRefused) {
  auto node = reservedNode();
  node->onReleases({release("r1", {{-3, 1.0, 5.0}})});
  const auto refusals = node->takeRefusals();
  ASSERT_EQ(refusals.size(), 1u);
  EXPECT_EQ(refusals[0].key, "TrafficRelease:implausible");
  EXPECT_EQ(node->find("r1")->releases().accepted, 0u);
  EXPECT_EQ(node->statsJson()["samples"]["rejected"]["TrafficRelease"]["implausible"], 1);
}

TEST(AgentNode, HostsOnlyTheRobotsAskedForAndRefusesToStartWithNone) {
  const auto world = floorWith({{"r1", {1.0, 1.0, 0.0}}, {"r2", {1.0, 8.0, 0.0}}});
  agent::Settings s;
  s.only = {"r2"};
  auto node = nodeOn(world, s);
  ASSERT_EQ(node->size(), 1u);
  EXPECT_EQ(node->agent(0).id(), "r2");
  EXPECT_EQ(node->find("r1"), nullptr);
  s.only = {"r9"};
  const auto none = agent::AgentNode::create(world, s);
  ASSERT_FALSE(none);
  EXPECT_NE(none.error().message.find("none of the requested robots"), std::string::npos);
}

TEST(AgentNode, StatsCountReleasesAndNameTheLineUpdates) {
  agent::Settings s;
  s.lineUpdates = false;
  auto node = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}}), s);
  (void)run(*node, "r1", 2);
  const auto j = node->statsJson();
  EXPECT_EQ(j["traffic"]["releases_taken"], 0);
  EXPECT_FALSE(j["traffic"].contains("mode")) << "one way to drive";
  EXPECT_EQ(j["localization"]["line_updates"], false);
  EXPECT_EQ(j["conduct"]["rejoins"], 0);
  EXPECT_EQ(j["samples"]["rejected_total"], 0);
}

TEST(AgentSettings, TheFileSetsWhatTheCommandLineLeftAndNamesAnUnknownPlanner) {
  agent::Settings s;
  s.localPlanner = "vo";  // as given on the command line
  Config cfg =
      Config::fromJson({{"local_planner", "follow"}, {"localization", {{"lines", false}}}}, "agent.json");
  agent::readSettings(cfg, s, {.localPlanner = true});
  cfg.finish();
  EXPECT_EQ(s.localPlanner, "vo");
  EXPECT_FALSE(s.lineUpdates);

  agent::Settings t;
  // The keys of the retired reactive conduct are unknown keys now, named like any other.
  Config bad = Config::fromJson(
      {{"local_planner", "teleport"}, {"speed", 3}, {"traffic", "reactive"}, {"global_planner", "astar"}},
      "agent.json");
  agent::readSettings(bad, t);
  try {
    bad.finish();
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("teleport"), std::string::npos) << what;
    EXPECT_NE(what.find("speed"), std::string::npos) << what;
    EXPECT_NE(what.find("traffic"), std::string::npos) << what;
    EXPECT_NE(what.find("global_planner"), std::string::npos) << what;
  }
}

TEST(AgentSettings, TheProgressWatchTakesOneSetOfParametersFromTheFile) {
  agent::Settings s;
  Config cfg = Config::fromJson(
      {{"progress",
        {{"want_speed", 0.05}, {"moved_m", 0.2}, {"stall_s", 4.0}, {"recover_s", 5.0}, {"fail_s", 90.0}}}},
      "agent.json");
  agent::readSettings(cfg, s);
  cfg.finish();
  EXPECT_EQ(s.progress.wantSpeed, 0.05);
  EXPECT_EQ(s.progress.movedM, 0.2);
  EXPECT_EQ(s.progress.stallS, 4.0);
  EXPECT_EQ(s.progress.recoverS, 5.0);
  EXPECT_EQ(s.progress.closerM, 0.25) << "the default";
  EXPECT_EQ(s.progress.failS, 90.0);

  agent::Settings t;
  Config bad = Config::fromJson({{"progress", {{"stall_s", -1.0}, {"stall_seconds", 3}}}}, "agent.json");
  agent::readSettings(bad, t);
  try {
    bad.finish();
    FAIL() << "accepted";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("progress.stall_s"), std::string::npos) << what;
    EXPECT_NE(what.find("progress.stall_seconds"), std::string::npos) << what;
  }
}

TEST(AgentNode, AnOrderFromAManagerOfAnOlderEpochIsIgnoredOnceANewerOneHasSpoken) {
  // A standby fleet manager took over (epoch 3) while the old one (epoch 2) still sends: its
  // order is never acted on or answered, whatever its revision; the new manager's orders are.
  auto node = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}, {"r2", {1.0, 8.0, 0.0}}}));
  auto fresh = order("r1", "t-new");
  fresh.epoch = 3;
  node->onAssignments({fresh});
  auto stale = order("r1", "t-old");
  stale.epoch = 2;
  stale.revision = 99;
  auto staleOther = order("r2", "t-other");
  staleOther.epoch = 2;
  node->onAssignments({stale, staleOther});
  const auto refusals = node->takeRefusals();
  ASSERT_EQ(refusals.size(), 2u);
  EXPECT_EQ(refusals[0].key, "TaskAssignment:stale_epoch");
  EXPECT_NE(refusals[0].message.find("epoch 2 (newest 3)"), std::string::npos) << refusals[0].message;
  const auto r1 = run(*node, "r1", 3);
  ASSERT_FALSE(r1.empty());
  EXPECT_EQ(r1.back().task_id, "t-new");
  EXPECT_FALSE(node->find("r2")->busy()) << "the old manager's order for r2 was dropped too";

  // Without a lease every manager says epoch 0: nothing is dropped.
  auto plain = nodeOn(floorWith({{"r1", {1.0, 1.0, 0.0}}}));
  plain->onAssignments({order("r1", "t1")});
  EXPECT_TRUE(plain->takeRefusals().empty());
  EXPECT_EQ(run(*plain, "r1", 2).back().task_id, "t1");
}
