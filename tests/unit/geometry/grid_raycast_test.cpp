#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fleet/core/angles.hpp"
#include "fleet/geometry/grid_raycast.hpp"

using namespace fleet;
using namespace fleet::geometry;

TEST(GridRaycast, StraightRays) {
  // 5x3 grid, a wall at column 3.
  std::vector<std::uint8_t> cells(15, 0);
  for (int y = 0; y < 3; ++y) {
    cells[static_cast<std::size_t>(y * 5 + 3)] = 1;
  }
  const GridView g{5, 3, 0.5, {-1.0, 0.0}, cells};
  const auto h = raycastGrid(g, {-0.75, 0.25}, 0.0, 10.0);  // cell (0,0) centre, wall starts at x = 0.5
  EXPECT_TRUE(h.hit);
  EXPECT_NEAR(h.range, 1.25, 1e-12);
  EXPECT_EQ(h.cx, 3);
  const auto m = raycastGrid(g, {-0.75, 0.25}, 0.0, 1.0);
  EXPECT_FALSE(m.hit);
  EXPECT_DOUBLE_EQ(m.range, 1.0);
  const auto out = raycastGrid(g, {-0.75, 0.25}, kPi, 10.0);  // leaves the grid at x = -1
  EXPECT_TRUE(out.hit);
  EXPECT_NEAR(out.range, 0.25, 1e-12);
}

TEST(GridRaycast, MatchesFineMarching) {
  std::mt19937 rng(4);
  const int w = 40, h = 30;
  std::vector<std::uint8_t> cells(w * h);
  std::bernoulli_distribution occ(0.12);
  for (auto& c : cells) {
    c = occ(rng) ? 1 : 0;
  }
  const GridView g{w, h, 0.25, {-3.0, 2.0}, cells};
  std::uniform_real_distribution<double> ux(-3.0, -3.0 + w * 0.25), uy(2.0, 2.0 + h * 0.25), ua(-kPi, kPi);
  int checked = 0;
  while (checked < 500) {
    const Vec2 o{ux(rng), uy(rng)};
    const auto cell = [&](Vec2 p) {
      return std::pair{static_cast<int>(std::floor((p.x + 3.0) / 0.25)),
                       static_cast<int>(std::floor((p.y - 2.0) / 0.25))};
    };
    if (g.blocked(cell(o).first, cell(o).second)) {
      continue;
    }
    const double a = ua(rng);
    const Vec2 d{std::cos(a), std::sin(a)};
    const auto hit = raycastGrid(g, o, a, 5.0);
    double t = 0.0;
    const double step = 1e-4;
    while (t < 5.0) {
      const auto [cx, cy] = cell(o + d * (t + step));
      if (g.blocked(cx, cy)) {
        break;
      }
      t += step;
    }
    if (t >= 5.0) {
      EXPECT_FALSE(hit.hit);
    } else {
      EXPECT_TRUE(hit.hit);
      EXPECT_NEAR(hit.range, t, 2 * step);
    }
    ++checked;
  }
}
