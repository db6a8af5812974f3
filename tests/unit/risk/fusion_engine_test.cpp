#include "fleet/risk/fusion_engine.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "fleet/risk/gaussian.hpp"
#include "fleet/risk/overlap_ratio.hpp"

namespace fleet::risk {
namespace {

constexpr std::int64_t kSec = 1'000'000'000;

std::string idOf(const char* prefix, int n) {
  std::string id(prefix);
  id += std::to_string(n);  // (not prefix + to_string: GCC 12 warns falsely on that with -Werror=restrict)
  return id;
}

Source randomSource(std::mt19937_64& rng, const std::string& id, double w, double h, int steps,
                    double sigmaMax) {
  std::uniform_real_distribution<double> ux(-1.0, w + 1.0), uy(-1.0, h + 1.0), ur(0.3, 0.6), uv(-1.5, 1.5),
      us(0.0, sigmaMax), uk(0.0, 1.0);
  Source s;
  s.id = id;
  s.kind = uk(rng) < 0.3 ? SourceKind::kHuman : SourceKind::kRobot;
  s.t0_ns = 0;
  s.dt = 0.1;
  double x = ux(rng), y = uy(rng);
  const double vx = uv(rng), vy = uv(rng), r = ur(rng), sg = us(rng);
  for (int k = 0; k < steps; ++k) {
    s.discs.push_back({x + vx * 0.1 * k, y + vy * 0.1 * k, r, sg});
  }
  return s;
}

FusionConfig smallConfig(double w, double h, int steps) {
  FusionConfig c;
  c.grid = GridSpec{0.0, 0.0, 0.1, static_cast<int>(w / 0.1), static_cast<int>(h / 0.1)};
  c.levels = 10;
  c.dt = 0.1;
  c.steps = steps;
  c.tileSize = 16;
  return c;
}

void expectEqualsReference(const FusionEngine& engine, const FusionResult& r) {
  const auto aligned = engine.alignedSources();
  const auto ref =
      referenceProbabilityGrid(engine.config().grid, aligned, engine.model(), engine.config().policy);
  ASSERT_EQ(ref.p.size(), r.probability.p.size());
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < ref.p.size(); ++i) {
    ASSERT_EQ(r.probability.p[i], ref.p[i]) << "cell " << i;
    ASSERT_EQ(r.levels.level[i], isoLevel(ref.p[i], engine.config().levels));
    nonzero += ref.p[i] > 0.0 ? 1 : 0;
  }
  EXPECT_GT(nonzero, 0u);  // the scene must exercise something
  const auto scene = referenceSceneIndex(aligned, engine.config().policy);
  ASSERT_EQ(scene.size(), r.sceneIndexPerStep.size());
  for (std::size_t k = 0; k < scene.size(); ++k) {
    EXPECT_NEAR(r.sceneIndexPerStep[k], scene[k], 1e-12 + 1e-9 * scene[k]);
  }
}

class FusionEquality : public ::testing::TestWithParam<int> {};

TEST_P(FusionEquality, RandomScenesMatchReferenceCellForCell) {
  const bool gaussian = GetParam() % 2 == 1;
  std::shared_ptr<const RiskModel> model =
      gaussian ? std::shared_ptr<const RiskModel>(std::make_shared<Gaussian>(1e-4))
               : std::shared_ptr<const RiskModel>(std::make_shared<OverlapRatio>());
  std::mt19937_64 rng(1000 + GetParam());
  auto cfg = smallConfig(8.0, 6.0, 8);
  cfg.policy.humanHuman = GetParam() % 3 == 0;
  auto engine = FusionEngine::create(cfg, model);
  ASSERT_TRUE(engine.has_value());
  for (int s = 0; s < 25; ++s) {
    ASSERT_TRUE(engine->upsert(randomSource(rng, idOf("s", s), 8.0, 6.0, 10, gaussian ? 0.3 : 0.0)));
  }
  const auto& r1 = engine->fuse(0);
  EXPECT_TRUE(r1.stats.fullRecompute);
  expectEqualsReference(*engine, r1);
  // Incremental: move, add and remove a few sources on the same time base.
  for (int round = 0; round < 4; ++round) {
    std::uniform_int_distribution<int> pick(0, 24);
    for (int c = 0; c < 2; ++c) {
      ASSERT_TRUE(
          engine->upsert(randomSource(rng, idOf("s", pick(rng)), 8.0, 6.0, 10, gaussian ? 0.3 : 0.0)));
    }
    engine->remove(idOf("s", pick(rng)));
    ASSERT_TRUE(engine->upsert(randomSource(rng, idOf("n", round), 8.0, 6.0, 10, gaussian ? 0.3 : 0.0)));
    const auto& r = engine->fuse(0);
    EXPECT_FALSE(r.stats.fullRecompute);
    expectEqualsReference(*engine, r);
  }
  // A new time base recomputes everything (sources are re-aligned, half a step later).
  const auto& r3 = engine->fuse(kSec / 20);
  EXPECT_TRUE(r3.stats.fullRecompute);
  expectEqualsReference(*engine, r3);
}

INSTANTIATE_TEST_SUITE_P(Seeds, FusionEquality, ::testing::Range(0, 8));

// Discs centred on cell centres and corners with radii of whole and half cells (and 3-4-5 distances),
// so cell centres lie on or within rounding of the rims: the painter's interval estimate must defer to
// the exact test there.
TEST(FusionEngine, LatticeAlignedDiscsMatchReferenceCellForCell) {
  auto cfg = smallConfig(6.0, 6.0, 3);
  cfg.policy.humanHuman = true;
  auto engine = FusionEngine::create(cfg, std::make_shared<OverlapRatio>());
  ASSERT_TRUE(engine.has_value());
  const double radii[] = {0.3, 0.5, 0.25, 0.35, 1.0};
  int n = 0;
  for (int k = 0; k < 10; ++k) {
    const double r = radii[k % 5];
    const double cx = 0.55 + 0.5 * k + (k % 2 == 0 ? 0.0 : 0.05);  // cell centre or cell corner
    for (int m = 0; m < 4; ++m) {
      Source s;
      s.id = idOf("l", n++);
      s.kind = SourceKind::kRobot;
      s.dt = 0.1;
      const double cy = 0.55 + 1.4 * m + (m % 2 == 0 ? 0.0 : 0.05);
      for (int step = 0; step < 3; ++step) {
        s.discs.push_back({cx, cy + 0.1 * step, r, 0.0});
      }
      ASSERT_TRUE(engine->upsert(s));
    }
  }
  expectEqualsReference(*engine, engine->fuse(0));
}

// The fast Gaussian (the service's default) on dense scenes: many pairs that do not touch, scored
// or passed over by the bounds of their bins, and pairs placed at the cut-off distance a.r + b.r +
// √(tail(a)² + tail(b)²) (and within rounding of it, either side). Cell for cell the thesis loop's grid.
TEST(FusionEngine, DenseGaussianScenesAndPairsAtTheCutOffMatchReference) {
  const auto model = std::make_shared<Gaussian>(1e-4, GaussianEvaluation::kFast);
  for (int seed = 0; seed < 4; ++seed) {
    std::mt19937_64 rng(2000 + seed);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    auto cfg = smallConfig(10.0, 8.0, 6);
    cfg.policy.humanHuman = seed % 2 == 0;
    auto engine = FusionEngine::create(cfg, model);
    ASSERT_TRUE(engine.has_value());
    for (int s = 0; s < 40; ++s) {
      ASSERT_TRUE(engine->upsert(randomSource(rng, idOf("s", s), 10.0, 8.0, 8, 0.4)));
    }
    // Pairs of static discs at the cut-off: one apart by exactly it, one by it·(1 ± 1e-15).
    for (int c = 0; c < 12; ++c) {
      const Disc a{1.0 + 0.7 * c, 1.0 + 0.5 * (c % 10), 0.2 + 0.2 * u(rng), 0.05 + 0.3 * u(rng)};
      Disc b{0.0, 0.0, 0.2 + 0.2 * u(rng), 0.05 + 0.3 * u(rng)};
      const double ta = model->tail(a), tb = model->tail(b);
      const double scale = c % 3 == 0 ? 1.0 : (c % 3 == 1 ? 1.0 - 1e-15 : 1.0 + 1e-15);
      const double cut = (a.r + b.r + std::sqrt(ta * ta + tb * tb)) * scale, th = 6.283 * u(rng);
      b.x = a.x + cut * std::cos(th);
      b.y = a.y + cut * std::sin(th);
      for (const auto& [name, disc] : {std::pair{idOf("ca", c), a}, std::pair{idOf("cb", c), b}}) {
        Source s;
        s.id = name;
        s.kind = SourceKind::kRobot;
        s.dt = 0.1;
        s.discs.assign(8, disc);
        ASSERT_TRUE(engine->upsert(s));
      }
    }
    const auto& r = engine->fuse(0);
    EXPECT_GT(r.stats.pairsTested, r.stats.pairsPositive);  // pairs were passed over
    expectEqualsReference(*engine, r);
  }
}

TEST(FusionEngine, IncrementalUpdateTouchesOnlyNearbyTiles) {
  auto cfg = smallConfig(20.0, 20.0, 5);
  auto engine = FusionEngine::create(cfg, std::make_shared<OverlapRatio>());
  ASSERT_TRUE(engine.has_value());
  std::mt19937_64 rng(5);
  for (int s = 0; s < 60; ++s) {
    ASSERT_TRUE(engine->upsert(randomSource(rng, idOf("s", s), 20.0, 20.0, 5, 0.0)));
  }
  const std::size_t allTiles = engine->fuse(0).stats.tilesRecomputed;
  Source moved{"s7", SourceKind::kRobot, 0, 0.1, {{3, 3, 0.4, 0}, {3.1, 3, 0.4, 0}}};
  ASSERT_TRUE(engine->upsert(moved));
  const auto& r = engine->fuse(0);
  EXPECT_FALSE(r.stats.fullRecompute);
  EXPECT_LT(r.stats.tilesRecomputed * 4, allTiles);
  expectEqualsReference(*engine, r);
}

TEST(FusionEngine, AlignmentInterpolatesAndDropsStepsOutsideThePrediction) {
  Source s{"a", SourceKind::kRobot, kSec, 0.2, {{0, 0, 0.5, 0.1}, {2, 0, 0.7, 0.3}}};
  const auto a = alignSource(s, TimeBase{kSec - kSec / 10 * 2, 0.1, 8});
  ASSERT_EQ(a.steps.size(), 8u);
  EXPECT_FALSE(a.steps[0].has_value());  // 0.2 s before t0: more than half a source step
  ASSERT_TRUE(a.steps[1].has_value());   // 0.1 s before: end disc held
  EXPECT_DOUBLE_EQ(a.steps[1]->x, 0.0);
  ASSERT_TRUE(a.steps[3].has_value());  // halfway
  EXPECT_NEAR(a.steps[3]->x, 1.0, 1e-12);
  EXPECT_NEAR(a.steps[3]->r, 0.6, 1e-12);
  EXPECT_NEAR(a.steps[3]->sigma, 0.2, 1e-12);
  EXPECT_TRUE(a.steps[5].has_value());   // 0.1 s after the last sample: held
  EXPECT_FALSE(a.steps[6].has_value());  // 0.2 s after
  Source one{"b", SourceKind::kHuman, 0, 0.1, {{1, 1, 0.3, 0}}};
  for (const auto& d : alignSource(one, TimeBase{5 * kSec, 0.1, 4}).steps) {
    EXPECT_TRUE(d.has_value());
  }
}

TEST(FusionEngine, ValidationRejectsBadSamplesWithTypedErrors) {
  SourceLimits lim;
  const Source good{"r1", SourceKind::kRobot, 0, 0.1, {{1, 1, 0.4, 0.1}}};
  EXPECT_TRUE(validateSource(good, lim));
  auto code = [&](Source s, std::optional<std::int64_t> now = std::nullopt) {
    auto r = validateSource(s, lim, now);
    return r ? std::string("ok") : r.error().code;
  };
  Source s = good;
  s.id = "bad id";
  EXPECT_EQ(code(s), "invalid_id");
  s = good;
  s.discs.clear();
  EXPECT_EQ(code(s), "empty");
  s = good;
  s.discs.assign(201, good.discs[0]);
  EXPECT_EQ(code(s), "too_many_steps");
  for (double dt : {0.0, -0.1, std::numeric_limits<double>::quiet_NaN(), 100.0}) {
    s = good;
    s.dt = dt;
    EXPECT_EQ(code(s), "bad_dt");
  }
  s = good;
  s.discs[0].x = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(code(s), "non_finite");
  s = good;
  s.discs[0].sigma = std::numeric_limits<double>::infinity();
  EXPECT_EQ(code(s), "non_finite");
  for (double r : {-0.1, 0.0, 50.0}) {
    s = good;
    s.discs[0].r = r;
    EXPECT_EQ(code(s), "bad_radius");
  }
  s = good;
  s.discs[0].sigma = -1;
  EXPECT_EQ(code(s), "bad_sigma");
  s = good;
  s.discs[0].y = 1e7;
  EXPECT_EQ(code(s), "out_of_range");
  s = good;
  s.t0_ns = 100 * kSec;
  EXPECT_EQ(code(s, 0), "future_timestamp");
  EXPECT_EQ(code(s, 99 * kSec), "ok");

  auto engine = FusionEngine::create(smallConfig(5, 5, 3), std::make_shared<OverlapRatio>());
  ASSERT_TRUE(engine.has_value());
  s = good;
  s.discs[0].r = -1;
  EXPECT_FALSE(engine->upsert(s));
  EXPECT_EQ(engine->sourceCount(), 0u);
  EXPECT_TRUE(engine->upsert(good));
  EXPECT_TRUE(engine->contains("r1"));
  EXPECT_FALSE(engine->remove("nope"));
  EXPECT_EQ(engine->removeOlderThan(1), 1u);
  EXPECT_EQ(engine->sourceCount(), 0u);
}

TEST(FusionEngine, ConfigValidation) {
  FusionConfig c;
  c.levels = 0;
  EXPECT_EQ(FusionEngine::create(c, std::make_shared<OverlapRatio>()).error().code, "bad_levels");
  c = FusionConfig{};
  c.grid.width = 0;
  EXPECT_EQ(FusionEngine::create(c, std::make_shared<OverlapRatio>()).error().code, "bad_grid");
  c = FusionConfig{};
  c.dt = 0;
  EXPECT_EQ(FusionEngine::create(c, std::make_shared<OverlapRatio>()).error().code, "bad_time_base");
  EXPECT_EQ(FusionEngine::create(FusionConfig{}, nullptr).error().code, "no_model");
  c = FusionConfig{};
  c.tileSize = 24;  // tiles are indexed by shifts
  EXPECT_EQ(FusionEngine::create(c, std::make_shared<OverlapRatio>()).error().code, "bad_tile");
  c.tileSize = 64;
  EXPECT_TRUE(FusionEngine::create(c, std::make_shared<OverlapRatio>()).has_value());
}

}  // namespace
}  // namespace fleet::risk
