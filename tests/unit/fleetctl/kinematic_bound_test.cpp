// The kinematic bound of a task: the disc's shortest way on the free map at cruise, plus dwell.

#include "kinematic_bound.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace fleet::ctl {
namespace {

using planning::OccupancyGrid;

/// A walled room of w x h cells at 0.5 m (the walls are its border cells).
OccupancyGrid room(int w, int h) {
  OccupancyGrid g(w, h, 0.5);
  for (int x = 0; x < w; ++x) {
    g.setBlocked({x, 0});
    g.setBlocked({x, h - 1});
  }
  for (int y = 0; y < h; ++y) {
    g.setBlocked({0, y});
    g.setBlocked({w - 1, y});
  }
  return g;
}

/// A wall across the room at x in [10, 10.5] m (column 20), open only where `open(y)` says.
template <class Open>
void wallAcross(OccupancyGrid& g, Open open) {
  for (int y = 0; y < g.height(); ++y) {
    if (!open(y)) {
      g.setBlocked({20, y});
    }
  }
}

KinematicBound only(const OccupancyGrid& g, const BoundTask& t) {
  auto r = kinematicBounds(g, {t});
  EXPECT_EQ(r.size(), 1u);
  EXPECT_TRUE(r.at(0)) << r.at(0).error().code << ": " << r.at(0).error().message;
  return r.at(0) ? *r.at(0) : KinematicBound{};
}

TEST(KinematicBound, StraightCorridorIsItsLengthAtCruisePlusDwell) {
  // 20 m x 3 m, free from 0.5 to 19.5 along x: start, pickup and drop-off on one line.
  const OccupancyGrid g = room(40, 6);
  const BoundTask t{{1.5, 1.5}, {10.0, 1.5}, {18.5, 1.5}, 0.3, 0.8, 4.0};
  const KinematicBound b = only(g, t);
  EXPECT_NEAR(b.toPickupM, 8.5, 1e-9);
  EXPECT_NEAR(b.toDropoffM, 8.5, 1e-9);
  EXPECT_NEAR(b.driveS, 17.0 / 0.8, 1e-9);
  EXPECT_EQ(b.dwellS, 4.0);
  EXPECT_NEAR(b.seconds(), 17.0 / 0.8 + 4.0, 1e-9);
  // Twice the cruise, half the drive.
  BoundTask fast = t;
  fast.cruise = 1.6;
  EXPECT_NEAR(only(g, fast).driveS, 17.0 / 1.6, 1e-9);
}

TEST(KinematicBound, AnObstacleInTheWayMakesItLonger) {
  // 20 m x 10 m; a wall at x = 10..10.5 m from the floor up to 7 m leaves a way round above it.
  OccupancyGrid g = room(40, 20);
  const BoundTask t{{2.0, 2.0}, {18.0, 2.0}, {18.0, 2.5}, 0.3, 0.8, 0.0};
  const double open = only(g, t).toPickupM;
  EXPECT_NEAR(open, 16.0, 1e-9);
  wallAcross(g, [](int y) { return y >= 14; });
  const double round = only(g, t).toPickupM;
  // Taut round the wall's end, 0.3 m clear of it: about |(2,2)-(10,7.3)| + 0.5 + |(10.5,7.3)-(18,2)|.
  const double expected = std::hypot(8.0, 5.3) + 0.5 + std::hypot(7.5, 5.3);
  EXPECT_GT(round, open + 3.0);
  EXPECT_NEAR(round, expected, 0.15);
}

TEST(KinematicBound, ARobotThatDoesNotFitAGapTakesTheWayRound) {
  // The wall has a 0.5 m gap at y = 4.5..5 m (row 9) and a 1 m opening at y = 8.5..9.5 m (rows 17-18).
  OccupancyGrid g = room(40, 20);
  wallAcross(g, [](int y) { return y == 9 || y == 17 || y == 18; });
  BoundTask t{{2.0, 4.75}, {18.0, 4.75}, {18.0, 5.0}, 0.2, 0.8, 0.0};
  const double small = only(g, t).toPickupM;
  EXPECT_NEAR(small, 16.0, 0.05) << "a 0.4 m disc goes through the 0.5 m gap";
  t.radius = 0.3;
  const double large = only(g, t).toPickupM;
  // Up through the opening, 0.3 m clear of its lower corners (10, 8.5) and (10.5, 8.5), and down again.
  EXPECT_GT(large, 17.5) << "a 0.6 m disc does not fit the gap";
  EXPECT_NEAR(large, std::hypot(8.0, 4.05) + 0.5 + std::hypot(7.5, 4.05), 0.15);
}

TEST(KinematicBound, AnUnreachableStationIsReportedNotCrashedOn) {
  // A pickup in a closed box (x 14..16.5 m, y 4..6.5 m): no way in for any disc.
  OccupancyGrid g = room(40, 20);
  for (int i = 28; i <= 32; ++i) {
    g.setBlocked({i, 8});
    g.setBlocked({i, 12});
    g.setBlocked({28, 8 + (i - 28)});
    g.setBlocked({32, 8 + (i - 28)});
  }
  const std::vector<BoundTask> tasks = {
      {{2.0, 2.0}, {15.25, 5.25}, {18.0, 2.0}, 0.3, 0.8, 4.0},  // pickup walled in
      {{2.0, 2.0}, {18.0, 2.0}, {15.25, 5.25}, 0.3, 0.8, 4.0},  // drop-off walled in
      {{2.0, 2.0}, {18.0, 2.0}, {18.0, 9.0}, 0.3, 0.8, 4.0},    // fine
      {{2.0, 2.0}, {18.0, 2.0}, {40.0, 2.0}, 0.3, 0.8, 4.0},    // drop-off off the map
      {{2.0, 2.0}, {18.0, 2.0}, {18.0, 9.0}, 0.3, 0.0, 4.0},    // no cruise
      {{2.0, 2.0}, {18.0, 2.0}, {18.0, 9.0}, 0.3, 0.8, NAN},    // no dwell
  };
  const auto r = kinematicBounds(g, tasks);
  ASSERT_EQ(r.size(), tasks.size());
  ASSERT_FALSE(r[0]);
  EXPECT_EQ(r[0].error().code, "unreachable");
  EXPECT_NE(r[0].error().message.find("to the pickup"), std::string::npos) << r[0].error().message;
  ASSERT_FALSE(r[1]);
  EXPECT_EQ(r[1].error().code, "unreachable");
  EXPECT_NE(r[1].error().message.find("pickup to drop-off"), std::string::npos) << r[1].error().message;
  ASSERT_TRUE(r[2]) << r[2].error().message;
  EXPECT_NEAR(r[2]->toPickupM, 16.0, 1e-9);
  ASSERT_FALSE(r[3]);
  EXPECT_EQ(r[3].error().code, "off_map");
  ASSERT_FALSE(r[4]);
  EXPECT_EQ(r[4].error().code, "bad_task");
  ASSERT_FALSE(r[5]);
  EXPECT_EQ(r[5].error().code, "bad_task");
  // An empty map bounds nothing, and says so.
  const auto none = kinematicBounds(OccupancyGrid(), {tasks[2]});
  ASSERT_FALSE(none.at(0));
  EXPECT_EQ(none.at(0).error().code, "bad_task");
}

TEST(KinematicBound, FleetFiguresAgainstTheBound) {
  // Two tasks of 60 and 100 s against bounds of 40 s: 2x the bound.
  const BoundFigures f = boundFigures({60.0, 100.0}, {40.0, 40.0});
  EXPECT_EQ(f.tasks, 2u);
  EXPECT_DOUBLE_EQ(f.meanTaskS, 80.0);
  EXPECT_DOUBLE_EQ(f.meanBoundS, 40.0);
  EXPECT_DOUBLE_EQ(f.timeOverBound, 2.0);
  const BoundFigures empty = boundFigures({}, {});
  EXPECT_EQ(empty.tasks, 0u);
  EXPECT_EQ(empty.timeOverBound, 0.0);
}

}  // namespace
}  // namespace fleet::ctl
