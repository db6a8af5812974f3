#include <gtest/gtest.h>

#include <cmath>

#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/control/velocity_limits.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/sim/lockstep.hpp"
#include "fleet/sim/replay.hpp"
#include "fleet/sim/world.hpp"
#include "sim_fixtures.hpp"

using namespace fleet;
using namespace fleet::sim;

namespace {

Scenario oneRobot(double x = 2.0, double y = 2.5, double theta = 0.0) {
  auto j = test::room(40, 10);  // 20 m x 5 m
  j["robots"] = {{{"id", "r"}, {"start", {x, y, theta}}}};
  return test::parse(j);
}

}  // namespace

TEST(World, StraightDriveFollowsAccelerationLimitExactly) {
  World w(oneRobot());
  // a = 1 m/s², dt = 0.1: speeds 0.1, 0.2, ..., 0.5 then 0.5; distance = dt * sum(v).
  double expected = 0.0;
  double v = 0.0;
  for (int k = 0; k < 20; ++k) {
    w.command("r", 0.5, 0.0);
    w.advance();
    v = std::min(0.5, v + 0.1);
    expected += v * 0.1;
  }
  EXPECT_NEAR(w.robots()[0].pose.x, 2.0 + expected, 1e-9);
  EXPECT_NEAR(w.robots()[0].pose.y, 2.5, 1e-12);
  EXPECT_NEAR(w.robots()[0].distance, expected, 1e-9);
  EXPECT_NEAR(w.robots()[0].twist.v, 0.5, 1e-12);
}

TEST(World, TurningMatchesExactArcAgainstControlLibrary) {
  World w(oneRobot(5.0, 2.5, 0.0));
  Pose2 ref{5.0, 2.5, 0.0};
  control::Twist prev;
  const control::VelocityLimits lim{1.0, -0.3, 1.5, 1.0, 3.0};
  for (int k = 0; k < 15; ++k) {
    w.command("r", 0.4, 0.8);
    w.advance();
    prev = control::applyLimits(lim, {0.4, 0.8}, prev, 0.1).twist;
    ref = control::DiffDriveKinematics::integrateExact(ref, prev, 0.1);
  }
  EXPECT_NEAR(w.robots()[0].pose.x, ref.x, 1e-9);
  EXPECT_NEAR(w.robots()[0].pose.y, ref.y, 1e-9);
  EXPECT_NEAR(w.robots()[0].pose.theta, ref.theta, 1e-9);
}

TEST(World, CommandTimeoutStopsTheRobot) {
  World w(oneRobot());
  for (int k = 0; k < 10; ++k) {
    w.command("r", 0.5, 0.0);
    w.advance();
  }
  for (int k = 0; k < 20; ++k) {  // 0.5 s timeout, then 0.5 s to brake at 1 m/s²
    w.advance();
  }
  EXPECT_EQ(w.robots()[0].twist.v, 0.0);
  EXPECT_EQ(w.counters().timeouts, 1U);
  const double x = w.robots()[0].pose.x;
  w.advance();
  EXPECT_EQ(w.robots()[0].pose.x, x);
}

TEST(World, NanCommandsIgnoredAndOverLimitClampedAndCounted) {
  World w(oneRobot());
  EXPECT_EQ(w.command("r", std::nan(""), 0.0), CommandOutcome::Ignored);
  EXPECT_EQ(w.command("r", 0.1, INFINITY), CommandOutcome::Ignored);
  EXPECT_EQ(w.command("ghost", 0.1, 0.0), CommandOutcome::Ignored);
  EXPECT_EQ(w.counters().nanCommands, 2U);
  EXPECT_EQ(w.counters().unknownRobot, 1U);
  double vmax = 0.0;
  for (int k = 0; k < 30; ++k) {
    EXPECT_EQ(w.command("r", 50.0, 0.0), CommandOutcome::Clamped);
    w.advance();
    vmax = std::max(vmax, w.robots()[0].twist.v);
  }
  EXPECT_EQ(w.counters().clampedCommands, 30U);
  EXPECT_NEAR(vmax, 1.0, 1e-12);
  EXPECT_TRUE(w.robots()[0].pose.isFinite());
}

TEST(World, ShelfStopsRobotAndCountsOneContact) {
  World w(oneRobot(17.0, 2.5, 0.0));  // wall face at x = 19.5
  for (int k = 0; k < 80; ++k) {
    w.command("r", 1.0, 0.0);
    w.advance();
    EXPECT_EQ(discGridPenetration(w.scenario().map, w.robots()[0].pose.position(), 0.3), 0.0);
  }
  EXPECT_LE(w.robots()[0].pose.x, 19.5 - 0.3 + 1e-12);
  EXPECT_GT(w.robots()[0].pose.x, 19.5 - 0.3 - 0.11);
  EXPECT_EQ(w.metrics().robotShelfContacts, 1U);  // one event while it keeps pushing
  EXPECT_GT(w.robots()[0].bumps, 1);
  EXPECT_LE(w.metrics().minSepRobotShelf, 0.0);
}

TEST(World, HeadOnRobotsGiveNearMissThenOneContactWithExactDepth) {
  auto j = test::room(40, 10);
  j["robots"] = {{{"id", "a"}, {"start", {5.0, 2.5, 0.0}}}, {{"id", "b"}, {"start", {9.0, 2.5, kPi}}}};
  World w(test::parse(j));
  for (int k = 0; k < 40; ++k) {
    w.command("a", 0.5, 0.0);
    w.command("b", 0.5, 0.0);
    w.advance();
    const double gap = distance(w.robots()[0].pose, w.robots()[1].pose) - 0.6;
    if (gap < 0.0) {
      ASSERT_FALSE(w.contacts().empty());
      EXPECT_NEAR(w.contacts()[0].depth, -gap, 1e-12);
      EXPECT_EQ(w.bodyId(w.contacts()[0].a), "a");
      EXPECT_EQ(w.bodyId(w.contacts()[0].b), "b");
    }
  }
  EXPECT_EQ(w.metrics().nearMissRobotRobot, 1U);
  EXPECT_EQ(w.metrics().robotRobotContacts, 1U);
  EXPECT_LT(w.metrics().minSepRobotRobot, 0.0);
}

TEST(World, SameSeedSameCommandsGiveIdenticalReplayDifferentSeedDoesNot) {
  auto run = [](std::uint64_t seed) {
    Scenario s = loadScenario(std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.json");
    s.seed = seed;
    World w(std::move(s));
    std::string out = replayHeader(w).dump();
    for (int k = 0; k < 100; ++k) {
      for (std::size_t i = 0; i < w.robots().size(); ++i) {
        w.command(i, 0.3 + 0.02 * static_cast<double>(i), 0.2 * std::sin(0.1 * k + static_cast<double>(i)));
      }
      for (const auto& f : w.sensorFrames()) {
        out += std::to_string(f.dsLeft) +
               std::to_string(f.ranges.empty() ? 0.0 : static_cast<double>(f.ranges[3]));
      }
      w.advance();
      out += replayStep(w).dump();
    }
    return out;
  };
  const std::string a = run(7);
  EXPECT_EQ(a, run(7));
  EXPECT_NE(a, run(8));
}

TEST(World, BatteryDrainsWhenDrivingAndChargesOnStation) {
  auto j = test::room(40, 10);
  j["stations"] = {{{"name", "C"}, {"kind", "charging"}, {"pose", {2.0, 2.5, 0.0}}}};
  j["robots"] = {
      {{"id", "r"}, {"start", {2.0, 2.5, 0.0}}, {"battery", {{"initial", 0.5}, {"drain_per_m", 0.01}}}},
      {{"id", "m"}, {"start", {5.0, 2.5, 0.0}}, {"battery", {{"initial", 0.5}, {"drain_per_m", 0.01}}}}};
  World w(test::parse(j));
  for (int k = 0; k < 50; ++k) {
    w.command("m", 0.5, 0.0);
    w.advance();
  }
  EXPECT_TRUE(w.robots()[0].charging);
  EXPECT_NEAR(w.robots()[0].battery, 0.5 + 5.0 * 2e-3, 1e-9);
  EXPECT_FALSE(w.robots()[1].charging);
  EXPECT_NEAR(w.robots()[1].battery, 0.5 - 5.0 * 1e-5 - 0.01 * w.robots()[1].distance, 1e-9);
}

// A VDA 5050 vehicle charges only once it switched its charging on (startCharging), and stops
// when it switches it off, however long it stands on the charger.
TEST(World, ARobotWithAChargeSwitchChargesOnlyWhileItIsOn) {
  auto j = test::room(40, 10);
  j["stations"] = {{{"name", "C"}, {"kind", "charging"}, {"pose", {2.0, 2.5, 0.0}}}};
  j["robots"] = {{{"id", "v"}, {"start", {2.0, 2.5, 0.0}}, {"battery", {{"initial", 0.5}}}},
                 {{"id", "far"}, {"start", {6.0, 2.5, 0.0}}, {"battery", {{"initial", 0.5}}}}};
  World w(test::parse(j));
  EXPECT_TRUE(w.atCharger(0));
  EXPECT_FALSE(w.atCharger(1));
  w.setChargeSwitch(0, false);
  w.setChargeSwitch(1, true);  // on, but not on a charger
  for (int k = 0; k < 10; ++k) {
    w.advance();
  }
  EXPECT_FALSE(w.robots()[0].charging);
  EXPECT_LT(w.robots()[0].battery, 0.5);
  EXPECT_FALSE(w.robots()[1].charging);
  const double before = w.robots()[0].battery;
  w.setChargeSwitch(0, true);
  for (int k = 0; k < 10; ++k) {
    w.advance();
  }
  EXPECT_TRUE(w.robots()[0].charging);
  EXPECT_NEAR(w.robots()[0].battery, before + 1.0 * 2e-3, 1e-9);
}

TEST(World, EmptyBatteryImmobilises) {
  auto j = test::room(40, 10);
  j["robots"] = {{{"id", "r"}, {"start", {2.0, 2.5, 0.0}}, {"battery", {{"initial", 0.0}}}}};
  World w(test::parse(j));
  for (int k = 0; k < 10; ++k) {
    w.command("r", 0.5, 0.0);
    w.advance();
  }
  EXPECT_EQ(w.robots()[0].pose.x, 2.0);
}

TEST(Lockstep, BarrierWaitsForEveryRegisteredParticipant) {
  LockstepBarrier b;
  EXPECT_TRUE(b.complete(0));  // nobody registered: nothing to wait for
  EXPECT_FALSE(b.onStepDone("ghost", 0));
  b.onStepDone("a", LockstepBarrier::kRegister);
  b.onStepDone("b", LockstepBarrier::kRegister);
  EXPECT_FALSE(b.complete(0));
  b.onStepDone("a", 0);
  EXPECT_EQ(b.missing(0), std::vector<std::string>{"b"});
  b.onStepDone("b", 1);  // a later ack covers earlier steps
  EXPECT_TRUE(b.complete(0));
  EXPECT_FALSE(b.complete(1));
  b.onStepDone("a", LockstepBarrier::kLeave);
  EXPECT_TRUE(b.complete(1));
  b.onStepDone("b", 0);  // stale ack does not go backwards
  EXPECT_TRUE(b.complete(1));
  EXPECT_EQ(b.registered(), 1U);
  // Joining while step 5 is out: not waited for at step 5 (it may have missed Clock(5)), but at 6.
  b.onStepDone("b", 5);
  b.begin(5);
  b.onStepDone("late", LockstepBarrier::kRegister);
  EXPECT_TRUE(b.complete(5));
  EXPECT_FALSE(b.complete(6));
  EXPECT_EQ(b.missing(6), (std::vector<std::string>{"b", "late"}));
}

TEST(Lockstep, AStepWaitsForTheCommandsItsAcknowledgementNames) {
  LockstepBarrier b;
  b.onStepDone("agents", LockstepBarrier::kRegister);
  b.onStepDone("risk", LockstepBarrier::kRegister);
  b.onStepDone("risk", 0);
  // The acknowledgement overtook the commands written before it (another writer's).
  b.onStepDone("agents", 0, {{"r1", 7}, {"r2", 7}});
  EXPECT_FALSE(b.complete(0));
  EXPECT_EQ(b.missing(0), (std::vector<std::string>{"agents (command 7 of r1)", "agents (command 7 of r2)"}));
  b.onCommand("r1", 7);
  EXPECT_FALSE(b.complete(0));
  b.onCommand("r2", 6);  // the previous step's, late: not this one
  EXPECT_FALSE(b.complete(0));
  b.onCommand("r2", 7);
  EXPECT_TRUE(b.complete(0));
  // The next step's marks replace these; an agent restarted with seq 0 is waited for too.
  b.onStepDone("agents", 1, {{"r1", 0}});
  b.onStepDone("risk", 1);
  EXPECT_FALSE(b.complete(1));
  b.onCommand("r1", 0);
  EXPECT_TRUE(b.complete(1));
  // A participant that leaves takes its marks along.
  b.onStepDone("agents", 2, {{"r1", 1}});
  b.onStepDone("risk", 2);
  EXPECT_FALSE(b.complete(2));
  b.onStepDone("agents", LockstepBarrier::kLeave);
  EXPECT_TRUE(b.complete(2));
}

TEST(World, MinimumSeparationIsTheExactSurfaceGap) {
  auto j = test::room(40, 10);
  j["robots"] = {{{"id", "a"}, {"start", {5.0, 1.2, 0.0}}}, {{"id", "b"}, {"start", {6.0, 1.2, 0.0}}}};
  World w(test::parse(j));
  w.advance();
  EXPECT_NEAR(w.metrics().minSepRobotRobot, 1.0 - 0.6, 1e-12);
  EXPECT_EQ(w.metrics().nearMissRobotRobot, 0U);                      // 0.4 m is above the 0.3 m threshold
  EXPECT_NEAR(w.metrics().minSepRobotShelf, 1.2 - 0.5 - 0.3, 1e-12);  // floor wall face at y = 0.5
}
