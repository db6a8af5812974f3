// Matching scan lines to the map's walls: the Mahalanobis gate, the end-point test of eq. 3.28, the
// side a wall is seen from, ambiguity, and a reason for every line left unmatched.

#include "fleet/estimation/line_matching.hpp"

#include <gtest/gtest.h>

#include <cmath>

#include "fleet/core/angles.hpp"

using namespace fleet;
using namespace fleet::estimation;

namespace {

Eigen::Matrix3d cov(double sxy, double sth) {
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  P.diagonal() << sxy * sxy, sxy * sxy, sth * sth;
  return P;
}

/// The line a robot at `pose` sees of the map line through a–b, with end points `from`..`to` along it
/// (map frame), as the extractor reports it (robot frame).
ExtractedLine seen(const Pose2& pose, const MapSegment& wall, Vec2 from, Vec2 to, double dr = 0.0,
                   double dpsi = 0.0) {
  const LinePrediction p = predictLine(pose, lineOf(wall));
  ExtractedLine l;
  l.line = {p.r + dr, wrapAngle(p.psi + dpsi), 1e-4, 1e-4, 0.0};
  l.first = pose.inverse().transform(from);
  l.last = pose.inverse().transform(to);
  l.points = 10;
  return l;
}

// A wall along y = 2 from x = 0 to 4, seen from below; its back (y = 3, seen from above); and a
// second wall along y = 2 from x = 6 to 9 (same line, another shelf).
const MapSegment kFront{{0, 2}, {4, 2}, {0, -1}};
const MapSegment kBack{{0, 3}, {4, 3}, {0, 1}};
const MapSegment kNextInRow{{6, 2}, {9, 2}, {0, -1}};

}  // namespace

TEST(LineMatching, SegmentLineIsTheFaceLineInRhoBetaForm) {
  const MapLine l = lineOf(kFront);
  EXPECT_NEAR(l.rho, 2.0, 1e-12);
  EXPECT_NEAR(l.beta, kPi / 2, 1e-12) << "ρ >= 0: the normal flips towards the foot of the perpendicular";
  const MapLine m = lineOf({{-1, -3}, {-1, 3}, {1, 0}});
  EXPECT_NEAR(m.rho, 1.0, 1e-12);
  EXPECT_NEAR(std::abs(m.beta), kPi, 1e-12);
}

TEST(LineMatching, AWallSeenWhereTheEstimateExpectsItMatches) {
  const Pose2 pose{2.0, 0.5, 0.3};
  const std::vector<MapSegment> map{kFront, kBack};
  const std::vector<ExtractedLine> obs{seen(pose, kFront, {1.0, 2.0}, {3.0, 2.0}, 0.01, 0.005)};
  const auto m = matchLines(pose, cov(0.05, 0.02), map, obs);
  ASSERT_EQ(m.matches.size(), 1u);
  EXPECT_EQ(m.matches[0].segment, 0u) << "the front face, not its back";
  EXPECT_LT(m.matches[0].d2, 1.0);
}

TEST(LineMatching, TheGateIsMahalanobisAndWidensWithTheEstimatesUncertainty) {
  const Pose2 pose{2.0, 0.5, 0.0};
  const std::vector<MapSegment> map{kFront};
  // 0.3 m further than predicted: far outside the gate for a 2 cm estimate, inside for a 0.3 m one.
  const std::vector<ExtractedLine> obs{seen(pose, kFront, {1.0, 2.3}, {3.0, 2.3}, 0.3)};
  const auto tight = matchLines(pose, cov(0.02, 0.01), map, obs);
  EXPECT_TRUE(tight.matches.empty());
  EXPECT_EQ(tight.outsideGate, 1u);
  const auto loose = matchLines(pose, cov(0.3, 0.01), map, obs);
  EXPECT_EQ(loose.matches.size(), 1u);
  // χ²(2): d² = 0.09 / (0.02² + 1e-4) = 180 against 13.82; a 4 cm miss (d² = 3.2) passes.
  const std::vector<ExtractedLine> near{seen(pose, kFront, {1.0, 2.04}, {3.0, 2.04}, 0.04)};
  EXPECT_EQ(matchLines(pose, cov(0.02, 0.01), map, near).matches.size(), 1u);
  LineGate strict;
  strict.mahalanobis = 2.0;
  EXPECT_EQ(matchLines(pose, cov(0.02, 0.01), map, near, strict).outsideGate, 1u);
  // The heading: a line turned by 0.2 rad is no match at σθ = 0.01.
  const std::vector<ExtractedLine> turned{seen(pose, kFront, {1.0, 2.0}, {3.0, 2.0}, 0.0, 0.2)};
  EXPECT_EQ(matchLines(pose, cov(0.02, 0.01), map, turned).outsideGate, 1u);
}

TEST(LineMatching, EndPointsOffTheWallFailTheOverlapTest) {
  const Pose2 pose{5.0, 0.5, 0.0};
  const std::vector<MapSegment> map{kFront};
  // On the wall's line but in the gap between shelves (x 4.5..5.5): the line is right, the place is not.
  const std::vector<ExtractedLine> gap{seen(pose, kFront, {4.5, 2.0}, {5.5, 2.0})};
  const auto m = matchLines(pose, cov(0.02, 0.01), map, gap);
  EXPECT_TRUE(m.matches.empty());
  EXPECT_EQ(m.noOverlap, 1u);
  // Sticking out 0.1 m past the end: inside T = 0.3 (2 × 0.1 < 0.3 + 6σ).
  const std::vector<ExtractedLine> over{seen(pose, kFront, {3.0, 2.0}, {4.1, 2.0})};
  EXPECT_EQ(matchLines(pose, cov(0.02, 0.01), map, over).matches.size(), 1u);
  // With the next shelf in the row on the same line, the observation in its extent matches it.
  const std::vector<MapSegment> row{kFront, kNextInRow};
  const std::vector<ExtractedLine> next{seen(pose, kFront, {6.5, 2.0}, {8.0, 2.0})};
  const auto r = matchLines(pose, cov(0.02, 0.01), row, next);
  ASSERT_EQ(r.matches.size(), 1u);
  EXPECT_EQ(r.matches[0].segment, 1u);
}

TEST(LineMatching, OnlyWallsFacingTheRobotAreCandidates) {
  const Pose2 pose{2.0, 4.0, 0.0};  // above the shelf: sees its back (y = 3) from 1 m
  const std::vector<MapSegment> map{kFront};
  const std::vector<ExtractedLine> obs{seen(pose, kBack, {1.0, 3.0}, {3.0, 3.0})};
  const auto m = matchLines(pose, cov(1.0, 0.01), map, obs);
  EXPECT_TRUE(m.matches.empty()) << "the front face's line is in the gate at σ = 1 m, but it looks away";
  EXPECT_EQ(m.noWallFacing, 1u);
}

TEST(LineMatching, WallsOutOfRangeAreNotLookedAt) {
  const Pose2 pose{2.0, 0.5, 0.0};
  const std::vector<MapSegment> map{kFront};  // 1.5 m away
  const std::vector<ExtractedLine> obs{seen(pose, kFront, {1.0, 2.0}, {3.0, 2.0})};
  LineGate g;
  g.maxRange = 2.0;
  EXPECT_EQ(matchLines(pose, cov(0.02, 0.01), map, obs, g).matches.size(), 1u);
  g.maxRange = 1.0;
  EXPECT_EQ(matchLines(pose, cov(0.02, 0.01), map, obs, g).noWallFacing, 1u);
  // Distance to the segment, not to its line: the same wall 3 m to the side is out of a 2 m range.
  const Pose2 aside{7.5, 1.0, 0.0};
  g.maxRange = 2.0;
  EXPECT_EQ(matchLines(aside, cov(0.02, 0.01), map, obs, g).noWallFacing, 1u);
}

TEST(LineMatching, TwoDifferentWallsInTheGateAreAmbiguousAndSkipped) {
  // Two parallel faces 0.4 m apart, both facing the robot, and an estimate too loose to tell.
  const MapSegment nearWall{{0, 2}, {4, 2}, {0, -1}};
  const MapSegment farWall{{0, 2.4}, {4, 2.4}, {0, -1}};
  const Pose2 pose{2.0, 0.5, 0.0};
  const std::vector<MapSegment> map{nearWall, farWall};
  const std::vector<ExtractedLine> obs{seen(pose, nearWall, {1.0, 2.35}, {3.0, 2.35}, 0.35)};
  const auto loose = matchLines(pose, cov(0.3, 0.01), map, obs);
  EXPECT_TRUE(loose.matches.empty());
  EXPECT_EQ(loose.ambiguous, 1u);
  const auto tight = matchLines(pose, cov(0.05, 0.01), map, obs);
  ASSERT_EQ(tight.matches.size(), 1u) << "a tight estimate tells them apart";
  EXPECT_EQ(tight.matches[0].segment, 1u)
      << "0.35 m further: the far wall (5 cm off) rather than the near one";
  // Collinear walls (the same line) are no ambiguity.
  const std::vector<MapSegment> row{kFront, {{3.0, 2.0}, {9.0, 2.0}, {0, -1}}};
  EXPECT_EQ(matchLines(pose, cov(0.3, 0.01), row, obs).ambiguous, 0u);
}

TEST(LineMatching, EveryLineGetsOneOutcomeAndAnEmptyMapMatchesNothing) {
  const Pose2 pose{2.0, 0.5, 0.0};
  const std::vector<MapSegment> map{kFront};
  std::vector<ExtractedLine> obs{seen(pose, kFront, {1.0, 2.0}, {3.0, 2.0}),
                                 seen(pose, kFront, {1.0, 2.0}, {3.0, 2.0}, 1.0),
                                 seen(pose, kFront, {5.5, 2.0}, {7.0, 2.0})};
  const auto m = matchLines(pose, cov(0.02, 0.01), map, obs);
  EXPECT_EQ(m.matches.size() + m.outsideGate + m.noOverlap + m.ambiguous + m.noWallFacing, obs.size());
  EXPECT_EQ(m.matches.size(), 1u);
  EXPECT_EQ(m.outsideGate, 1u);
  EXPECT_EQ(m.noOverlap, 1u);
  const auto none = matchLines(pose, cov(0.02, 0.01), {}, obs);
  EXPECT_EQ(none.noWallFacing, 3u);
  EXPECT_TRUE(matchLines(pose, cov(0.02, 0.01), map, {}).matches.empty());
}
