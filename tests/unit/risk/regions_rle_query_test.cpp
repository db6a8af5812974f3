#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fleet/risk/query.hpp"
#include "fleet/risk/regions.hpp"
#include "fleet/risk/rle.hpp"

namespace fleet::risk {
namespace {

LevelGrid randomLevels(std::mt19937_64& rng, int w, int h, int K, double fill) {
  LevelGrid g{GridSpec{-1.0, 2.0, 0.5, w, h}, K,
              std::vector<std::uint8_t>(static_cast<std::size_t>(w * h), 0)};
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> lv(1, K);
  for (auto& v : g.level) {
    v = u(rng) < fill ? static_cast<std::uint8_t>(lv(rng)) : 0;
  }
  return g;
}

TEST(Rle, RoundTripAndMaximalRuns) {
  std::mt19937_64 rng(3);
  for (int t = 0; t < 20; ++t) {
    const auto g = randomLevels(rng, 37, 23, 3, 0.5);
    const auto runs = encodeRle(g.level);
    for (std::size_t k = 1; k < runs.size(); ++k) {
      ASSERT_NE(runs[k].level, runs[k - 1].level);
    }
    const auto back = decodeRle(runs, g.level.size(), 3);
    ASSERT_TRUE(back.has_value());
    EXPECT_EQ(*back, g.level);
  }
  const std::vector<std::uint8_t> flat(1000, 0);
  EXPECT_EQ(encodeRle(flat), (std::vector<LevelRun>{{0, 1000}}));
  EXPECT_TRUE(encodeRle(std::vector<std::uint8_t>{}).empty());
}

// The encoder extends runs eight bytes at a time; compare with a cell-by-cell encoder on random rows
// of short and long runs (lengths not multiples of eight, runs ending at the array's end).
TEST(Rle, WordwiseEncoderMatchesCellByCell) {
  std::mt19937_64 rng(3);
  for (int t = 0; t < 3000; ++t) {
    std::vector<std::uint8_t> v(rng() % 200);
    const std::uint64_t change = t % 3 == 0 ? 2 : (t % 3 == 1 ? 10 : 40);
    std::uint8_t cur = 0;
    for (auto& x : v) {
      if (rng() % change == 0) {
        cur = static_cast<std::uint8_t>(rng() % 4);
      }
      x = cur;
    }
    std::vector<LevelRun> naive;
    for (std::uint8_t x : v) {
      if (!naive.empty() && naive.back().level == x) {
        ++naive.back().length;
      } else {
        naive.push_back(LevelRun{x, 1});
      }
    }
    ASSERT_EQ(encodeRle(v), naive) << "case " << t;
  }
}

TEST(Rle, DecodeRejectsMalformedRuns) {
  const std::vector<LevelRun> ok{{0, 5}, {2, 5}};
  EXPECT_TRUE(decodeRle(ok, 10, 2).has_value());
  EXPECT_EQ(decodeRle(ok, 11, 2).error().code, "rle_length_mismatch");
  EXPECT_EQ(decodeRle(ok, 9, 2).error().code, "rle_length_mismatch");
  EXPECT_EQ(decodeRle(ok, 10, 1).error().code, "rle_bad_level");
  const std::vector<LevelRun> zero{{0, 0}, {1, 10}};
  EXPECT_EQ(decodeRle(zero, 10, 2).error().code, "rle_zero_run");
  const std::vector<LevelRun> huge{{0, 0xffffffffu}, {0, 0xffffffffu}, {0, 0xffffffffu}};
  EXPECT_EQ(decodeRle(huge, 10, 2).error().code, "rle_length_mismatch");
}

TEST(Regions, SquareWithAHole) {
  // 5×5 block of level 2 with a level-0 centre cell: one region, outer square and one hole.
  LevelGrid g{GridSpec{0, 0, 1, 7, 7}, 3, std::vector<std::uint8_t>(49, 0)};
  for (int j = 1; j <= 5; ++j) {
    for (int i = 1; i <= 5; ++i) {
      g.level[g.spec.index(i, j)] = 2;
    }
  }
  g.level[g.spec.index(3, 3)] = 0;
  const auto regions = extractRegions(g);
  ASSERT_EQ(regions.size(), 1u);
  EXPECT_EQ(regions[0].level, 2);
  EXPECT_EQ(regions[0].cells, 24u);
  EXPECT_EQ(regions[0].outer.size(), 4u);  // corners only
  EXPECT_DOUBLE_EQ(signedArea(regions[0].outer), 25.0);
  ASSERT_EQ(regions[0].holes.size(), 1u);
  EXPECT_DOUBLE_EQ(signedArea(regions[0].holes[0]), -1.0);
  EXPECT_TRUE(regionContains(regions[0], {1.5, 1.5}));
  EXPECT_FALSE(regionContains(regions[0], {3.5, 3.5}));
  EXPECT_FALSE(regionContains(regions[0], {0.5, 0.5}));
}

TEST(Regions, DiagonalCellsAreSeparateRegions) {
  LevelGrid g{GridSpec{0, 0, 1, 2, 2}, 1, {1, 0, 0, 1}};
  const auto regions = extractRegions(g);
  ASSERT_EQ(regions.size(), 2u);
  for (const auto& r : regions) {
    EXPECT_EQ(r.cells, 1u);
    EXPECT_DOUBLE_EQ(signedArea(r.outer), 1.0);
    EXPECT_TRUE(r.holes.empty());
  }
}

TEST(Regions, RandomGridsPolygonsReproduceTheCells) {
  std::mt19937_64 rng(9);
  for (int t = 0; t < 30; ++t) {
    const auto g = randomLevels(rng, 31, 27, t % 2 == 0 ? 1 : 3, t % 3 == 0 ? 0.8 : 0.45);
    const auto regions = extractRegions(g);
    std::size_t cells = 0;
    std::vector<int> owner(g.level.size(), -1);
    for (std::size_t r = 0; r < regions.size(); ++r) {
      const auto& reg = regions[r];
      double area = signedArea(reg.outer);
      ASSERT_GT(area, 0.0);
      for (const auto& h : reg.holes) {
        ASSERT_LT(signedArea(h), 0.0);
        area += signedArea(h);
      }
      const double res2 = g.spec.resolution * g.spec.resolution;
      ASSERT_NEAR(area, static_cast<double>(reg.cells) * res2, 1e-9);
      cells += reg.cells;
      // Each region's polygon contains exactly its cells' centres, all of one level.
      for (int j = 0; j < g.spec.height; ++j) {
        for (int i = 0; i < g.spec.width; ++i) {
          if (regionContains(reg, {g.spec.cellCentreX(i), g.spec.cellCentreY(j)})) {
            const std::size_t idx = g.spec.index(i, j);
            ASSERT_EQ(g.level[idx], reg.level);
            ASSERT_EQ(owner[idx], -1) << "cell in two regions";
            owner[idx] = static_cast<int>(r);
          }
        }
      }
    }
    std::size_t nonzero = 0;
    for (std::size_t c = 0; c < g.level.size(); ++c) {
      nonzero += g.level[c] > 0 ? 1 : 0;
      ASSERT_EQ(owner[c] >= 0, g.level[c] > 0);
    }
    EXPECT_EQ(cells, nonzero);
  }
}

// Brute force: every cell whose square the segment crosses (slab test on the closed square).
double bruteSegmentMax(const ProbabilityGrid& g, Vec2 a, Vec2 b) {
  double best = -1.0;
  for (int j = 0; j < g.spec.height; ++j) {
    for (int i = 0; i < g.spec.width; ++i) {
      const double x0 = g.spec.originX + i * g.spec.resolution, x1 = x0 + g.spec.resolution;
      const double y0 = g.spec.originY + j * g.spec.resolution, y1 = y0 + g.spec.resolution;
      double t0 = 0, t1 = 1;
      const double d[2] = {b.x - a.x, b.y - a.y}, o[2] = {a.x, a.y}, lo[2] = {x0, y0}, hi[2] = {x1, y1};
      bool hit = true;
      for (int k = 0; k < 2 && hit; ++k) {
        if (d[k] == 0) {
          hit = o[k] >= lo[k] && o[k] <= hi[k];
        } else {
          double ta = (lo[k] - o[k]) / d[k], tb = (hi[k] - o[k]) / d[k];
          if (ta > tb)
            std::swap(ta, tb);
          t0 = std::max(t0, ta);
          t1 = std::min(t1, tb);
          hit = t0 <= t1;
        }
      }
      if (hit)
        best = std::max(best, g.p[g.spec.index(i, j)]);
    }
  }
  return best;
}

TEST(Query, SegmentMaxMatchesBruteForce) {
  std::mt19937_64 rng(21);
  ProbabilityGrid g{GridSpec{-2.0, -1.0, 0.25, 40, 30}, std::vector<double>(1200)};
  std::uniform_real_distribution<double> u(0.0, 1.0), ux(-4.0, 10.0), uy(-3.0, 8.0);
  for (int t = 0; t < 300; ++t) {
    for (auto& v : g.p)
      v = u(rng);
    const Vec2 a{ux(rng), uy(rng)}, b{ux(rng), uy(rng)};
    const auto got = maxRiskAlongSegment(g, a, b);
    const double want = bruteSegmentMax(g, a, b);
    if (want < 0) {
      EXPECT_FALSE(got.has_value());
    } else {
      ASSERT_TRUE(got.has_value());
      EXPECT_EQ(got->risk, want) << a.x << "," << a.y << " -> " << b.x << "," << b.y;
    }
  }
  // A zero-length segment is the point query.
  const auto p = maxRiskAlongSegment(g, {1.1, 1.1}, {1.1, 1.1});
  ASSERT_TRUE(p.has_value());
  EXPECT_EQ(p->risk, riskAt(g, {1.1, 1.1})->risk);
}

TEST(Query, PointAndLowestCell) {
  ProbabilityGrid g{GridSpec{0, 0, 1, 4, 3},
                    {0.9, 0.8, 0.7, 0.6,  //
                     0.5, 0.2, 0.4, 0.2,  //
                     0.3, 0.9, 0.9, 0.9}};
  auto r = riskAt(g, {1.5, 1.2});
  ASSERT_TRUE(r.has_value());
  EXPECT_EQ(r->risk, 0.2);
  EXPECT_EQ(r->i, 1);
  EXPECT_EQ(riskAt(g, {-0.1, 1}).error().code, "off_grid");
  EXPECT_EQ(riskAt(g, {4.0, 1}).error().code, "off_grid");
  // Two cells at 0.2; the window centred at (3.4, 1.5) prefers the nearer one, (3, 1).
  auto low = lowestRiskCell(g, {3.4, 1.5}, 5.0);
  ASSERT_TRUE(low.has_value());
  EXPECT_EQ(low->i, 3);
  EXPECT_EQ(low->j, 1);
  low = lowestRiskCell(g, {0.5, 2.5}, 0.6);  // window covers cells (0..1, 2) only -> lowest 0.3 at (0,2)
  ASSERT_TRUE(low.has_value());
  EXPECT_EQ(low->risk, 0.3);
  EXPECT_FALSE(lowestRiskCell(g, {50, 50}, 1.0).has_value());
  LevelGrid l = classifyLevels(g, 10);
  EXPECT_EQ(riskAt(l, {0.5, 0.5})->risk, 9.0);
  EXPECT_EQ(maxRiskAlongSegment(l, {0.5, 1.5}, {3.5, 1.5})->risk, 5.0);
}

}  // namespace
}  // namespace fleet::risk
