// Shortest distances for a disc on the free map: Euclidean where the way is clear (not the grid's
// octile length), round what the disc does not fit through, and errors for places it cannot be.

#include "fleet/site/disc_distance.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

namespace fleet::site {
namespace {

using planning::OccupancyGrid;

TEST(DiscDistance, AClearDiagonalIsItsEuclideanLengthNotTheOctileOne) {
  OccupancyGrid g(30, 20, 0.5);  // 15 m x 10 m, nothing in it
  DiscDistance d(g, 0.3);
  const auto len = d.length({1.0, 1.0}, {11.0, 6.0});
  ASSERT_TRUE(len) << len.error().message;
  EXPECT_NEAR(*len, std::hypot(10.0, 5.0), 1e-9);  // octile: 5 * sqrt(2) + 5 = 12.07
  // The refined grid: 0.1 m cells of the 0.5 m map.
  EXPECT_EQ(d.grid().width(), 150);
  EXPECT_NEAR(d.grid().resolution(), 0.1, 1e-12);
}

/// A 10 m x 10 m hall of 0.5 m cells with the square block of cells [from, to) x [from, to).
OccupancyGrid hallWithBlock(int from, int to) {
  OccupancyGrid g(20, 20, 0.5);
  for (int y = from; y < to; ++y) {
    for (int x = from; x < to; ++x) {
      g.setBlocked({x, y});
    }
  }
  return g;
}

TEST(DiscDistance, BendsRoundABlockAtTheDiscsClearance) {
  // A 2 m x 2 m block in the middle of a 10 m x 10 m hall, between start and goal.
  const OccupancyGrid g = hallWithBlock(8, 12);
  DiscDistance d(g, 0.3);
  const auto len = d.length({1.0, 5.0}, {9.0, 5.0});
  ASSERT_TRUE(len) << len.error().message;
  // Round the block's lower corners, 0.3 m clear of them: about |(1,5)-(4,3.7)| + 2 + |(6,3.7)-(9,5)|.
  const double viaCorners = 2.0 * std::hypot(3.0, 1.3) + 2.0;
  EXPECT_GT(*len, 8.0);
  EXPECT_NEAR(*len, viaCorners, 0.1);
}

TEST(DiscDistance, PlacesTheDiscCannotBeAreErrors) {
  const OccupancyGrid g = hallWithBlock(4, 16);
  DiscDistance d(g, 0.3);
  const auto inside = d.length({5.0, 5.0}, {1.0, 1.0});
  ASSERT_FALSE(inside);
  EXPECT_EQ(inside.error().code, "no_room");
  EXPECT_NE(inside.error().message.find("(5.00, 5.00)"), std::string::npos) << inside.error().message;
  const auto off = d.length({1.0, 1.0}, {-3.0, 1.0});
  ASSERT_FALSE(off);
  EXPECT_EQ(off.error().code, "off_map");
  const auto nan = d.length({NAN, 1.0}, {1.0, 1.0});
  ASSERT_FALSE(nan);
  EXPECT_EQ(nan.error().code, "off_map");
  // Pressed against the block (0.1 m from it): joined to the nearest place the disc fits.
  const auto pressed = d.length({1.9, 3.0}, {1.0, 3.0});
  ASSERT_TRUE(pressed) << pressed.error().message;
  EXPECT_NEAR(*pressed, 0.9, 0.15);
  EXPECT_THROW(DiscDistance(g, -0.1), std::invalid_argument);
  EXPECT_THROW(DiscDistance(OccupancyGrid(), 0.3), std::invalid_argument);
}

}  // namespace
}  // namespace fleet::site
