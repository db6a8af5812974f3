#include "fleet/traffic/execution.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <random>

namespace fleet::traffic {
namespace {

/// A w×h 4-connected grid with unit spacing; `exclusion` > 0 makes every node exclude the nodes
/// within that many cells (Chebyshev), as a roadmap's footprint does.
Graph grid(int w, int h, int exclusion = 0, const std::vector<int>& blocked = {}) {
  Graph g;
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x)
      g.addNode({static_cast<double>(x), static_cast<double>(y)});
  }
  auto id = [w](int x, int y) { return static_cast<NodeId>(y * w + x); };
  auto free = [&](NodeId v) { return std::find(blocked.begin(), blocked.end(), v) == blocked.end(); };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      if (!free(id(x, y))) {
        g.setOpen(id(x, y), false);
        continue;
      }
      if (x + 1 < w && free(id(x + 1, y))) {
        g.addEdge(id(x, y), id(x + 1, y));
        g.addEdge(id(x + 1, y), id(x, y));
      }
      if (y + 1 < h && free(id(x, y + 1))) {
        g.addEdge(id(x, y), id(x, y + 1));
        g.addEdge(id(x, y + 1), id(x, y));
      }
      for (int dy = -exclusion; dy <= exclusion; ++dy) {
        for (int dx = -exclusion; dx <= exclusion; ++dx) {
          const int X = x + dx, Y = y + dy;
          if (X >= 0 && Y >= 0 && X < w && Y < h && (dx || dy))
            g.addConflict(id(x, y), id(X, Y));
        }
      }
    }
  }
  return g;
}

TEST(Execution, AFollowerEntersOnlyAfterTheLeaderHasLeft) {
  const Graph g = grid(4, 1);
  const std::vector<NodeId> start{1, 0};  // robot 0 leads, robot 1 follows in the same step
  Execution ex(g, start);
  ex.append(std::vector<NodeId>{2, 1});
  ex.append(std::vector<NodeId>{3, 2});
  EXPECT_EQ(ex.plannedSteps(), 2);
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0}));
  EXPECT_EQ(ex.waitingOn(1), (std::vector<std::size_t>{0}));
  const auto lead = ex.release(0);
  EXPECT_EQ(lead.base, (std::vector<NodeId>{1, 2, 3}));  // nothing ahead of the leader waits
  EXPECT_TRUE(lead.horizon.empty());
  EXPECT_EQ(lead.baseEndStep, 2);
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0}));  // released is not reached
  ASSERT_EQ(ex.reached(0, 2), Report::Accepted);
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0, 1}));  // node 2 waits for the leader again
  EXPECT_EQ(ex.release(1).horizon, (std::vector<NodeId>{2}));
  EXPECT_EQ(ex.waitingOn(1), (std::vector<std::size_t>{0}));
  ASSERT_EQ(ex.reached(0, 3), Report::Accepted);
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0, 1, 2}));
  EXPECT_TRUE(ex.waitingOn(1).empty());
}

// The planner moves a robot aside and back onto its node ([0 1 4 3 0 1 2]); a base that passes a
// node twice made the agent take it as driven (its node at both ends) and stand for good.
// Each release says why its base ends where it does: a dependency, the plan's end, or the base
// is long enough (more was free).
TEST(Execution, EachReleaseSaysWhyItsBaseEndsThere) {
  const Graph g = grid(8, 1);
  const std::vector<NodeId> start{1, 0};
  ReleaseOptions o;
  o.baseAhead = 2.0;  // two unit edges
  Execution ex(g, start, o);
  for (NodeId k = 2; k <= 6; ++k)
    ex.append(std::vector<NodeId>{k, static_cast<NodeId>(k - 1)});
  ex.release(1);
  EXPECT_EQ(ex.baseCut(1), BaseCut::Held) << "its next node waits for robot 0 to leave it";
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{1, 2, 3}));
  EXPECT_EQ(ex.baseCut(0), BaseCut::Limit) << "more was free: the base is long enough";
  ASSERT_EQ(ex.reached(0, 3), Report::Accepted);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{3, 4, 5}));
  EXPECT_EQ(ex.reached(0, 5), Report::Accepted);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{5, 6}));
  EXPECT_EQ(ex.baseCut(0), BaseCut::PlanEnd);
  EXPECT_STREQ(toString(BaseCut::Limit), "limit");
}

TEST(Execution, ReleasedFromIsTheNodeTheReleasedRouteEntersItsEndFrom) {
  const Graph g = grid(8, 1);
  const std::vector<NodeId> start{0};
  ReleaseOptions o;
  o.baseAhead = 2.0;  // two unit edges
  Execution ex(g, start, o);
  EXPECT_EQ(ex.releasedFrom(0), kNoNode) << "it never moved";
  for (const NodeId v : {1, 1, 2, 3, 4, 5})
    ex.append(std::vector<NodeId>{v});
  const auto base = ex.release(0).base;
  ASSERT_EQ(base, (std::vector<NodeId>{0, 1, 2}));
  EXPECT_EQ(ex.releasedEnd(0), 2);
  EXPECT_EQ(ex.releasedFrom(0), 1) << "a step standing on the way is no heading";
  ASSERT_EQ(ex.reached(0, 2), Report::Accepted);
  ex.release(0);
  EXPECT_EQ(ex.releasedEnd(0), 4);
  EXPECT_EQ(ex.releasedFrom(0), 3);
}

TEST(Execution, ABaseNeverPassesANodeTwice) {
  const Graph g = grid(3, 2);  // 0 1 2 / 3 4 5
  const std::vector<NodeId> start{0};
  Execution ex(g, start, ReleaseOptions{10.0, 12, 8});
  for (const NodeId v : {1, 4, 3, 0, 1, 2})
    ex.append(std::vector<NodeId>{v});
  const auto first = ex.release(0);
  EXPECT_EQ(first.base, (std::vector<NodeId>{0, 1, 4, 3}));
  EXPECT_TRUE(first.horizon.empty()) << "the horizon stops where it comes back too";
  // Once the robot has left 0 the way back to it is released, up to 1, which comes again.
  EXPECT_EQ(ex.reached(0, 1), Report::Accepted);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{1, 4, 3, 0}));
  EXPECT_EQ(ex.reached(0, 0), Report::Accepted);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{0, 1, 2}));
  EXPECT_EQ(ex.reached(0, 2), Report::Accepted);
}

TEST(Execution, RefusedStepsNameTheRobotsAndChangeNothing) {
  const Graph g = grid(3, 3);
  Execution ex(g, std::vector<NodeId>{0, 1});
  auto refused = [&](std::vector<NodeId> next, const std::string& what) {
    try {
      ex.append(next);
      ADD_FAILURE() << "accepted a step with " << what;
    } catch (const PlanStepError& e) {
      EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
    }
    EXPECT_EQ(ex.plannedSteps(), 0);
    EXPECT_EQ(ex.plannedEnd(0), 0);
    EXPECT_EQ(ex.plannedEnd(1), 1);
  };
  refused({1, 0}, "each enter what the next one leaves");  // a swap
  refused({1, 1}, "on node 1");
  refused({8, 1}, "no open edge");
  refused({0}, "1 nodes for 2 robots");
  refused({0, 99}, "off the graph");
  EXPECT_THROW(Execution(g, std::vector<NodeId>{4, 4}), PlanStepError);
}

TEST(Execution, ARotationIsRefused) {
  const Graph g = grid(2, 2);  // nodes 0 1 / 2 3, a cycle 0-1-3-2
  Execution ex(g, std::vector<NodeId>{0, 1, 3, 2});
  EXPECT_THROW(ex.append(std::vector<NodeId>{1, 3, 2, 0}), PlanStepError);
  ex.append(std::vector<NodeId>{0, 1, 3, 2});  // all wait: fine
  EXPECT_EQ(ex.plannedSteps(), 1);
}

TEST(Execution, ConflictSetsKeepRobotsApartNotOnlyNodes) {
  const Graph g = grid(5, 1, 1);  // a node excludes its neighbours
  Execution ex(g, std::vector<NodeId>{2, 0});
  EXPECT_THROW(ex.append(std::vector<NodeId>{2, 1}), PlanStepError);
  ex.append(std::vector<NodeId>{3, 0});
  ex.append(std::vector<NodeId>{4, 1});  // follows at a distance of two nodes
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0}));
  ex.release(0);
  ASSERT_EQ(ex.reached(0, 3), Report::Accepted);  // 3 excludes 2 and 4, no longer 1
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0, 1}));
}

TEST(Execution, BadReportsAreRefusedAndTheRobotStaysHeld) {
  const Graph g = grid(6, 1);
  Execution ex(g, std::vector<NodeId>{0}, ReleaseOptions{2.0, 12, 8});
  for (NodeId v = 1; v < 6; ++v)
    ex.append(std::vector<NodeId>{v});
  EXPECT_EQ(ex.reached(0, 1), Report::NotReleased);  // nothing released yet
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{0, 1, 2}));
  EXPECT_EQ(ex.reached(0, 5), Report::NotReleased);
  EXPECT_EQ(ex.reached(3, 1), Report::UnknownRobot);
  EXPECT_EQ(ex.reached(0, 0), Report::Duplicate);
  EXPECT_EQ(ex.reached(0, 2), Report::Accepted);     // skipping a node's report is fine
  EXPECT_EQ(ex.reached(0, 1), Report::NotReleased);  // out of order: behind it
  EXPECT_EQ(ex.at(0), 2);
  EXPECT_EQ(ex.progressStep(0), 2);
}

// One robot's move appended by itself is the configuration with that move appended: the same
// refusals, dependencies, releases and waits, on random moves (many refused: onto others, off the
// edges) with robots reporting as they go and now and then the plan cut back to what is released,
// on grids whose nodes exclude their neighbours (even seeds) or not. (The order a let-pass raises is
// read by the dependencies both share, Execution::depend.)
TEST(Execution, AMoveAppendedAloneIsTheConfigurationWithThatMove) {
  for (std::uint32_t seed = 1; seed <= 6; ++seed) {
    std::mt19937 rng(seed);
    const Graph g = grid(10, 7, seed % 2 == 0 ? 1 : 0, {12, 13, 33, 47});
    std::vector<NodeId> pos;
    for (NodeId v = 0; static_cast<std::size_t>(v) < g.size() && pos.size() < 9; v += 3) {
      if (g.isOpen(v) && std::none_of(pos.begin(), pos.end(), [&](NodeId p) { return g.conflicting(p, v); }))
        pos.push_back(v);
    }
    const std::size_t n = pos.size();
    Execution whole(g, pos, ReleaseOptions{2.0, 4, 3});
    Execution alone(g, pos, ReleaseOptions{2.0, 4, 3});
    int refused = 0, moved = 0;
    for (int k = 0; k < 400; ++k) {
      const std::size_t r = rng() % n;
      const auto out = g.edges(pos[r]);
      // Mostly along an edge, sometimes a node it has no edge to, or standing still.
      const NodeId to = rng() % 10 == 0                  ? static_cast<NodeId>(rng() % g.size())
                        : out.empty() || rng() % 10 == 0 ? pos[r]
                                                         : out[rng() % out.size()].to;
      const bool moves = to != pos[r];
      std::vector<NodeId> next = pos;
      next[r] = to;
      std::string a, b;
      try {
        whole.append(next);
      } catch (const PlanStepError& e) {
        a = e.what();
      }
      try {
        alone.appendMove(r, to);
      } catch (const PlanStepError& e) {
        b = e.what();
      }
      ASSERT_EQ(a.empty(), b.empty()) << "seed " << seed << " move " << k << ": " << a << " | " << b;
      if (a.empty()) {
        pos = next;
        moved += moves ? 1 : 0;
      } else {
        ++refused;
      }
      ASSERT_EQ(whole.plannedSteps(), alone.plannedSteps());
      // Robots report their next released node now and then, the same on both.
      for (std::size_t q = 0; q < n; ++q) {
        const auto ra = whole.release(q);
        const auto rb = alone.release(q);
        ASSERT_EQ(ra.base, rb.base) << "seed " << seed << " move " << k << " robot " << q;
        ASSERT_EQ(whole.describe(q), alone.describe(q)) << "seed " << seed << " move " << k;
        ASSERT_EQ(whole.waitingOn(q), alone.waitingOn(q));
        if (ra.base.size() > 1 && rng() % 3 == 0) {
          ASSERT_EQ(whole.reached(q, ra.base[1]), Report::Accepted);
          ASSERT_EQ(alone.reached(q, ra.base[1]), Report::Accepted);
        }
      }
      if (k % 53 == 52) {  // planned again from what is released
        const auto ends = whole.truncateToReleased();
        ASSERT_EQ(ends, alone.truncateToReleased());
        pos = ends;
      }
    }
    EXPECT_GT(refused, 10) << "seed " << seed;
    EXPECT_GT(moved, 100) << "seed " << seed;
  }
}

/// Random plans executed by robots that are late at random: at every tick no two robots occupy
/// conflicting nodes (a moving robot occupies both ends of its edge), and every route is driven to
/// its end (no deadlock). Plans are drawn step by step as a planner would: robots decide in random
/// order, a robot may follow one that decided to move away, and half-way the unreleased plan is
/// dropped and planning starts again from the released ends.
void randomExecution(int exclusion, std::uint32_t seed, int* passes = nullptr) {
  std::mt19937 rng(seed);
  const int w = 12, h = 9;
  std::vector<int> blocked;
  for (int i = 0; i < 14; ++i)
    blocked.push_back(static_cast<int>(rng() % (w * h)));
  const Graph g = grid(w, h, exclusion, blocked);
  // Starts: free nodes that do not conflict.
  std::vector<NodeId> pos;
  std::vector<NodeId> order(g.size());
  for (std::size_t i = 0; i < g.size(); ++i)
    order[i] = static_cast<NodeId>(i);
  std::shuffle(order.begin(), order.end(), rng);
  const std::size_t robots = exclusion ? 7 : 18;
  for (NodeId v : order) {
    if (pos.size() == robots)
      break;
    if (!g.isOpen(v))
      continue;
    if (std::none_of(pos.begin(), pos.end(), [&](NodeId p) { return g.conflicting(p, v); }))
      pos.push_back(v);
  }
  ASSERT_EQ(pos.size(), robots);
  Execution ex(g, pos, ReleaseOptions{2.0, 4, 3});

  auto planSteps = [&](int steps) {
    for (int s = 0; s < steps; ++s) {
      std::vector<NodeId> next(robots, kNoNode);
      std::vector<std::size_t> turn(robots);
      for (std::size_t r = 0; r < robots; ++r)
        turn[r] = r;
      std::shuffle(turn.begin(), turn.end(), rng);
      for (std::size_t r : turn) {
        std::vector<NodeId> cand{pos[r]};
        for (const auto& e : g.edges(pos[r])) {
          if (g.passable(pos[r], e))
            cand.push_back(e.to);
        }
        std::shuffle(cand.begin() + 1, cand.end(), rng);
        std::rotate(cand.begin(), cand.begin() + 1, cand.end());  // waiting is the last resort
        for (NodeId c : cand) {
          bool ok = true;
          for (std::size_t q = 0; q < robots && ok; ++q) {
            if (q == r)
              continue;
            if (next[q] != kNoNode) {
              ok = !g.conflicting(next[q], c);  // decided robots: their next node
            } else {
              ok = !g.conflicting(pos[q], c);  // undecided robots may stay
            }
          }
          if (ok) {
            next[r] = c;
            break;
          }
        }
        ASSERT_NE(next[r], kNoNode);  // waiting is always possible
      }
      ex.append(next);
      pos = next;
    }
  };

  // Execution: a moving robot takes 1-4 ticks per edge.
  std::vector<NodeId> at(robots), target(robots, kNoNode);
  std::vector<int> left(robots, 0);
  for (std::size_t r = 0; r < robots; ++r)
    at[r] = ex.at(r);
  auto occupied = [&](std::size_t r) {
    std::vector<NodeId> o{at[r]};
    if (target[r] != kNoNode)
      o.push_back(target[r]);
    return o;
  };
  auto checkApart = [&](int tick) {
    for (std::size_t a = 0; a < robots; ++a) {
      for (std::size_t b = a + 1; b < robots; ++b) {
        for (NodeId x : occupied(a)) {
          for (NodeId y : occupied(b)) {
            ASSERT_FALSE(g.conflicting(x, y))
                << "tick " << tick << ": robots " << a << " and " << b << " on " << x << " and " << y;
          }
        }
      }
    }
  };
  auto drive = [&](int ticks, int& tick) {
    for (int t = 0; t < ticks; ++t, ++tick) {
      for (std::size_t r = 0; r < robots; ++r) {
        if (target[r] != kNoNode) {
          if (--left[r] == 0) {
            at[r] = target[r];
            target[r] = kNoNode;
            ASSERT_EQ(ex.reached(r, at[r]), Report::Accepted);
          }
          continue;
        }
        if (rng() % 3 == 0)
          continue;  // late
        // Robots waiting on late ones sometimes go first (switchable dependencies).
        if (passes != nullptr && !ex.waitingOn(r).empty() && rng() % 2 == 0 &&
            ex.letPass(r, 1 + static_cast<std::int64_t>(rng() % 3)))
          ++*passes;
        const auto rel = ex.release(r);
        ASSERT_EQ(rel.base.front(), at[r]);
        if (rel.base.size() > 1) {
          target[r] = rel.base[1];
          left[r] = 1 + static_cast<int>(rng() % 4);
        }
      }
      checkApart(tick);
    }
  };
  int tick = 0;
  planSteps(40);
  drive(60, tick);
  pos = ex.truncateToReleased();
  planSteps(40);
  // Drive until every robot has reached the end of its route.
  for (int round = 0; round < 400; ++round) {
    bool done = true;
    for (std::size_t r = 0; r < robots; ++r)
      done = done && ex.pendingNodes(r) == 0 && target[r] == kNoNode;
    if (done)
      return;
    drive(1, tick);
  }
  for (std::size_t r = 0; r < robots; ++r) {
    ADD_FAILURE() << "robot " << r << " stuck with " << ex.pendingNodes(r) << " nodes to go, waiting on "
                  << ex.waitingOn(r).size() << " robots";
  }
}

TEST(Execution, RandomPlansLateRobotsNeverMeetNorDeadlockOnAGrid) {
  for (std::uint32_t seed = 1; seed <= 25; ++seed) {
    SCOPED_TRACE(seed);
    randomExecution(0, seed);
  }
}

TEST(Execution, RandomPlansLateRobotsNeverMeetNorDeadlockWithFootprints) {
  for (std::uint32_t seed = 1; seed <= 25; ++seed) {
    SCOPED_TRACE(seed);
    randomExecution(1, seed);
  }
}

TEST(Execution, RandomPlansWithRobotsLetPastLateOnesNeverMeetNorDeadlock) {
  int grid = 0, footprints = 0;
  for (std::uint32_t seed = 1; seed <= 25; ++seed) {
    SCOPED_TRACE(seed);
    randomExecution(0, seed, &grid);
    randomExecution(1, seed, &footprints);
  }
  // The orders were switched often enough for the checks above to mean something.
  EXPECT_GT(grid, 40);
  EXPECT_GT(footprints, 8);
  std::cout << "robots let past late ones: " << grid << " on the grid, " << footprints
            << " with footprints\n";
}

/// Robot 0 crosses a junction from the left, planned first; robot 1 comes down through it after.
Execution crossing(const Graph& g) {
  // Row y = 1 is nodes 5..9; node 2 is (2, 0), node 7 the junction (2, 1), node 12 is (2, 2).
  Execution ex(g, std::vector<NodeId>{5, 2});
  ex.append(std::vector<NodeId>{6, 2});
  ex.append(std::vector<NodeId>{7, 2});
  ex.append(std::vector<NodeId>{8, 7});  // robot 1 enters what robot 0 leaves
  ex.append(std::vector<NodeId>{9, 12});
  return ex;
}

TEST(Execution, ARobotWaitingOnALateOneGoesFirstAndTheLateOneThenWaits) {
  const Graph g = grid(5, 3);
  Execution ex = crossing(g);
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{2}));
  EXPECT_EQ(ex.waitingOn(1), (std::vector<std::size_t>{0}));
  // Robot 0 has not moved: it is 3 nodes short of what robot 1 waits for.
  EXPECT_FALSE(ex.letPass(1, 4));
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{2}));
  ASSERT_TRUE(ex.letPass(1, 3));
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{2, 7, 12}));
  // Robot 0 may drive up to the junction and waits there until robot 1 is through.
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{5, 6}));
  EXPECT_EQ(ex.waitingOn(0), (std::vector<std::size_t>{1}));
  ASSERT_EQ(ex.reached(1, 7), Report::Accepted);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{5, 6}));
  ASSERT_EQ(ex.reached(1, 12), Report::Accepted);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{5, 6, 7}));
  EXPECT_TRUE(ex.waitingOn(0).empty());
}

TEST(Execution, NoRobotGoesFirstWhereTheLateOneIsAlreadyReleased) {
  const Graph g = grid(5, 3);
  Execution ex = crossing(g);
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{5, 6, 7}));  // 1.5 m: into the junction
  EXPECT_FALSE(ex.letPass(1, 1));
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{2}));
  EXPECT_EQ(ex.waitingOn(1), (std::vector<std::size_t>{0}));
}

TEST(Execution, NoRobotGoesFirstWhereThatWouldDeadlock) {
  // A corridor: robot 1 follows robot 0 east; robot 1 cannot pass robot 0, which stands ahead of it.
  const Graph g = grid(6, 1);
  Execution ex(g, std::vector<NodeId>{1, 0});
  ex.append(std::vector<NodeId>{2, 1});
  ex.append(std::vector<NodeId>{3, 2});
  ex.append(std::vector<NodeId>{4, 3});
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0}));
  EXPECT_FALSE(ex.letPass(1, 1));  // robot 1's route runs through robot 0's node
  EXPECT_EQ(ex.release(1).base, (std::vector<NodeId>{0}));
  EXPECT_EQ(ex.release(0).base, (std::vector<NodeId>{1, 2, 3}));
}

}  // namespace
}  // namespace fleet::traffic
