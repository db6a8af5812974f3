// The pose file a robot_agent process keeps so that, started again, its robots' localization
// starts where they are (pose_store.hpp): written whole and read back exactly, a missing file is
// no pose, a damaged one an error naming the key path, old poses are left out, and a node built
// with saved poses starts each robot's estimate there while its parking place stays its home.

#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "agent_node.hpp"
#include "agent_settings.hpp"
#include "agent_world.hpp"
#include "pose_store.hpp"

using namespace fleet;
using namespace fleet::agent;
namespace fs = std::filesystem;

namespace {

fs::path scratch(const std::string& name) {
  const fs::path dir = fs::path(::testing::TempDir()) / ("pose-store-" + std::to_string(getpid()));
  fs::create_directories(dir);
  return dir / name;
}

void writeText(const fs::path& p, const std::string& text) {
  std::ofstream(p) << text;
}

}  // namespace

TEST(PoseStore, WrittenPosesAreReadBackExactly) {
  const auto path = scratch("poses.json").string();
  SavedPoses poses;
  poses["r1"] = SavedPose{Pose2{12.345678901, -3.25, 2.9}, 1'796'000'000'123, {}};
  poses["r7"] = SavedPose{Pose2{19.0, 9.7, -1.175}, 1'796'000'000'456, WheelTotals{1234.5678, -0.125}};
  // The driver's session: a random 64-bit value, above what a double holds exactly.
  poses["r9"] =
      SavedPose{Pose2{1.0, 2.0, 0.5}, 1'796'000'000'789, WheelTotals{3.5, 3.25, 0xF00D'CAFE'1234'5679ULL}};
  ASSERT_TRUE(writePoseFile(path, poses));
  const auto back = readPoseFile(path);
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->size(), 3U);
  for (const auto& [id, s] : poses) {
    EXPECT_EQ(back->at(id).pose.x, s.pose.x) << id;
    EXPECT_EQ(back->at(id).pose.y, s.pose.y) << id;
    EXPECT_EQ(back->at(id).pose.theta, s.pose.theta) << id;
    EXPECT_EQ(back->at(id).savedUnixMs, s.savedUnixMs) << id;
  }
  EXPECT_FALSE(back->at("r1").wheels) << "a pose without wheel totals (a driver that sends none)";
  ASSERT_TRUE(back->at("r7").wheels);
  EXPECT_EQ(back->at("r7").wheels->left, 1234.5678);
  EXPECT_EQ(back->at("r7").wheels->right, -0.125);
  EXPECT_EQ(back->at("r7").wheels->session, 0U) << "a driver that tells no session";
  ASSERT_TRUE(back->at("r9").wheels);
  EXPECT_EQ(back->at("r9").wheels->session, 0xF00D'CAFE'1234'5679ULL) << "every bit of it";
  EXPECT_FALSE(fs::exists(path + ".tmp")) << "the temporary file was renamed over the old one";
}

TEST(PoseStore, AMissingFileIsNoPose) {
  const auto back = readPoseFile(scratch("never-written.json").string());
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_TRUE(back->empty());
}

TEST(PoseStore, ADamagedFileIsAnErrorNamingWhatIsWrong) {
  const std::vector<std::pair<std::string, std::string>> cases = {
      {"{not json", "not JSON"},
      {R"({"poses": {}})", "robots: required object"},
      {R"({"robots": {"r1": [1, 2, 3]}})", "robots.r1: required object"},
      {R"({"robots": {"r1": {"x": 1, "y": "2", "theta": 0, "saved_unix_ms": 5}}})",
       "robots.r1.y: required finite number"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "saved_unix_ms": 5}}})",
       "robots.r1.theta: required finite number"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "theta": 0}}})", "robots.r1.saved_unix_ms: required integer"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "theta": 0, "saved_unix_ms": 5, "wheel_left_total": 3}}})",
       "robots.r1.wheel_right_total: required with the other wheel's total"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "theta": 0, "saved_unix_ms": 5, "wheel_left_total": 3,
          "wheel_right_total": null}}})",
       "robots.r1.wheel_right_total: required finite number"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "theta": 0, "saved_unix_ms": 5, "driver_session": 7}}})",
       "robots.r1.driver_session: required with the wheel totals"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "theta": 0, "saved_unix_ms": 5, "wheel_left_total": 3,
          "wheel_right_total": 3, "driver_session": -7}}})",
       "robots.r1.driver_session: required non-negative integer"},
      {R"({"robots": {"r1": {"x": 1, "y": 2, "theta": 0, "saved_unix_ms": 5, "wheel_left_total": 3,
          "wheel_right_total": 3, "driver_session": "7"}}})",
       "robots.r1.driver_session: required non-negative integer"},
  };
  for (const auto& [text, why] : cases) {
    const auto path = scratch("damaged.json");
    writeText(path, text);
    const auto back = readPoseFile(path.string());
    ASSERT_FALSE(back) << text;
    EXPECT_NE(back.error().message.find(why), std::string::npos) << back.error().message;
    EXPECT_NE(back.error().message.find(path.string()), std::string::npos) << back.error().message;
  }
}

TEST(PoseStore, OnlyFreshPosesAreUsed) {
  SavedPoses poses;
  poses["old"] = SavedPose{Pose2{1, 1, 0}, 1'000, {}};
  poses["fresh"] = SavedPose{Pose2{2, 2, 0}, 600'000, {}};
  poses["ahead"] = SavedPose{Pose2{3, 3, 0}, 900'000, {}};  // a clock set back since: still fresh
  const auto fresh = freshPoses(poses, 700'000, 600.0);
  EXPECT_EQ(fresh.count("old"), 0U);
  EXPECT_EQ(fresh.count("fresh"), 1U);
  EXPECT_EQ(fresh.count("ahead"), 1U);
}

TEST(PoseStore, TheWriterWritesAtMostOnceAPeriod) {
  PoseWriter off("", 200);
  EXPECT_FALSE(off.due(0));
  PoseWriter w(scratch("period.json").string(), 200);
  EXPECT_TRUE(w.due(1'000));
  ASSERT_TRUE(w.write({}, 1'000));
  EXPECT_FALSE(w.due(1'199));
  EXPECT_TRUE(w.due(1'200));
}

TEST(PoseStore, ANodeStartsAResumedRobotWhereItWasAndKeepsItsHome) {
  World w;
  w.map = std::make_shared<const planning::OccupancyGrid>(80, 80, 0.25, Vec2{0, 0});
  for (const auto& [id, start] : {std::pair{"r1", Pose2{1, 1, 0}}, std::pair{"r2", Pose2{2, 1, 0}}}) {
    World::Robot r;
    r.id = id;
    r.start = start;
    w.robots.push_back(r);
  }
  w.dt = 0.1;
  w.name = "floor";
  Settings s;
  s.threads = 1;
  SavedPoses resume;
  resume["r2"] = SavedPose{Pose2{15.0, 12.0, 1.5}, 0, {}};
  World::Robot third;
  third.id = "r3";
  third.start = Pose2{3, 1, 0};
  w.robots.push_back(third);
  resume["r3"] = SavedPose{Pose2{16.0, 12.0, 1.5}, 0, WheelTotals{40.0, 41.0}};
  auto node = AgentNode::create(w, s, resume);
  ASSERT_TRUE(node) << node.error().message;
  const Agent* r1 = (*node)->find("r1");
  const Agent* r2 = (*node)->find("r2");
  ASSERT_NE(r1, nullptr);
  ASSERT_NE(r2, nullptr);
  EXPECT_EQ(r1->pose().x, 1.0) << "no saved pose: its start";
  EXPECT_EQ(r2->pose().x, 15.0);
  EXPECT_EQ(r2->pose().y, 12.0);
  EXPECT_EQ(r2->pose().theta, 1.5);
  EXPECT_EQ(r2->home().x, 2.0) << "its home is still its start pose";
  EXPECT_EQ(r2->home().y, 1.0);
  EXPECT_FALSE(r2->wheelTotals()) << "kept without totals: none until its first reading";
  EXPECT_GT(r2->covariance()(0, 0), 0.4) << "the roll since is unknown: it starts uncertain";
  const Agent* r3 = (*node)->find("r3");
  ASSERT_NE(r3, nullptr);
  ASSERT_TRUE(r3->wheelTotals()) << "kept with its wheel totals";
  EXPECT_EQ(r3->wheelTotals()->left, 40.0);
  EXPECT_LT(r3->covariance()(0, 0), 0.02) << "the roll since comes from the wheels: it starts certain";
}
