// The site's walls as maximal straight faces (the localizer's line map).

#include "fleet/site/wall_segments.hpp"

#include <gtest/gtest.h>

#include <algorithm>

namespace fleet::site {
namespace {

bool has(const std::vector<WallSegment>& walls, Vec2 a, Vec2 b, Vec2 n) {
  return std::any_of(walls.begin(), walls.end(), [&](const WallSegment& w) {
    return distance(w.a, a) < 1e-9 && distance(w.b, b) < 1e-9 && distance(w.normal, n) < 1e-9;
  });
}

TEST(WallSegments, ABoxInAnOpenRoomGivesItsFourFacesLookingOut) {
  // 10 × 8 cells of 0.5 m at origin (-1, 2); a 3 × 2-cell box at cells x 2..4, y 3..4.
  planning::OccupancyGrid g(10, 8, 0.5, {-1.0, 2.0});
  for (int x = 2; x <= 4; ++x) {
    for (int y = 3; y <= 4; ++y) {
      g.setBlocked({x, y});
    }
  }
  const auto walls = wallSegments(g);
  // The box: x from 0 to 1.5, y from 3.5 to 4.5, each face one merged segment.
  EXPECT_TRUE(has(walls, {0.0, 3.5}, {1.5, 3.5}, {0, -1})) << "bottom face, looking down";
  EXPECT_TRUE(has(walls, {0.0, 4.5}, {1.5, 4.5}, {0, 1})) << "top face";
  EXPECT_TRUE(has(walls, {0.0, 3.5}, {0.0, 4.5}, {-1, 0})) << "left face";
  EXPECT_TRUE(has(walls, {1.5, 3.5}, {1.5, 4.5}, {1, 0})) << "right face";
  // The grid's edge counts as blocked (OccupancyGrid::blocked): the room's four sides look in.
  EXPECT_TRUE(has(walls, {-1.0, 2.0}, {4.0, 2.0}, {0, 1}));
  EXPECT_TRUE(has(walls, {-1.0, 6.0}, {4.0, 6.0}, {0, -1}));
  EXPECT_TRUE(has(walls, {-1.0, 2.0}, {-1.0, 6.0}, {1, 0}));
  EXPECT_TRUE(has(walls, {4.0, 2.0}, {4.0, 6.0}, {-1, 0}));
  EXPECT_EQ(walls.size(), 8u);
}

TEST(WallSegments, FacesSplitWhereTheyTurnOrStopButNotAlongAStraightRun) {
  // An L of blocked cells on a 6 × 6 map with a border wall: the L's long edge is one face, the
  // step in it starts a new one.
  planning::OccupancyGrid g(6, 6, 1.0);
  for (int i = 0; i < 6; ++i) {
    g.setBlocked({i, 0});
    g.setBlocked({i, 5});
    g.setBlocked({0, i});
    g.setBlocked({5, i});
  }
  g.setBlocked({2, 2});
  g.setBlocked({3, 2});
  g.setBlocked({2, 3});
  const auto walls = wallSegments(g);
  EXPECT_TRUE(has(walls, {2, 2}, {4, 2}, {0, -1})) << "the L's bottom, two cells, one face";
  EXPECT_TRUE(has(walls, {3, 3}, {4, 3}, {0, 1})) << "the step's top";
  EXPECT_TRUE(has(walls, {2, 4}, {3, 4}, {0, 1})) << "the upright's top";
  EXPECT_TRUE(has(walls, {1, 1}, {5, 1}, {0, 1})) << "the border's inner face, merged over 4 cells";
  for (const auto& w : walls) {
    EXPECT_NEAR(w.normal.norm(), 1.0, 1e-12);
    EXPECT_TRUE(w.a.x == w.b.x || w.a.y == w.b.y) << "axis-aligned";
  }
  // Border (4 faces) + the L's outline of 6 faces.
  EXPECT_EQ(walls.size(), 10u);
  const auto longOnes = wallSegments(g, 1.5);
  EXPECT_EQ(longOnes.size(), 6u) << "the border's 4 faces, the L's bottom and its left side are >= 1.5 m";
}

TEST(WallSegments, TwoBoxesInARowAreTwoFacesAndFreeMapsHaveOnlyTheirEdge) {
  planning::OccupancyGrid g(9, 3, 1.0);
  g.setBlocked({1, 1});
  g.setBlocked({2, 1});
  g.setBlocked({6, 1});
  const auto walls = wallSegments(g);
  EXPECT_TRUE(has(walls, {1, 2}, {3, 2}, {0, 1}));
  EXPECT_TRUE(has(walls, {6, 2}, {7, 2}, {0, 1})) << "a gap between boxes ends a face";
  planning::OccupancyGrid empty(4, 4, 1.0);
  EXPECT_EQ(wallSegments(empty).size(), 4u);
}

}  // namespace
}  // namespace fleet::site
