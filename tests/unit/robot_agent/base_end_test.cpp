// The end of a base in reserved traffic (base_end.hpp): drive on, drive onto the end, or stand.

#include "base_end.hpp"

#include "release_tracker.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace fleet;
using agent::BaseEnd;
using agent::baseEnd;

namespace {

Vec2 heading(double theta) {
  return {std::cos(theta), std::sin(theta)};
}

}  // namespace

TEST(BaseEnd, ProjectedOntoTheEndButBesideItTheRobotDrivesOntoIt) {
  // As r6 stood 1,400 s going home (full stack, seed 2): its way from (25.73, 4.865)
  // to node 258 at (26.25, 5.25), the local planner swerved east and the robot came at the node
  // from the side: at (26.34, 5.11) facing 1.50 rad, 0.011 m left by projection, 0.166 m from
  // The node (the release tracker's reach: 0.15 m). It stood and never reported the node.
  const Vec2 from{25.73, 4.865};
  const Vec2 end{26.25, 5.25};
  const Vec2 here{26.34, 5.11};
  const Vec2 way = (end - from) / (end - from).norm();
  const double left = (end - from).norm() - (here - from).dot(way);
  ASSERT_LT(left, 0.02);
  EXPECT_EQ(baseEnd(left, end - here, heading(1.50), true), BaseEnd::kSettle);
  // Facing away from it too (it turns on the spot first, which sweeps nothing for a disc).
  EXPECT_EQ(baseEnd(left, end - here, heading(1.50 + M_PI), true), BaseEnd::kSettle);
}

TEST(BaseEnd, ItSettlesOnlyWhereTheReleaseTrackerWouldNotCountTheNodeReached) {
  // Standing within settleBeyond of the end, the robot must be within the tracker's reach of it, or
  // it stands without reporting the node (the stand this decision is for).
  EXPECT_LT(agent::BaseEndParams{}.settleBeyond, agent::ReleaseParams{}.reachTolerance);
  EXPECT_LE(agent::BaseEndParams{}.behindWithin, agent::ReleaseParams{}.reachTolerance);
}

TEST(BaseEnd, OnTheEndOrJustBesideItTheRobotStands) {
  EXPECT_EQ(baseEnd(0.0, {0.0, 0.0}, heading(0.0), true), BaseEnd::kStand);
  EXPECT_EQ(baseEnd(0.01, {0.01, 0.08}, heading(0.0), true), BaseEnd::kStand);
}

TEST(BaseEnd, TheEndCloseBehindTheRobotIsReached) {
  // Within the reach tolerance and no longer ahead: turning round would sweep the body over what
  // was not released.
  EXPECT_EQ(baseEnd(0.05, {-0.12, 0.0}, heading(0.0), true), BaseEnd::kStand);
  // Not on the final approach (the carrot is not on the end yet): drive on.
  EXPECT_EQ(baseEnd(0.05, {-0.12, 0.0}, heading(0.0), false), BaseEnd::kDrive);
  // Ahead of it: drive on.
  EXPECT_EQ(baseEnd(0.12, {0.12, 0.0}, heading(0.0), true), BaseEnd::kDrive);
}

TEST(BaseEnd, ItSettlesExactlyWhereTheProjectionEndsAndTheEndIsFurtherThanTheSettleDistance) {
  // Property: with the projection at the end, the decision depends only on the distance to it,
  // never on the heading.
  const agent::BaseEndParams p;
  for (double d = 0.0; d < 0.5; d += 0.01) {
    for (double th = -M_PI; th < M_PI; th += 0.3) {
      const Vec2 to{d * std::cos(1.0), d * std::sin(1.0)};
      EXPECT_EQ(baseEnd(0.0, to, heading(th), true, p),
                d > p.settleBeyond ? BaseEnd::kSettle : BaseEnd::kStand)
          << d << " " << th;
    }
  }
}
