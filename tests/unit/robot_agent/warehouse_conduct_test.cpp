// Several agents in a kinematic world on the small warehouse's map (no DDS, no simulator: every run
// is deterministic and takes well under a second): neighbours in the parking band sent off across
// each other's way, coming home past each other, queues behind a robot that waits on a person or
// for a station. Each case comes from a failure seen in a 20-robot load test.
//
// PARKING_TRACE=1 prints every robot's pose, command and mode once a simulated second.

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "agent.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"

using namespace fleet;

namespace {

struct Body {
  Pose2 truth;
  double v = 0.0;
  double w = 0.0;
  double left = 0.0;
  double right = 0.0;
  std::uint32_t seq = 0;
};

// The small warehouse (sim/scenarios/small_warehouse.json): 30 m x 20 m at 0.5 m, parking places
// every metre at y = 0.9 under the first shelf row.
std::shared_ptr<const planning::OccupancyGrid> warehouse() {
  planning::WarehouseParams w;
  w.width = 60;
  w.height = 40;
  w.margin = 5;
  w.shelfWidth = 8;
  w.shelfHeight = 2;
  w.aisleX = 3;
  w.aisleY = 3;
  w.resolution = 0.5;
  return std::make_shared<const planning::OccupancyGrid>(planning::makeWarehouseGrid(w));
}

struct Run {
  std::vector<std::string> done;
  std::vector<std::string> failed;
  double minSeparation = 1e9;  // between robots' centres
  double minToPeople = 1e9;    // robot centre to person centre
  std::vector<Pose2> end;
};

struct Order {
  std::string robot;
  msg::Goal goal;
  double at = 0.0;  // [s]
};

struct Robot {
  std::string id;
  Pose2 home;  // its parking place, where it starts and drives to when idle
};

/// `people` stand still where they are (a person who does not step aside) for the whole run.
Run drive(const std::vector<Robot>& robots, const std::vector<Order>& orders, int steps,
          const std::vector<Vec2>& people = {}) {
  const bool trace = std::getenv("PARKING_TRACE") != nullptr;
  auto raw = warehouse();
  auto grid = agent::inflate(*raw, 0.5);
  std::vector<std::unique_ptr<agent::Agent>> agents;
  std::vector<Body> bodies;
  for (const auto& r : robots) {
    agent::AgentParams p;
    p.id = r.id;
    p.start = r.home;
    p.wheelBase = 0.4;
    agents.push_back(std::make_unique<agent::Agent>(p, grid, raw));
    bodies.push_back({p.start});
  }
  Run run;
  std::vector<msg::RobotState> states(agents.size());
  for (int k = 0; k < steps; ++k) {
    const double dt = 0.1;
    for (std::size_t i = 0; i < orders.size(); ++i) {
      if (static_cast<int>(std::lround(orders[i].at / dt)) != k) {
        continue;
      }
      msg::TaskAssignment a;
      a.robot_id = orders[i].robot;
      a.task_id = "t" + std::to_string(i);
      a.revision = 1;
      a.goals.push_back(orders[i].goal);
      for (auto& ag : agents) {
        if (ag->id() == a.robot_id) {
          ag->onAssignment(a);
        }
      }
    }
    for (auto& b : bodies) {
      const double l = (b.v - b.w * 0.2) * dt;
      const double r = (b.v + b.w * 0.2) * dt;
      b.truth = control::DiffDriveKinematics::integrateExact(b.truth, {b.v, b.w}, dt);
      b.left += l;
      b.right += r;
    }
    for (std::size_t i = 0; i < agents.size(); ++i) {
      msg::SensorFrame f;
      f.robot_id = agents[i]->id();
      f.seq = bodies[i].seq++;
      f.wheel_totals_valid = true;
      f.wheel_left_total = bodies[i].left;
      f.wheel_right_total = bodies[i].right;
      f.compass_valid = true;
      f.compass = bodies[i].truth.theta;
      f.range_max = 8.0f;
      f.battery = 0.9f;
      // What the robot's detector reports: a disc in the robot's frame.
      auto seen = [&](Vec2 at, msg::SourceKind kind, float r) {
        const Vec2 rel = at - bodies[i].truth.position();
        const double c = std::cos(bodies[i].truth.theta);
        const double s = std::sin(bodies[i].truth.theta);
        f.detections.push_back(
            {kind, static_cast<float>(c * rel.x + s * rel.y), static_cast<float>(-s * rel.x + c * rel.y), r});
        return rel.norm();
      };
      for (std::size_t j = 0; j < agents.size(); ++j) {
        if (j != i) {
          run.minSeparation =
              std::min(run.minSeparation, seen(bodies[j].truth.position(), msg::SourceKind::Robot, 0.3f));
        }
      }
      for (const Vec2& h : people) {
        run.minToPeople = std::min(run.minToPeople, seen(h, msg::SourceKind::Human, 0.25f));
      }
      agents[i]->onFrame(f);
      for (std::size_t j = 0; j < agents.size(); ++j) {
        if (j != i && k > 0) {
          agents[i]->onOtherRobot(states[j]);
        }
      }
    }
    for (std::size_t i = 0; i < agents.size(); ++i) {
      auto out = agents[i]->step(static_cast<std::int64_t>(k) * 100'000'000, 0.1);
      states[i] = out.state;
      bodies[i].v = out.command.v;
      bodies[i].w = out.command.w;
      if (out.status && out.status->state == msg::TaskState::Done) {
        run.done.push_back(agents[i]->id());
      }
      if (out.status && out.status->state == msg::TaskState::Failed) {
        run.failed.push_back(agents[i]->id() + ": " + out.status->error);
      }
      if (trace && k % 10 == 0) {
        std::printf("%5.1f %s %6.2f %6.2f %5.2f v %5.2f w %5.2f mode %d\n", k * 0.1, agents[i]->id().c_str(),
                    bodies[i].truth.x, bodies[i].truth.y, bodies[i].truth.theta, out.command.v, out.command.w,
                    static_cast<int>(out.state.mode));
      }
    }
  }
  for (const auto& b : bodies) {
    run.end.push_back(b.truth);
  }
  return run;
}

const double kUp = M_PI / 2;

msg::Goal station(const std::string& name) {
  if (name == "P-1") {
    return {{3.5, 16.75, -kUp}, name, msg::GoalAction::Load, 1.0};
  }
  if (name == "P-3") {
    return {{14.5, 16.75, -kUp}, name, msg::GoalAction::Load, 1.0};
  }
  if (name == "D-1") {
    return {{28.6, 4.0, M_PI}, name, msg::GoalAction::Unload, 1.0};
  }
  return {{1.5, 4.0, 0.0}, name, msg::GoalAction::Charge, 1.0};  // CHG-1
}

/// Every order done, none failed, the robots never closer than two radii; each robot of `parked`
/// back on its parking place at the end.
void expectDelivered(const Run& run, std::size_t orders, const std::vector<Robot>& parked = {}) {
  for (const auto& f : run.failed) {
    ADD_FAILURE() << f;
  }
  EXPECT_EQ(run.done.size(), orders);
  EXPECT_GE(run.minSeparation, 0.6) << "the bodies touched";
  for (std::size_t i = 0; i < parked.size(); ++i) {
    EXPECT_LT(distance(run.end[i].position(), parked[i].home.position()), 0.3) << parked[i].id << " not home";
  }
}

}  // namespace

// Every pair of destinations (west and east, up an aisle and along the band), sent at the same
// moment and 1.5 s apart: both robots leave, do the task, and drive home to their own places.
class ParkingBandPair : public ::testing::TestWithParam<std::tuple<const char*, const char*, double>> {};

TEST_P(ParkingBandPair, NeighboursLeaveDoTheTaskAndParkAgain) {
  const auto [to4, to5, lag] = GetParam();
  const std::vector<Robot> robots{{"r4", {6.0, 0.9, kUp}}, {"r5", {7.0, 0.9, kUp}}};
  expectDelivered(drive(robots, {{"r4", station(to4), 0.0}, {"r5", station(to5), lag}}, 3000), 2, robots);
}

// e.g. "r4_P1_r5_CHG1_at_once", "r4_P1_r5_D1_1500ms_later"
std::string pairName(const ::testing::TestParamInfo<ParkingBandPair::ParamType>& info) {
  auto bare = [](std::string n) {
    std::erase(n, '-');
    return n;
  };
  const double lag = std::get<2>(info.param);
  return "r4_" + bare(std::get<0>(info.param)) + "_r5_" + bare(std::get<1>(info.param)) +
         (lag > 0.0 ? "_" + std::to_string(static_cast<int>(lag * 1000)) + "ms_later"
                    : std::string("_at_once"));
}

INSTANTIATE_TEST_SUITE_P(Destinations, ParkingBandPair,
                         ::testing::Combine(::testing::Values("P-1", "P-3", "D-1", "CHG-1"),
                                            ::testing::Values("P-1", "P-3", "D-1", "CHG-1"),
                                            ::testing::Values(0.0, 1.5)),
                         pairName);

TEST(ParkingBand, ThreeNeighboursLeaveTogetherAndComeBack) {
  // The middle one goes west, its neighbours east and west: every way out crosses another's.
  const std::vector<Robot> robots{{"r3", {5.0, 0.9, kUp}}, {"r4", {6.0, 0.9, kUp}}, {"r5", {7.0, 0.9, kUp}}};
  const auto run =
      drive(robots, {{"r3", station("P-3"), 0.0}, {"r4", station("CHG-1"), 0.0}, {"r5", station("P-1"), 0.0}},
            3000);
  expectDelivered(run, 3, robots);
}

// One robot drives home along the band while its neighbour leaves towards it, at a few timings.
class ParkingBandCrossing : public ::testing::TestWithParam<double> {};

TEST_P(ParkingBandCrossing, ARobotComingHomeAndItsNeighbourLeavingPass) {
  // r5 runs an errand 5 m east along the band and drives home from there 5 s after it.
  const std::vector<Robot> robots{{"r4", {6.0, 0.9, kUp}}, {"r5", {7.0, 0.9, kUp}}};
  const msg::Goal errand{{12.0, 1.9, M_PI}, "X", msg::GoalAction::Park, 0.0};
  expectDelivered(drive(robots, {{"r5", errand, 0.0}, {"r4", station("P-3"), GetParam()}}, 2500), 2, robots);
}

std::string leavingName(const ::testing::TestParamInfo<double>& info) {
  return "leaves_at_" + std::to_string(static_cast<int>(info.param)) + "s";
}

INSTANTIATE_TEST_SUITE_P(Timings, ParkingBandCrossing, ::testing::Values(18.0, 22.0, 26.0, 30.0),
                         leavingName);

TEST(AisleQueue, TheRobotBehindGoesRoundOneThatWaitsOnAPerson) {
  // Up the aisle above PARK-5 (from a 20-robot run, where the one behind failed its task): a
  // person stands at the mouth of the shelf rows and does not step aside; one robot waits on the
  // person, a second queues right behind it and has priority (the smaller id). The one behind must
  // go round by another aisle: its detour around the robot in front failed while the disc kept
  // clear around that robot covered the cell it stood in itself.
  const std::vector<Robot> robots{{"r6", {7.36, 11.66, 1.48}}, {"r7", {7.39, 12.61, 1.48}}};
  const auto run =
      drive(robots, {{"r6", station("P-1"), 0.0}, {"r7", station("P-3"), 0.0}}, 2000, {Vec2{6.83, 12.82}});
  expectDelivered(run, 2);
  EXPECT_GE(run.minToPeople, 0.55) << "touched the person";
}

TEST(StationQueue, ARobotLeavesADropOffThroughTheQueueInFrontOfIt) {
  // From a 20-robot run: r1 leaves D-4 for P-5, up and to the left, where r4 queues for D-4 and
  // r2 comes down from P-5 right behind r4. r4 could not make room (r2 at its back), r2 had
  // priority over r4 and waited on it, r1 waited on r4: two tasks failed after 60 s there. (In this
  // world the chain resolves with and without the rules written for it, docs/algorithms.md sixth
  // round: the run's timing is not reproduced; the case stays as a regression test.)
  const std::vector<Robot> robots{
      {"r1", {28.6, 13.0, M_PI}}, {"r2", {26.19, 14.63, -1.44}}, {"r4", {26.55, 13.71, -0.6}}};
  const msg::Goal d4{{28.6, 13.0, M_PI}, "D-4", msg::GoalAction::Unload, 2.0};
  const msg::Goal p5{{25.5, 16.75, -kUp}, "P-5", msg::GoalAction::Load, 2.0};
  expectDelivered(drive(robots, {{"r1", p5, 0.0}, {"r2", station("D-1"), 0.0}, {"r4", d4, 0.0}}, 2000), 3);
}

TEST(ParkingBand, AnOrderWhilePassingAboveAParkedNeighbourIsNotHeldByIt) {
  // From a 20-robot run: r7, on its way home along the band, gets an order for P-2 right above
  // its parked neighbour r6. Its path passes r6 with room to spare, but turning towards it, the
  // local planner faced r6 and stopped. The re-plan around a standing robot (every 3 s, the same
  // path each time) shared its timer with the detour around the blocking point (every 8 s), which
  // therefore never ran: the task failed after 60 s. Ordered at several moments of the pass.
  const std::vector<Robot> robots{{"r6", {8.0, 0.9, kUp}}, {"r7", {9.0, 0.9, kUp}}};
  const msg::Goal errand{{7.25, 4.5, kUp}, "X", msg::GoalAction::Park, 0.0};
  const msg::Goal p2{{9.0, 16.75, -kUp}, "P-2", msg::GoalAction::Load, 2.0};
  for (const double at : {30.0, 30.5, 31.0, 31.5, 32.0}) {
    SCOPED_TRACE("ordered at " + std::to_string(at) + " s");
    expectDelivered(drive(robots, {{"r7", errand, 0.0}, {"r7", p2, at}}, 1500), 2);
  }
}
