#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>
#include <numbers>
#include <queue>
#include <random>
#include <thread>

#include "fleet/planning/astar.hpp"
#include "fleet/planning/distance_field_cache.hpp"
#include "fleet/planning/wavefront.hpp"

using namespace fleet;
using namespace fleet::planning;

namespace {

OccupancyGrid randomGrid(std::mt19937& rng, int w, int h, double p) {
  std::bernoulli_distribution occ(p);
  OccupancyGrid g(w, h, 0.5, {-3.0, 4.0});
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      g.setBlocked({x, y}, occ(rng));
    }
  }
  return g;
}

Cell randomFree(std::mt19937& rng, const OccupancyGrid& g) {
  std::uniform_int_distribution<int> ux(0, g.width() - 1), uy(0, g.height() - 1);
  while (true) {
    const Cell c{ux(rng), uy(rng)};
    if (!g.blocked(c)) {
      return c;
    }
  }
}

}  // namespace

TEST(AStar, MatchesDistanceFieldOnRandomGrids) {
  std::mt19937 rng(12);
  for (Connectivity conn : {Connectivity::Four, Connectivity::Eight}) {
    int reached = 0, unreachable = 0;
    for (int trial = 0; trial < 30; ++trial) {
      const OccupancyGrid g = randomGrid(rng, 40, 30, 0.3);
      const Cell goal = randomFree(rng, g);
      const DistanceField f = computeDistanceField(g, goal, conn);
      for (int q = 0; q < 10; ++q) {
        const Cell s = randomFree(rng, g);
        const auto r = astar(g, s, goal, conn);
        ASSERT_EQ(r.has_value(), f.reachable(s));
        if (!r) {
          ++unreachable;
          EXPECT_EQ(r.error().code, "unreachable");
          continue;
        }
        ++reached;
        EXPECT_NEAR(r->cost, f.at(s), 1e-9);
        double sum = 0.0;
        for (std::size_t k = 1; k < r->cells.size(); ++k) {
          const Cell o{r->cells[k].x - r->cells[k - 1].x, r->cells[k].y - r->cells[k - 1].y};
          ASSERT_TRUE(moveAllowed(g, r->cells[k - 1], o));
          sum += moveCost(o);
        }
        EXPECT_NEAR(sum, r->cost, 1e-9);
      }
    }
    EXPECT_GT(reached, 100);
    EXPECT_GT(unreachable, 0);
  }
}

TEST(AStar, LandmarkHeuristicKeepsCostsAndExpandsLess) {
  std::mt19937 rng(31);
  for (Connectivity conn : {Connectivity::Four, Connectivity::Eight}) {
    const OccupancyGrid g = randomGrid(rng, 80, 50, 0.3);  // several components
    const LandmarkHeuristic lh = LandmarkHeuristic::build(g, conn, 6);
    EXPECT_EQ(lh.count(), 6);
    long plain = 0, alt = 0;
    for (int q = 0; q < 200; ++q) {
      const Cell s = randomFree(rng, g), t = randomFree(rng, g);
      const auto a = astar(g, s, t, conn);
      const auto b = astar(g, s, t, conn, &lh);
      ASSERT_EQ(a.has_value(), b.has_value());
      if (a) {
        EXPECT_NEAR(a->cost, b->cost, 1e-9);
        plain += a->expanded;
        alt += b->expanded;
      }
    }
    EXPECT_LT(alt, plain) << (conn == Connectivity::Four ? "four" : "eight");
  }
  // Landmarks built for the other move set are ignored, not misused.
  const OccupancyGrid g = randomGrid(rng, 30, 30, 0.2);
  const LandmarkHeuristic four = LandmarkHeuristic::build(g, Connectivity::Four, 4);
  const Cell s = randomFree(rng, g), t = randomFree(rng, g);
  const auto a = astar(g, s, t, Connectivity::Eight);
  const auto b = astar(g, s, t, Connectivity::Eight, &four);
  ASSERT_EQ(a.has_value(), b.has_value());
  if (a) {
    EXPECT_NEAR(a->cost, b->cost, 1e-9);
  }
}

TEST(GlobalPlanner, WavefrontAndAStarGiveEqualLengthsOnTheWarehouse) {
  WarehouseParams wp;
  wp.resolution = 0.5;
  const OccupancyGrid g = makeWarehouseGrid(wp);
  std::mt19937 rng(4);
  WavefrontPlanner wf;
  AStarPlanner as;
  AStarPlanner alt(Connectivity::Eight, std::make_shared<const LandmarkHeuristic>(
                                            LandmarkHeuristic::build(g, Connectivity::Eight, 4)));
  std::vector<GlobalPlanner*> planners{&wf, &as, &alt};
  for (int q = 0; q < 10; ++q) {
    const Vec2 a = g.cellCenter(randomFree(rng, g)), b = g.cellCenter(randomFree(rng, g));
    std::vector<double> lengths;
    for (GlobalPlanner* p : planners) {
      const auto path = p->plan(g, {a.x, a.y, 0.3}, {b.x, b.y, -1.0});
      ASSERT_TRUE(path.has_value()) << p->name();
      EXPECT_DOUBLE_EQ(path->poses.front().theta, 0.3);
      EXPECT_DOUBLE_EQ(path->poses.back().theta, -1.0);
      lengths.push_back(path->length());
      for (const Pose2& pose : path->poses) {
        EXPECT_FALSE(g.blocked(*g.cellAt(pose.position())));
      }
    }
    EXPECT_NEAR(lengths[0], lengths[1], 1e-9);
    EXPECT_NEAR(lengths[0], lengths[2], 1e-9);
    EXPECT_GE(lengths[0], distance(a, b) - 1e-9);
  }
}

TEST(DistanceFieldCache, CachedCostsMatchAStarAndAreComputedOncePerGoal) {
  std::mt19937 rng(6);
  auto grid = std::make_shared<const OccupancyGrid>(randomGrid(rng, 60, 40, 0.2));
  DistanceFieldCache cache(grid, Connectivity::Eight, 8);
  std::vector<Cell> goals;
  for (int k = 0; k < 4; ++k) {
    goals.push_back(randomFree(rng, *grid));
  }
  std::vector<Cell> starts;
  for (int k = 0; k < 50; ++k) {
    starts.push_back(randomFree(rng, *grid));
  }
  std::vector<std::thread> threads;
  std::vector<std::vector<double>> results(4);
  for (int t = 0; t < 4; ++t) {
    threads.emplace_back([&, t] {
      for (int rep = 0; rep < 3; ++rep) {
        for (const Cell& goal : goals) {
          for (const Cell& s : starts) {
            results[static_cast<std::size_t>(t)].push_back(cache.travelCost(s, goal));
          }
        }
      }
    });
  }
  for (auto& th : threads) {
    th.join();
  }
  EXPECT_EQ(cache.computations(), goals.size());
  for (int t = 1; t < 4; ++t) {
    EXPECT_EQ(results[static_cast<std::size_t>(t)], results[0]);
  }
  std::size_t k = 0;
  for (const Cell& goal : goals) {
    for (const Cell& s : starts) {
      const auto r = astar(*grid, s, goal);
      const double c = results[0][k++];
      if (r) {
        EXPECT_NEAR(c, r->cost, 1e-9);
      } else {
        EXPECT_TRUE(std::isinf(c));
      }
    }
  }
  // Metres: resolution 0.5.
  const Vec2 a = grid->cellCenter(starts[0]), b = grid->cellCenter(goals[0]);
  EXPECT_NEAR(cache.travelDistance(a, b), 0.5 * cache.travelCost(starts[0], goals[0]), 1e-12);
  EXPECT_TRUE(std::isinf(cache.travelDistance({-100, -100}, b)));
  // LRU: more goals than the capacity forces recomputation of the evicted ones.
  for (int j = 0; j < 10; ++j) {
    cache.field(randomFree(rng, *grid));
  }
  const std::size_t before = cache.computations();
  cache.field(goals[0]);
  EXPECT_EQ(cache.computations(), before + 1);
}

// Grids above ~175k cells use fewer fractional bits for the fixed-point costs (so a path through
// every cell still fits); costs must stay exact there too, and the per-thread scratch must follow
// the grid size when queries alternate between maps.
TEST(AStar, ExactOnLargeGridsAndAcrossGridSizes) {
  std::mt19937 rng(31);
  const OccupancyGrid big = randomGrid(rng, 600, 400, 0.2);
  const OccupancyGrid small = randomGrid(rng, 30, 20, 0.2);
  for (int round = 0; round < 3; ++round) {
    const Cell goal = randomFree(rng, big);
    const DistanceField f = computeDistanceField(big, goal, Connectivity::Eight);
    for (int q = 0; q < 4; ++q) {
      const Cell s = randomFree(rng, big);
      const auto r = astar(big, s, goal);
      ASSERT_EQ(r.has_value(), f.reachable(s));
      if (r) {
        EXPECT_NEAR(r->cost, f.at(s), 1e-9);
        EXPECT_EQ(r->cells.front(), s);
        EXPECT_EQ(r->cells.back(), goal);
      }
    }
    const Cell sg = randomFree(rng, small), ss = randomFree(rng, small);
    const DistanceField fs = computeDistanceField(small, sg, Connectivity::Eight);
    const auto rs = astar(small, ss, sg);
    ASSERT_EQ(rs.has_value(), fs.reachable(ss));
    if (rs) {
      EXPECT_NEAR(rs->cost, fs.at(ss), 1e-9);
    }
  }
}

namespace {

// Dijkstra over the same moves (8-connected, no corner cutting) with the same layered costs: the
// reference the one A* is checked against.
double layeredDijkstra(const OccupancyGrid& g, Cell s, Cell t, const CostLayers& layers) {
  std::vector<double> d(g.size(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  d[g.index(s)] = 0.0;
  open.emplace(0.0, g.index(s));
  while (!open.empty()) {
    const auto [k, i] = open.top();
    open.pop();
    if (k > d[i]) {
      continue;
    }
    const Cell c = g.cellOf(i);
    for (int dy = -1; dy <= 1; ++dy) {
      for (int dx = -1; dx <= 1; ++dx) {
        const Cell q{c.x + dx, c.y + dy};
        if ((dx == 0 && dy == 0) || g.blocked(q) ||
            (dx != 0 && dy != 0 && (g.blocked({c.x + dx, c.y}) || g.blocked({c.x, c.y + dy})))) {
          continue;
        }
        double f = 1.0;
        for (const auto& l : layers) {
          f *= std::max(1.0, l->factor(c, q));
        }
        const double nd = d[i] + (dx != 0 && dy != 0 ? std::numbers::sqrt2 : 1.0) * f;
        if (nd < d[g.index(q)]) {
          d[g.index(q)] = nd;
          open.emplace(nd, g.index(q));
        }
      }
    }
  }
  return d[g.index(t)];
}

// Prices in [0.5, 4) per cell (below 1 counts as 1) and a direction rule: moving left costs 3x.
CostLayers randomLayers(int w, int h, std::mt19937& rng) {
  auto price = std::make_shared<std::vector<double>>(static_cast<std::size_t>(w * h));
  std::uniform_real_distribution<double> u(0.5, 4.0);
  for (auto& p : *price) {
    p = u(rng);
  }
  struct Leftward final : CostLayer {
    double factor(Cell from, Cell to) const override { return to.x < from.x ? 3.0 : 1.0; }
    const char* name() const override { return "leftward"; }
  };
  return {std::make_shared<EnterCellCost>(
              "price", [price, w](Cell c) { return (*price)[static_cast<std::size_t>(c.y * w + c.x)]; }),
          std::make_shared<Leftward>()};
}

}  // namespace

TEST(LayeredAStar, MatchesDijkstraOnRandomGridsWithRandomLayers) {
  std::mt19937 rng(11);
  std::bernoulli_distribution wall(0.25);
  int solved = 0;
  for (int trial = 0; trial < 60; ++trial) {
    OccupancyGrid g(25, 18, 0.5);
    for (int y = 0; y < 18; ++y) {
      for (int x = 0; x < 25; ++x) {
        if (wall(rng)) {
          g.setBlocked({x, y});
        }
      }
    }
    const Cell s{0, 0};
    const Cell t{24, 17};
    g.setBlocked(s, false);
    g.setBlocked(t, false);
    const auto layers = randomLayers(25, 18, rng);
    const auto got = astar(g, s, t, layers);
    const double ref = layeredDijkstra(g, s, t, layers);
    ASSERT_EQ(got.has_value(), std::isfinite(ref)) << "trial " << trial;
    if (!got) {
      continue;
    }
    ++solved;
    EXPECT_NEAR(got->cost, ref, 1e-9) << "trial " << trial;
    // The returned cells are a legal path whose layered cost is the reported cost.
    double cost = 0.0;
    for (std::size_t i = 1; i < got->cells.size(); ++i) {
      const Cell a = got->cells[i - 1], b = got->cells[i];
      ASSERT_LE(std::max(std::abs(a.x - b.x), std::abs(a.y - b.y)), 1);
      double f = 1.0;
      for (const auto& l : layers) {
        f *= std::max(1.0, l->factor(a, b));
      }
      cost += (a.x != b.x && a.y != b.y ? std::numbers::sqrt2 : 1.0) * f;
    }
    EXPECT_NEAR(cost, got->cost, 1e-9);
  }
  EXPECT_GT(solved, 20);
}

TEST(LayeredAStar, WithoutLayersIsThePlainSearchAndLayersOnlyLengthen) {
  std::mt19937 rng(5);
  const auto grid = makeWarehouseGrid();
  std::vector<Cell> free;
  for (std::size_t i = 0; i < grid.size(); ++i) {
    if (grid.cells()[i] == 0) {
      free.push_back(grid.cellOf(i));
    }
  }
  std::uniform_int_distribution<std::size_t> pick(0, free.size() - 1);
  const auto layers = randomLayers(grid.width(), grid.height(), rng);
  for (int t = 0; t < 20; ++t) {
    const Cell a = free[pick(rng)], b = free[pick(rng)];
    const auto plain = astar(grid, a, b);
    const auto none = astar(grid, a, b, CostLayers{});
    const auto layered = astar(grid, a, b, layers);
    ASSERT_EQ(plain.has_value(), none.has_value());
    ASSERT_EQ(plain.has_value(), layered.has_value());
    if (plain) {
      EXPECT_EQ(plain->cells, none->cells) << "no layers: the fixed-point search itself";
      EXPECT_GE(layered->cost, plain->cost - 1e-9) << "factors below 1 count as 1";
    }
  }
}
