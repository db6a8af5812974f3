#include "fleet/fleet/robot_registry.hpp"

#include <gtest/gtest.h>

namespace fleet {
namespace {

constexpr std::int64_t kSec = 1'000'000'000;

TEST(RobotRegistry, LeaseFromRate) {
  EXPECT_EQ(leaseFromRate(10.0, 5.0), kSec / 2);
  EXPECT_EQ(leaseFromRate(1.0, 3.0), 3 * kSec);
  EXPECT_EQ(leaseFromRate(0.0, 3.0), 0);
}

TEST(RobotRegistry, ExpireReportsEachLostRobotOnce) {
  RobotRegistry reg(kSec);
  EXPECT_EQ(reg.observe({"r1", {}, 0.9, 0}), RobotRegistry::Update::New);
  EXPECT_EQ(reg.observe({"r2", {}, 0.8, 0}), RobotRegistry::Update::New);
  ASSERT_TRUE(reg.setTask("r1", "t1"));
  EXPECT_EQ(reg.observe({"r2", {}, 0.8, kSec / 2}), RobotRegistry::Update::Updated);
  EXPECT_TRUE(reg.expire(kSec).empty()) << "a lease of exactly 1 s is not yet exceeded";
  auto lost = reg.expire(kSec + 1);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0].id, "r1");
  EXPECT_EQ(lost[0].taskId, "t1") << "the caller needs the task to requeue it";
  EXPECT_TRUE(reg.expire(kSec + 2).empty()) << "reported once";
  EXPECT_EQ(reg.onlineCount(), 1u);
  auto lost2 = reg.expire(2 * kSec);
  ASSERT_EQ(lost2.size(), 1u);
  EXPECT_EQ(lost2[0].id, "r2");
  EXPECT_EQ(reg.onlineCount(), 0u);
}

TEST(RobotRegistry, StaleSamplesIgnoredAndRecoveryClearsTask) {
  RobotRegistry reg(kSec);
  reg.observe({"r1", {1, 2, 0}, 0.5, 10 * kSec});
  EXPECT_EQ(reg.observe({"r1", {9, 9, 0}, 0.1, 5 * kSec}), RobotRegistry::Update::Stale);
  EXPECT_DOUBLE_EQ(reg.find("r1")->pose.x, 1.0);
  reg.setTask("r1", "t1");
  EXPECT_TRUE(reg.idleRobots().empty());
  EXPECT_TRUE(reg.markLost("r1"));
  EXPECT_FALSE(reg.markLost("r1"));
  EXPECT_FALSE(reg.markLost("unknown"));
  EXPECT_TRUE(reg.expire(100 * kSec).empty()) << "already lost";
  EXPECT_EQ(reg.observe({"r1", {3, 3, 0}, 0.4, 101 * kSec}), RobotRegistry::Update::Recovered);
  const RobotInfo* r = reg.find("r1");
  ASSERT_NE(r, nullptr);
  EXPECT_FALSE(r->lost);
  EXPECT_TRUE(r->idle());
  EXPECT_DOUBLE_EQ(r->battery, 0.4);
  EXPECT_EQ(reg.idleRobots().size(), 1u);
}

TEST(RobotRegistry, ExpectStartsTheLeaseAtRestart) {
  RobotRegistry reg(kSec);
  reg.expect("r7", 50 * kSec);
  reg.setTask("r7", "t9");
  EXPECT_TRUE(reg.expire(50 * kSec + kSec / 2).empty());
  auto lost = reg.expire(52 * kSec);
  ASSERT_EQ(lost.size(), 1u);
  EXPECT_EQ(lost[0].taskId, "t9");
}

}  // namespace
}  // namespace fleet

namespace fleet {
namespace {

TEST(RobotRegistry, JsonView) {
  RobotRegistry reg(kSec);
  reg.observe({"r1", {1.5, -2.0, 0.25}, 0.75, 42});
  reg.setTask("r1", "t9");
  const auto j = toJson(*reg.find("r1"));
  EXPECT_EQ(j.at("id"), "r1");
  EXPECT_DOUBLE_EQ(j.at("x").get<double>(), 1.5);
  EXPECT_DOUBLE_EQ(j.at("theta").get<double>(), 0.25);
  EXPECT_DOUBLE_EQ(j.at("battery").get<double>(), 0.75);
  EXPECT_EQ(j.at("last_seen_ns"), 42);
  EXPECT_EQ(j.at("lost"), false);
  EXPECT_EQ(j.at("task"), "t9");
}

}  // namespace
}  // namespace fleet
