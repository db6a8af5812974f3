#include "fleet/geometry/polygon.hpp"

#include <gtest/gtest.h>

#include <vector>

namespace fleet::geometry {
namespace {

TEST(InsidePolygon, SquareEitherOrientation) {
  std::vector<Vec2> sq{{0, 0}, {2, 0}, {2, 2}, {0, 2}};
  EXPECT_TRUE(insidePolygon({1, 1}, sq));
  EXPECT_FALSE(insidePolygon({3, 1}, sq));
  EXPECT_FALSE(insidePolygon({1, -0.5}, sq));
  std::vector<Vec2> cw(sq.rbegin(), sq.rend());
  EXPECT_TRUE(insidePolygon({1, 1}, cw));
  EXPECT_FALSE(insidePolygon({-1, 1}, cw));
}

TEST(InsidePolygon, ConcaveByTheEvenOddRule) {
  // A "U": the notch between the arms is outside.
  std::vector<Vec2> u{{0, 0}, {3, 0}, {3, 3}, {2, 3}, {2, 1}, {1, 1}, {1, 3}, {0, 3}};
  EXPECT_TRUE(insidePolygon({0.5, 2}, u));
  EXPECT_TRUE(insidePolygon({2.5, 2}, u));
  EXPECT_TRUE(insidePolygon({1.5, 0.5}, u));
  EXPECT_FALSE(insidePolygon({1.5, 2}, u));
}

TEST(InsidePolygon, FewerThanThreeCornersContainNothing) {
  EXPECT_FALSE(insidePolygon({0, 0}, std::vector<Vec2>{}));
  EXPECT_FALSE(insidePolygon({0, 0}, std::vector<Vec2>{{0, 0}}));
  EXPECT_FALSE(insidePolygon({0.5, 0}, std::vector<Vec2>{{0, 0}, {1, 0}}));
}

TEST(InsidePolygon, HorizontalEdgesAndVerticesCountOnce) {
  // The ray from the point runs through a vertex and along a horizontal edge.
  std::vector<Vec2> tri{{0, 0}, {4, 0}, {2, 2}};
  EXPECT_TRUE(insidePolygon({2, 1}, tri));
  EXPECT_FALSE(insidePolygon({-1, 0}, tri));
  EXPECT_FALSE(insidePolygon({0, 2}, tri));
}

}  // namespace
}  // namespace fleet::geometry
