#include "fleet/traffic/traffic_control.hpp"

#include <gtest/gtest.h>

#include <algorithm>

#include "fleet/site/site_loader.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/virtual_fleet.hpp"

namespace fleet::traffic {
namespace {

Roadmap smallWarehouse(RoadmapOptions options = {}) {
  const auto site =
      site::loadSite(std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/small_warehouse.site.json");
  return buildRoadmap(site, options);
}

/// Robots follow the releases, late at random. What holds whatever the planner does: no two robots
/// ever hold conflicting nodes, their centres keep the contact distance, no report is refused.
/// (How much work they get done is the planner's business: measured in docs/benchmarks.md, where
/// the 20-robot fleet still jams; see the issue notes.)
/// Seeds 1–3 of the virtual fleet, each checked against every promise; returns the results.
std::vector<VirtualFleetResult> runSeeds(Roadmap& map, VirtualFleetOptions o) {
  std::vector<VirtualFleetResult> out;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    o.seed = seed;
    const auto r = runVirtualFleet(map, o);
    SCOPED_TRACE(formatResult(r));
    EXPECT_EQ(r.holdViolations, 0U);
    EXPECT_EQ(r.contacts, 0U);
    EXPECT_EQ(r.refusedReports, 0U);
    if (o.robots > 1) {
      EXPECT_GE(r.minSeparation, map.separation.contact - map.separation.margin);
    }
    out.push_back(r);
  }
  return out;
}

TEST(VirtualFleet, TwentyRobotsOnTheSmallWarehouseNeverMeet) {
  Roadmap map = smallWarehouse();
  VirtualFleetOptions o;
  o.robots = 20;
  o.duration = 300.0;
  runSeeds(map, o);
}

/// A robot parked in a dock whose only way out is excluded by a robot standing on the lane in
/// front: PIBT moves one node per step and the robot outside cannot clear the exit in one step, so
/// plain PIBT leaves both where they are for ever. The stalled robot makes the other drive away.
TEST(TrafficControl, ARobotBlockingADockExitIsSentAway) {
  // The lattice of before session 21 (nodes beside shelf corners too), where the lane node in
  // front of PARK-1 has no way round the exit it excludes: the knot this test needs.
  RoadmapOptions o;
  o.nodeClearance = 0.0;
  Roadmap map = smallWarehouse(o);
  const NodeId park = map.station("PARK-1")->dock;
  // The lane node just right of the dock's exit (PARK-1 at (3, 0.9) is left by (3, 1.9)): it
  // excludes the exit, and every node it can step to excludes the exit or the dock.
  const NodeId exit = map.graph.edges(park)[0].to;
  const NodeId front = map.nearest({3.25, 1.75});
  ASSERT_TRUE(map.graph.conflicting(front, exit));
  ASSERT_NE(front, kNoNode);
  const std::vector<NodeId> starts{park, front};
  const NodeId goal0 = map.station("P-4")->dock, goal1 = map.station("P-1")->dock;
  // Evasion alone gets it off the dock, detours alone get both robots to their goals (the robot in
  // front goes round the parked one's exit instead of waiting on it), so does the planner's
  // untangling alone (a search over a few steps of both robots), and so do all together (the
  // default); none of them: both stay for ever. (Evasion alone no longer gets both to their goals
  // here since steps for robots the plan keeps standing are paced: they swap places back and forth.)
  enum class Way { Neither, Evasion, Detour, Untangle, All };
  for (Way way : {Way::Neither, Way::Evasion, Way::Detour, Way::Untangle, Way::All}) {
    const bool evade = way != Way::Neither;
    TrafficOptions opt;
    if (way != Way::All) {
      opt.evadeAfter = way == Way::Evasion ? 6 : 1000000;
      opt.pibt.detourAfter = way == Way::Detour ? 4 : 0;
      opt.pibt.untangleGroup = way == Way::Untangle ? 4 : 0;
    }
    TrafficControl tc(map.graph, starts, opt);
    tc.setGoal(0, goal0);
    tc.setGoal(1, goal1);
    bool left = false;
    for (int t = 0; t < 600; ++t) {
      tc.update();
      for (std::size_t r = 0; r < 2; ++r) {
        const auto rel = tc.release(r);
        if (rel.base.size() > 1) {
          EXPECT_EQ(tc.reached(r, rel.base[1]), Report::Accepted);
        }
      }
      left = left || tc.at(0) != park;
    }
    EXPECT_EQ(left, evade) << "way " << static_cast<int>(way);
    if (way == Way::Detour || way == Way::Untangle || way == Way::All) {
      EXPECT_TRUE(tc.arrived(0)) << "way " << static_cast<int>(way);
      EXPECT_TRUE(tc.arrived(1)) << "way " << static_cast<int>(way);
    }
    if (way == Way::Evasion) {
      EXPECT_GE(tc.stats().evasions, 1U);
    }
    if (way == Way::Detour) {
      EXPECT_GE(tc.plannerStats().detours, 1U);
    }
    if (way == Way::Untangle) {
      EXPECT_GE(tc.plannerStats().untangles, 1U);
    }
  }
}

/// A lone robot released one node on (its goal was there), then given a goal behind it: the plan
/// starts again from the released end and comes back over the node the robot stands on. That plan
/// was two nodes long, so it was not planned further, and the robot stood for good on a base that
/// ended where it was (seen in the full stack when a task preempted a trip home).
TEST(TrafficControl, APlanThatComesBackToTheRobotsNodeIsPlannedOn) {
  // A corridor 0 - 1 - ... - 6, 0.5 m apart; the robot on 3.
  Graph g;
  for (int i = 0; i <= 6; ++i)
    g.addNode({0.5 * i, 0.0});
  for (NodeId i = 0; i < 6; ++i) {
    g.addEdge(i, i + 1);
    g.addEdge(i + 1, i);
  }
  const std::vector<NodeId> starts{3};
  TrafficControl tc(g, starts);
  ASSERT_TRUE(tc.setGoal(0, 4));
  tc.update();
  auto rel = tc.release(0);
  ASSERT_EQ(rel.base, (std::vector<NodeId>{3, 4}));
  ASSERT_TRUE(tc.setGoal(0, 0));  // before the robot reports 4
  for (int t = 0; t < 5; ++t)
    tc.update();
  rel = tc.release(0);
  // Planned 3 4 3 2 1 0: released up to 4 only, since a base passing the robot's node twice is
  // taken as driven by the agent (Execution.ABaseNeverPassesANodeTwice); the rest once it reports 4.
  ASSERT_EQ(rel.base, (std::vector<NodeId>{3, 4})) << tc.explain(0);
  EXPECT_NE(rel.base.back(), 3) << "the base must lead somewhere, not back to where the robot stands";
  // Reporting the end of every base gets it there.
  for (int t = 0; t < 100 && !tc.arrived(0); ++t) {
    tc.update();
    rel = tc.release(0);
    if (rel.base.size() > 1) {
      EXPECT_EQ(tc.reached(0, rel.base.back()), Report::Accepted);
    }
  }
  EXPECT_TRUE(tc.arrived(0));
}

TEST(TrafficControl, RobotsWaitInLineAtABusyStation) {
  Roadmap map = smallWarehouse();
  const auto* d1 = map.station("D-1");
  ASSERT_GE(d1->queue.size(), 2U);
  std::vector<NodeId> starts;
  for (const char* p : {"PARK-1", "PARK-5", "PARK-9"})
    starts.push_back(map.station(p)->dock);
  TrafficControl tc(map.graph, starts);
  tc.setStations({{d1->dock, d1->queue}});
  for (std::size_t r = 0; r < 3; ++r)
    tc.setGoal(r, d1->dock);
  EXPECT_EQ(tc.line(d1->dock), (std::vector<std::size_t>{0, 1, 2}));
  EXPECT_EQ(tc.planner().goal(0), d1->dock);
  EXPECT_EQ(tc.planner().goal(1), d1->queue[0]);
  EXPECT_EQ(tc.planner().goal(2), d1->queue[1]);
  tc.setGoal(0, map.station("P-1")->dock);  // robot 0 is done: the line moves up
  EXPECT_EQ(tc.line(d1->dock), (std::vector<std::size_t>{1, 2}));
  EXPECT_EQ(tc.planner().goal(1), d1->dock);
  EXPECT_EQ(tc.planner().goal(2), d1->queue[0]);
}

/// The line's order is where robots stand, not when they joined: robot 0 joined first but is far
/// away, robot 1 stands in the queue. The queue is one way toward the station, so with robot 0
/// first robot 1 would wait for it and robot 0 could never get past robot 1 (seen in the virtual
/// fleet: three robots in a drop-off's queue behind an empty dock, for 200 s).
TEST(TrafficControl, RobotsStandingInTheQueueGoBeforeRobotsOnTheirWay) {
  Roadmap map = smallWarehouse();
  const auto* d1 = map.station("D-1");
  ASSERT_GE(d1->queue.size(), 2U);
  const std::vector<NodeId> starts{map.station("PARK-1")->dock, d1->queue[1]};
  TrafficControl tc(map.graph, starts);
  tc.setStations({{d1->dock, d1->queue, d1->approach}});
  tc.setGoal(0, d1->dock);
  tc.setGoal(1, d1->dock);
  EXPECT_EQ(tc.line(d1->dock), (std::vector<std::size_t>{0, 1}));
  tc.update();
  EXPECT_EQ(tc.line(d1->dock), (std::vector<std::size_t>{1, 0}));
  EXPECT_EQ(tc.planner().goal(1), d1->dock);
}

/// While the robot that was at the dock drives off it, the next in line waits where it leaves the
/// approach's ways out free, not only the dock's: a robot leaving a drop-off goes on sideways from
/// the approach, and a robot waiting on the queue's head shut that way (seen in the virtual fleet:
/// the leaving robot and three waiting ones stood for 220 s at D-3).
TEST(TrafficControl, TheNextInLineWaitsClearOfTheWaysOutOfTheApproach) {
  Roadmap map = smallWarehouse();
  const auto* d3 = map.station("D-3");
  ASSERT_NE(d3->approach, kNoNode);
  ASSERT_GE(d3->queue.size(), 2U);
  std::vector<NodeId> exits;
  for (const Edge& e : map.graph.edges(d3->approach)) {
    if (e.to != d3->dock && std::find(d3->queue.begin(), d3->queue.end(), e.to) == d3->queue.end())
      exits.push_back(e.to);
  }
  ASSERT_FALSE(exits.empty());
  auto shuts = [&](NodeId q) {
    return std::any_of(exits.begin(), exits.end(), [&](NodeId x) { return map.graph.conflicting(x, q); });
  };
  ASSERT_TRUE(shuts(d3->queue[0]));  // the case: the head of the queue is in the way out
  const std::vector<NodeId> starts{d3->dock, map.station("PARK-1")->dock};
  TrafficControl tc(map.graph, starts);
  tc.setStations({{d3->dock, d3->queue, d3->approach}});
  tc.setGoal(0, d3->dock);
  tc.setGoal(1, d3->dock);
  tc.setGoal(0, map.station("P-1")->dock);  // robot 0 is done and drives off
  EXPECT_EQ(tc.line(d3->dock), (std::vector<std::size_t>{1}));
  const NodeId wait = tc.planner().goal(1);
  EXPECT_NE(std::find(d3->queue.begin(), d3->queue.end(), wait), d3->queue.end());
  EXPECT_FALSE(shuts(wait));
}

/// The dock stays the leaving robot's until it has *reported* a node clear of it. The plan runs
/// ahead of the robots; freeing the dock when the plan had the robot off it let the next in line
/// onto the approach, and after a re-plan put the leaving robot back on the dock in the planner,
/// each stood waiting for the other's node for good (virtual fleet, station cap 2, seed 14: 401 s
/// at D-4 until the run ended).
TEST(TrafficControl, TheDockIsFreeOnlyOnceTheLeavingRobotReportsItOff) {
  Roadmap map = smallWarehouse();
  const auto* d3 = map.station("D-3");
  ASSERT_NE(d3->approach, kNoNode);
  const std::vector<NodeId> starts{d3->dock, map.station("PARK-1")->dock};
  TrafficControl tc(map.graph, starts);
  tc.setStations({{d3->dock, d3->queue, d3->approach}});
  tc.setGoal(0, d3->dock);
  tc.setGoal(1, d3->dock);
  tc.setGoal(0, map.station("P-1")->dock);  // robot 0 is done and is to drive off
  // Robot 0 drives on, slowly, but only within what the dock excludes (onto the approach): the plan
  // runs ahead of it, clear of the dock, yet robot 1 must go on waiting in line.
  for (int k = 0; k < 30; ++k) {
    tc.update();
    const auto base = tc.release(0).base;
    if (base.size() > 1 && map.graph.conflicting(base[1], d3->dock))
      tc.reached(0, base[1]);
    ASSERT_TRUE(map.graph.conflicting(tc.execution().at(0), d3->dock));
    ASSERT_NE(tc.planner().goal(1), d3->dock) << "update " << k << ": the dock was given away";
  }
  // Robot 0 drives what it is released until it reports a node clear of the dock.
  for (int k = 0; k < 200 && map.graph.conflicting(tc.execution().at(0), d3->dock); ++k) {
    tc.update();
    const auto base = tc.release(0).base;
    if (base.size() > 1)
      tc.reached(0, base[1]);
  }
  ASSERT_FALSE(map.graph.conflicting(tc.execution().at(0), d3->dock)) << "robot 0 never left the dock";
  tc.update();
  EXPECT_EQ(tc.planner().goal(1), d3->dock);
}

/// Five robots chained on random tasks. Before detours, pacing and leaving docks first, three
/// seeds did 3, 7 and 24 tasks in 600 s (robots stood for hundreds of seconds next to a free way
/// round a robot waiting in line, and one leaving a drop-off spur was pushed back onto it by the
/// robot waiting for it). A lone robot does 6 or 7.
TEST(VirtualFleet, FiveRobotsKeepWorkingOnTheSmallWarehouse) {
  Roadmap map = smallWarehouse();
  VirtualFleetOptions o;
  o.robots = 5;
  o.duration = 600.0;
  for (const auto& r : runSeeds(map, o)) {
    SCOPED_TRACE(formatResult(r));
    EXPECT_LT(r.longestWait, 120.0);
    EXPECT_GE(r.tasksDone, 15U);
  }
}

/// The fleet manager's station cap in the virtual fleet: with one task per station, at most as many
/// robots have a task as there are drop-offs, no two of them head for one station, and the others
/// wait at parking places; the promises hold and work gets done.
TEST(VirtualFleet, AStationCapKeepsTasksApartAndTheRestParked) {
  Roadmap map = smallWarehouse();
  std::size_t dropoffs = 0;
  for (const auto& s : map.stations) {
    dropoffs += s.kind == site::StationKind::Dropoff && s.dock != kNoNode ? 1 : 0;
  }
  VirtualFleetOptions o;
  o.robots = 10;
  o.duration = 300.0;
  o.stationCap = 1;
  o.recordEvery = 1.0;
  for (const auto& r : runSeeds(map, o)) {
    SCOPED_TRACE(formatResult(r));
    EXPECT_GE(r.tasksDone, 4U);
    std::size_t most = 0;
    for (const auto& f : r.frames) {
      std::vector<NodeId> targets;
      for (const auto& b : f.robots) {
        if (b.target != kNoNode) {
          targets.push_back(b.target);
        }
      }
      most = std::max(most, targets.size());
      std::sort(targets.begin(), targets.end());
      EXPECT_EQ(std::adjacent_find(targets.begin(), targets.end()), targets.end())
          << "two robots head for one station at " << f.time << " s";
    }
    EXPECT_LE(most, dropoffs);
    EXPECT_GE(most, 2U);
    // The robots without a task end up at parking places.
    std::size_t parked = 0;
    for (const auto& b : r.frames.back().robots) {
      if (b.target == kNoNode) {
        for (const auto& s : map.stations) {
          parked +=
              s.kind == site::StationKind::Parking && (map.graph.position(s.dock) - b.position).norm() < 1e-6;
        }
      }
    }
    EXPECT_GE(parked, o.robots - dropoffs - 2) << "robots without a task are not at parking places";
  }
}

TEST(VirtualFleet, ALoneRobot) {
  Roadmap map = smallWarehouse();
  VirtualFleetOptions o;
  o.robots = 1;
  o.duration = 1200.0;
  const auto r = runVirtualFleet(map, o);
  std::cout << formatResult(r) << "\n";
  EXPECT_GT(r.tasksDone, 10U);
  EXPECT_EQ(r.refusedReports, 0U);
}

}  // namespace
}  // namespace fleet::traffic
