#include "fleet/fleet/allocator.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>
#include <set>

namespace fleet {
namespace {

constexpr std::int64_t kSec = 1'000'000'000;

/// Exhaustive reference: over every injective map of the smaller side, the most finite pairs,
/// then the least total cost.
std::pair<std::size_t, double> bruteForce(const CostMatrix& c) {
  const bool rowsSmall = c.rows <= c.cols;
  const std::size_t k = rowsSmall ? c.rows : c.cols;
  const std::size_t big = rowsSmall ? c.cols : c.rows;
  std::vector<std::size_t> perm(big);
  std::iota(perm.begin(), perm.end(), std::size_t{0});
  std::pair<std::size_t, double> best{0, 0.0};
  // Every k-permutation appears as the prefix of some permutation of `big` elements.
  do {
    std::size_t n = 0;
    double sum = 0.0;
    for (std::size_t i = 0; i < k; ++i) {
      const double x = rowsSmall ? c.at(i, perm[i]) : c.at(perm[i], i);
      if (std::isfinite(x)) {
        ++n;
        sum += x;
      }
    }
    if (n > best.first || (n == best.first && sum < best.second)) {
      best = {n, sum};
    }
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

std::pair<std::size_t, double> evaluate(const CostMatrix& c, const std::vector<int>& rowToCol) {
  std::set<int> cols;
  std::pair<std::size_t, double> out{0, 0.0};
  for (std::size_t i = 0; i < rowToCol.size(); ++i) {
    if (rowToCol[i] < 0) {
      continue;
    }
    EXPECT_TRUE(cols.insert(rowToCol[i]).second) << "column used twice";
    const double x = c.at(i, static_cast<std::size_t>(rowToCol[i]));
    EXPECT_TRUE(std::isfinite(x)) << "forbidden pair chosen";
    ++out.first;
    out.second += x;
  }
  return out;
}

TEST(Hungarian, WorkedExample) {
  // The 3×3 example of every textbook: optimum 1→2, 2→1, 3→3 with cost 5 + 2 + 2... computed by hand:
  // rows {4,1,3},{2,0,5},{3,2,2}: best is (0,1)+(1,0)+(2,2) = 1+2+2 = 5.
  CostMatrix c(3, 3);
  c.v = {4, 1, 3, 2, 0, 5, 3, 2, 2};
  const auto s = solveHungarian(c);
  EXPECT_EQ(s, (std::vector<int>{1, 0, 2}));
  EXPECT_DOUBLE_EQ(evaluate(c, s).second, 5.0);
}

TEST(Hungarian, MatchesBruteForceOnRandomRectangularInstances) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> cost(-50.0, 100.0);
  for (int trial = 0; trial < 600; ++trial) {
    const std::size_t rows = 1 + rng() % 6;
    const std::size_t cols = 1 + rng() % 6;
    CostMatrix c(rows, cols);
    const double forbidShare = (trial % 3) * 0.25;
    for (auto& x : c.v) {
      x = std::uniform_real_distribution<double>(0, 1)(rng) < forbidShare ? kInfeasible
                                                                          : std::round(cost(rng));
    }
    const auto got = evaluate(c, solveHungarian(c));
    const auto want = bruteForce(c);
    ASSERT_EQ(got.first, want.first) << "trial " << trial;
    ASSERT_NEAR(got.second, want.second, 1e-9) << "trial " << trial;
  }
}

TEST(Hungarian, AllForbiddenOrEmpty) {
  CostMatrix none(3, 2, kInfeasible);
  EXPECT_EQ(solveHungarian(none), (std::vector<int>{-1, -1, -1}));
  EXPECT_TRUE(solveHungarian(CostMatrix(0, 4)).empty());
  EXPECT_EQ(solveHungarian(CostMatrix(2, 0)), (std::vector<int>{-1, -1}));
}

Task mkTask(std::string id, std::int32_t priority = 0, std::int64_t deadlineNs = 0,
            TaskKind kind = TaskKind::Transport, std::string robot = "") {
  Task t;
  t.id = std::move(id);
  t.priority = priority;
  t.deadlineNs = deadlineNs;
  t.kind = kind;
  t.robot = std::move(robot);
  return t;
}

RobotInfo mkRobot(std::string id, double x = 0.0, double battery = 1.0) {
  RobotInfo r;
  r.id = std::move(id);
  r.pose = {x, 0.0, 0.0};
  r.battery = battery;
  return r;
}

struct World {
  std::vector<Task> tasks;
  std::vector<RobotInfo> robots;
  std::vector<Pose2> taskPos;
  TravelCost travel() const {
    return [this](const RobotInfo& r, const Task& t) {
      const auto idx = static_cast<std::size_t>(std::stoi(t.id.substr(1)));
      return std::hypot(r.pose.x - taskPos[idx].x, r.pose.y - taskPos[idx].y);
    };
  }
};

World randomWorld(std::mt19937& rng, std::size_t nt, std::size_t nr, double lowBatteryShare) {
  World w;
  std::uniform_real_distribution<double> pos(0.0, 100.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (std::size_t i = 0; i < nt; ++i) {
    Task t;
    t.id = "t";
    t.id += std::to_string(i);
    t.kind = u(rng) < 0.15 ? TaskKind::Charge : TaskKind::Transport;
    t.priority = static_cast<std::int32_t>(rng() % 3);
    t.deadlineNs = u(rng) < 0.5 ? static_cast<std::int64_t>((10.0 + 100.0 * u(rng)) * 1e9) : 0;
    if (u(rng) < 0.1) {
      t.robot = "r";
      t.robot += std::to_string(rng() % std::max<std::size_t>(nr, 1));
    }
    w.tasks.push_back(t);
    w.taskPos.push_back({pos(rng), pos(rng), 0.0});
  }
  for (std::size_t j = 0; j < nr; ++j) {
    RobotInfo r;
    r.id = "r";
    r.id += std::to_string(j);
    r.pose = {pos(rng), pos(rng), 0.0};
    r.battery = u(rng) < lowBatteryShare ? 0.1 : 0.9;
    w.robots.push_back(r);
  }
  return w;
}

void checkValid(const World& w, const std::vector<Assignment>& as, const AllocationPolicy& p) {
  std::set<std::size_t> tasks, robots;
  for (const auto& a : as) {
    ASSERT_LT(a.task, w.tasks.size());
    ASSERT_LT(a.robot, w.robots.size());
    EXPECT_TRUE(tasks.insert(a.task).second) << "task assigned twice";
    EXPECT_TRUE(robots.insert(a.robot).second) << "robot assigned twice";
    EXPECT_TRUE(eligible(w.robots[a.robot], w.tasks[a.task], p));
    if (w.robots[a.robot].battery < p.batteryThreshold) {
      EXPECT_EQ(w.tasks[a.task].kind, TaskKind::Charge) << "a low robot got a non-charge task";
    }
  }
}

TEST(Allocators, HungarianIsOptimalAndGreedyValidOnRandomWorlds) {
  std::mt19937 rng(11);
  const AllocationPolicy p;
  const HungarianAllocator hungarian(p);
  const GreedyAllocator greedy(p);
  int greedyWorse = 0;
  for (int trial = 0; trial < 300; ++trial) {
    const auto w = randomWorld(rng, 1 + rng() % 6, 1 + rng() % 6, 0.3);
    const auto c = effectiveCosts(w.tasks, w.robots, w.travel(), p, 5 * kSec);
    const auto h = hungarian.assign(w.tasks, w.robots, w.travel(), 5 * kSec);
    const auto g = greedy.assign(w.tasks, w.robots, w.travel(), 5 * kSec);
    checkValid(w, h, p);
    checkValid(w, g, p);
    auto objective = [&](const std::vector<Assignment>& as) {
      double s = 0.0;
      for (const auto& a : as) {
        s += c.at(a.task, a.robot);
      }
      return std::pair{as.size(), s};
    };
    const auto want = bruteForce(c);
    const auto got = objective(h);
    ASSERT_EQ(got.first, want.first) << trial;
    ASSERT_NEAR(got.second, want.second, 1e-6) << trial;
    const auto gg = objective(g);
    EXPECT_LE(gg.first, got.first);
    if (gg.first == got.first) {
      EXPECT_GE(gg.second, got.second - 1e-6) << "nothing beats the optimum";
      greedyWorse += gg.second > got.second + 1e-6 ? 1 : 0;
    }
  }
  EXPECT_GT(greedyWorse, 0) << "the instances should be hard enough to separate greedy from optimal";
}

TEST(Allocators, NoTaskOrRobotTwiceOnLargeInstances) {
  std::mt19937 rng(3);
  const AllocationPolicy p;
  for (auto [nt, nr] : {std::pair<std::size_t, std::size_t>{60, 90}, {90, 60}, {120, 120}}) {
    const auto w = randomWorld(rng, nt, nr, 0.2);
    checkValid(w, HungarianAllocator(p).assign(w.tasks, w.robots, w.travel(), 0), p);
    checkValid(w, GreedyAllocator(p).assign(w.tasks, w.robots, w.travel(), 0), p);
  }
}

TEST(Allocators, PriorityDecidesWhoIsServedWhenRobotsAreScarce) {
  World w;
  w.taskPos = {{1, 0, 0}, {50, 0, 0}};
  w.tasks = {mkTask("t0"), mkTask("t1", 1)};
  w.robots = {mkRobot("r0")};
  const HungarianAllocator h;
  const GreedyAllocator g;
  for (const Allocator* a : {static_cast<const Allocator*>(&h), static_cast<const Allocator*>(&g)}) {
    const auto as = a->assign(w.tasks, w.robots, w.travel(), 0);
    ASSERT_EQ(as.size(), 1u);
    EXPECT_EQ(as[0].task, 1u) << "one priority step (600 s) outweighs 49 m";
  }
  // Without the priority the near task wins.
  w.tasks[1].priority = 0;
  const auto as = HungarianAllocator().assign(w.tasks, w.robots, w.travel(), 0);
  ASSERT_EQ(as.size(), 1u);
  EXPECT_EQ(as[0].task, 0u);
}

// No task starves: with one robot and a stream of tasks nearer to it, a far task is served once its
// age outweighs the difference in travel (A = 1 s of travel per s waited), and not before.
TEST(Allocators, AnOldFarTaskIsServedOnceItsAgeOutweighsANewNearOne) {
  World w;
  w.taskPos = {{90, 0, 0}, {10, 0, 0}};
  w.tasks = {mkTask("t0"), mkTask("t1")};
  w.robots = {mkRobot("r0")};
  const HungarianAllocator h;
  // t0 waited 70 s, t1 is new: 90 - 70 > 10, the near one still wins.
  w.tasks[0].createdNs = 30 * kSec;
  w.tasks[1].createdNs = 100 * kSec;
  auto as = h.assign(w.tasks, w.robots, w.travel(), 100 * kSec);
  ASSERT_EQ(as.size(), 1u);
  EXPECT_EQ(as[0].task, 1u);
  // (The greedy allocator, for backlogs too large for the Hungarian method, serves the oldest first.)
  as = GreedyAllocator().assign(w.tasks, w.robots, w.travel(), 100 * kSec);
  ASSERT_EQ(as.size(), 1u);
  EXPECT_EQ(as[0].task, 0u);
  // t0 waited 90 s: 90 - 90 < 10, its turn.
  w.tasks[0].createdNs = 10 * kSec;
  as = h.assign(w.tasks, w.robots, w.travel(), 100 * kSec);
  ASSERT_EQ(as.size(), 1u);
  EXPECT_EQ(as[0].task, 0u);
  // Without the age term the far task would wait for ever behind near ones.
  AllocationPolicy p;
  p.ageWeight = 0.0;
  const auto c = effectiveCosts(w.tasks, w.robots, w.travel(), p, 100 * kSec);
  EXPECT_LT(c.at(1, 0), c.at(0, 0));
}

TEST(Allocators, DeadlinesPickTheUrgentTaskAndTheNearRobot) {
  World w;
  // Robot r0 at the origin; t1 has a deadline it only meets if served now.
  w.taskPos = {{10, 0, 0}, {30, 0, 0}};
  w.tasks = {mkTask("t0"), mkTask("t1", 0, 40 * kSec)};
  w.robots = {mkRobot("r0")};
  auto as = HungarianAllocator().assign(w.tasks, w.robots, w.travel(), 0);
  ASSERT_EQ(as.size(), 1u);
  EXPECT_EQ(as[0].task, 1u);
  EXPECT_DOUBLE_EQ(as[0].cost, 30.0) << "on time: no lateness";
  // Two robots: the deadline task gets the robot that makes it on time.
  w.taskPos = {{0, 0, 0}, {0, 0, 0}};
  w.tasks = {mkTask("t0"), mkTask("t1", 0, 20 * kSec)};
  w.robots = {mkRobot("near", 10), mkRobot("far", 25)};
  as = HungarianAllocator().assign(w.tasks, w.robots, w.travel(), 0);
  ASSERT_EQ(as.size(), 2u);
  for (const auto& a : as) {
    EXPECT_EQ(w.robots[a.robot].id, a.task == 1 ? "near" : "far");
  }
  // Hand-computed effective costs at now = 0, L = 10, H = 60:
  //   t1 skip = 10·max(0, 60 + 10 − 20) = 500; (near,t1) = 10 − 500; (far,t1) = 25 + 10·5 − 500.
  const auto c = effectiveCosts(w.tasks, w.robots, w.travel(), AllocationPolicy{}, 0);
  EXPECT_DOUBLE_EQ(c.at(1, 0), -490.0);
  EXPECT_DOUBLE_EQ(c.at(1, 1), -425.0);
  EXPECT_DOUBLE_EQ(c.at(0, 1), 25.0);
}

TEST(Allocators, BatteryAndPinningRules) {
  AllocationPolicy p;
  RobotInfo low = mkRobot("low", 0, 0.1);
  RobotInfo ok = mkRobot("ok", 0, 0.5);
  const Task transport = mkTask("t");
  const Task charge = mkTask("c", 0, 0, TaskKind::Charge);
  const Task pinned = mkTask("p", 0, 0, TaskKind::Goto, "ok");
  EXPECT_FALSE(eligible(low, transport, p));
  EXPECT_TRUE(eligible(low, charge, p));
  EXPECT_TRUE(eligible(ok, transport, p));
  EXPECT_TRUE(eligible(ok, pinned, p));
  EXPECT_FALSE(eligible(low, pinned, p));
  ok.taskId = "busy";
  EXPECT_FALSE(eligible(ok, charge, p));
  low.lost = true;
  EXPECT_FALSE(eligible(low, charge, p));
}

}  // namespace
}  // namespace fleet
