// Discs with a 2×2 position covariance: the Gaussian pair model, validation, alignment and fusion.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <random>

#include "fleet/risk/fusion_engine.hpp"
#include "fleet/risk/gaussian.hpp"
#include "fleet/risk/overlap_ratio.hpp"

namespace fleet::risk {
namespace {

// Covariance with standard deviations sAlong along heading th and sAcross across it.
Cov2 covAlong(double th, double sAlong, double sAcross) {
  const double c = std::cos(th), s = std::sin(th), l1 = sAlong * sAlong, l2 = sAcross * sAcross;
  return {c * c * l1 + s * s * l2, c * s * (l1 - l2), s * s * l1 + c * c * l2};
}

TEST(AnisotropicDiscs, PairUsesTheSummedCovarianceAndIsSymmetric) {
  const Gaussian m(1e-4);
  const Disc a{0, 0, 0.3, 0.4, covAlong(0.0, 0.4, 0.05)};
  const Disc b{1.2, 0.3, 0.35, 0.1};  // isotropic partner: enters as σ²I
  const double expected =
      gaussianCollisionProbability(Vec2{1.2, 0.3}, Cov2{0.16 + 0.01, 0.0, 0.0025 + 0.01}, 0.65, 1e-4);
  EXPECT_GT(expected, 1e-3);
  EXPECT_NEAR(m.pair(a, b), expected, 1e-12);
  EXPECT_EQ(m.pair(b, a), m.pair(a, b));
  // Across the major axis at the same distance the probability is far smaller.
  const Disc across{0.3, 1.2, 0.35, 0.1};
  EXPECT_LT(m.pair(a, across), 0.01 * expected);
}

TEST(AnisotropicDiscs, IsotropicCovarianceGivesTheIsotropicModel) {
  const Gaussian m(1e-6);
  std::mt19937_64 rng(5);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 200; ++i) {
    const double sa = 0.02 + 0.5 * u(rng), sb = 0.02 + 0.5 * u(rng);
    const Disc a{u(rng), u(rng), 0.2 + 0.4 * u(rng), sa};
    const Disc b{2 * u(rng), 2 * u(rng), 0.2 + 0.4 * u(rng), sb};
    Disc a2 = a;
    a2.cov = Cov2{sa * sa, 0.0, sa * sa};
    EXPECT_NEAR(m.pair(a2, b), m.pair(a, b), 1e-10) << i;
  }
}

TEST(AnisotropicDiscs, CullAndReachBoundTheAnisotropicPair) {
  const Gaussian m(1e-4);
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 500; ++i) {
    const Disc a{0, 0, 0.3, 0, covAlong(6.283 * u(rng), 0.05 + 0.8 * u(rng), 0.02 + 0.1 * u(rng))};
    const Disc b{0, 0, 0.4, 0.05 + 0.3 * u(rng)};
    EXPECT_GE(m.reach(a) + m.reach(b), m.cullDistance(a, b));
    // Just beyond the cull distance, in any direction, the exact probability is below the floor.
    const double c = m.cullDistance(a, b) * 1.0001, th = 6.283 * u(rng);
    const Disc far{c * std::cos(th), c * std::sin(th), 0.4, b.sigma};
    const Cov2 ca = a.covariance(), cb = far.covariance();
    EXPECT_LT(
        gaussianCollisionProbability(Vec2{far.x, far.y}, Cov2{ca.xx + cb.xx, ca.xy, ca.yy + cb.yy}, 0.7),
        1e-4);
    EXPECT_EQ(m.pair(a, far), 0.0);
  }
}

// The fusion engine drops a pair at or beyond a.r + b.r + √(tail(a)² + tail(b)²) without asking the
// model: the pair must score exactly 0 there (isotropic and anisotropic, fast and exact evaluation).
TEST(AnisotropicDiscs, PairsAtOrBeyondTheTailDistanceScoreZero) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (const auto eval : {GaussianEvaluation::kExact, GaussianEvaluation::kFast}) {
    const Gaussian m(1e-4, eval);
    for (int i = 0; i < 2000; ++i) {
      Disc a{0, 0, 0.2 + 0.4 * u(rng), 0.02 + 0.9 * u(rng)};
      if (i % 2 == 0) {
        a.cov = covAlong(6.283 * u(rng), 0.05 + 0.8 * u(rng), 0.01 + 0.2 * u(rng));
        a.sigma = a.sigmaMax();
      }
      const double rb = 0.2 + 0.4 * u(rng), sb = 0.02 + 0.9 * u(rng);
      const double ta = m.tail(a), tb = m.tail(Disc{0, 0, rb, sb});
      const double t = a.r + rb + std::sqrt(ta * ta + tb * tb), th = 6.283 * u(rng);
      ASSERT_LE(std::abs(t - m.cullDistance(a, Disc{0, 0, rb, sb})), 1e-12 * t) << i;
      for (const double scale : {1.0, 1.0 + 1e-12, 1.01}) {
        const Disc b{t * scale * std::cos(th), t * scale * std::sin(th), rb, sb};
        ASSERT_GE(centreDistance(a, b), t * (1.0 - 1e-15));
        EXPECT_EQ(m.pair(a, b), 0.0) << i << " " << scale;
      }
    }
  }
  // The overlap ratio's tail is 0 (touching is the cull), and the default for other models follows from
  // the reaches.
  const OverlapRatio o;
  EXPECT_EQ(o.tail(Disc{0, 0, 0.4, 0.3}), 0.0);
  struct ReachOnly final : RiskModel {
    double pair(const Disc& a, const Disc& b) const override {
      return centreDistance(a, b) < 1.0 ? 1.0 : 0.0;
    }
    double cullDistance(const Disc&, const Disc&) const override { return 1.0; }
    double reach(const Disc&) const override { return 0.5; }
    std::string_view name() const override { return "reach_only"; }
  } r;
  const Disc z{0, 0, 0.1, 0};
  EXPECT_GE(z.r + z.r + std::sqrt(2.0) * r.tail(z), r.cullDistance(z, z));
}

// The engine passes over a deferred pair when the bound of its bin, tailRatioBound(x) with x the bin's
// smallest gap² / (tail(a)² + tail(b)²), is below both discs' maxima: that bound must hold for every
// pair of the class, isotropic and anisotropic, exact and fast, down to pairs exactly at a bin's edge.
TEST(AnisotropicDiscs, TailRatioBoundHoldsForEveryPairOfItsClass) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  constexpr int kBins = 32;
  for (const auto eval : {GaussianEvaluation::kExact, GaussianEvaluation::kFast}) {
    const Gaussian m(1e-4, eval);
    EXPECT_EQ(m.tailRatioBound(0.0), 1.0);
    for (int i = 0; i < 4000; ++i) {
      Disc a{0, 0, 0.2 + 0.4 * u(rng), 0.02 + 0.9 * u(rng)};
      Disc b{0, 0, 0.2 + 0.4 * u(rng), 0.02 + 0.9 * u(rng)};
      if (i % 2 == 0) {
        a.cov = covAlong(6.283 * u(rng), 0.05 + 0.8 * u(rng), 0.01 + 0.2 * u(rng));
        a.sigma = a.sigmaMax();
      }
      if (i % 4 == 0) {
        b.cov = covAlong(6.283 * u(rng), 0.05 + 0.8 * u(rng), 0.01 + 0.2 * u(rng));
        b.sigma = b.sigmaMax();
      }
      const double ta = m.tail(a), tb = m.tail(b);
      // Half the pairs exactly at a bin's edge, the others anywhere in [0, 1).
      const int bin = static_cast<int>(u(rng) * kBins);
      const double x = i % 2 == 0 ? static_cast<double>(bin) / kBins : u(rng);
      const double gap = std::sqrt(x * (ta * ta + tb * tb));
      const double th = 6.283 * u(rng);
      b.x = (a.r + b.r + gap) * std::cos(th);
      b.y = (a.r + b.r + gap) * std::sin(th);
      const double g = centreDistance(a, b) - a.r - b.r;
      const double xr = g * g / (ta * ta + tb * tb);
      const int cls = std::min(kBins - 1, static_cast<int>(xr * kBins));
      const double p = m.pair(a, b);
      EXPECT_LE(p, m.tailRatioBound(static_cast<double>(cls) / kBins)) << i << " x " << xr;
      EXPECT_LE(p, m.tailRatioBound(xr)) << i << " x " << xr;
    }
  }
  EXPECT_EQ(OverlapRatio().tailRatioBound(0.5), 1.0);  // the default bounds nothing
}

TEST(AnisotropicDiscs, ValidationRefusesNonFiniteAndIndefiniteCovariances) {
  const SourceLimits lim;
  const Source good{"r1", SourceKind::kRobot, 0, 0.1, {{1, 1, 0.4, 0.3, Cov2{0.09, 0.01, 0.01}}}};
  EXPECT_TRUE(validateSource(good, lim));
  auto code = [&](Cov2 c) {
    Source s = good;
    s.discs[0].cov = c;
    auto r = validateSource(s, lim);
    return r ? std::string("ok") : r.error().code;
  };
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  EXPECT_EQ(code({nan, 0, 0.1}), "non_finite_covariance");
  EXPECT_EQ(code({0.1, inf, 0.1}), "non_finite_covariance");
  EXPECT_EQ(code({0.1, 0, -inf}), "non_finite_covariance");
  EXPECT_EQ(code({-0.01, 0, 0.1}), "bad_covariance");          // negative variance
  EXPECT_EQ(code({0.1, 0.2, 0.1}), "bad_covariance");          // |xy| > sqrt(xx·yy): indefinite
  EXPECT_EQ(code({0.0, 0.01, 0.0}), "bad_covariance");         // trace 0 yet not zero
  EXPECT_EQ(code({200.0, 0.0, 0.01}), "bad_covariance");       // σ along the major axis > maxSigma
  EXPECT_EQ(code({0.04, 0.02, 0.01}), "ok");                   // singular (a line) is semi-definite
  EXPECT_EQ(code({0.04f, 0.02f * (1 + 1e-7f), 0.01f}), "ok");  // ... also after rounding to float
  EXPECT_EQ(code({0, 0, 0}), "ok");                            // isotropic
}

TEST(AnisotropicDiscs, AlignmentInterpolatesTheCovariance) {
  Source s{"a", SourceKind::kRobot, 0, 0.2, {{0, 0, 0.5, 0.1}, {2, 0, 0.5, 0.5, Cov2{0.25, 0.1, 0.09}}}};
  const auto a = alignSource(s, TimeBase{0, 0.1, 3});
  ASSERT_TRUE(a.steps[1].has_value());
  const Disc& d = *a.steps[1];  // halfway: (σ²I + C)/2 with σ = 0.1
  ASSERT_TRUE(d.anisotropic());
  EXPECT_NEAR(d.cov.xx, 0.5 * (0.01 + 0.25), 1e-12);
  EXPECT_NEAR(d.cov.xy, 0.05, 1e-12);
  EXPECT_NEAR(d.cov.yy, 0.5 * (0.01 + 0.09), 1e-12);
  EXPECT_NEAR(d.sigma, d.sigmaMax(), 1e-15);
  EXPECT_NEAR(a.steps[0]->covariance().xx, 0.01, 1e-15);  // at the isotropic end: σ²I
  EXPECT_EQ(a.steps[0]->covariance().xy, 0.0);
}

// The engine's spatial hash and tiles with anisotropic reaches: cell for cell the thesis grid loop.
TEST(AnisotropicDiscs, FusionMatchesTheReferenceOnMixedScenes) {
  FusionConfig cfg;
  cfg.grid = GridSpec{0.0, 0.0, 0.1, 80, 60};
  cfg.steps = 8;
  cfg.tileSize = 16;
  auto engine = FusionEngine::create(cfg, std::make_shared<Gaussian>(1e-4));
  ASSERT_TRUE(engine.has_value());
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 30; ++i) {
    Source s;
    s.id = "s";
    s.id += std::to_string(i);
    s.kind = u(rng) < 0.3 ? SourceKind::kHuman : SourceKind::kRobot;
    const double x = 8 * u(rng), y = 6 * u(rng), th = 6.283 * u(rng), v = 1.5 * u(rng);
    const bool aniso = i % 2 == 0;
    for (int k = 0; k < 10; ++k) {
      const double t = 0.1 * k;
      Disc d{x + v * std::cos(th) * t, y + v * std::sin(th) * t, 0.3 + 0.2 * u(rng), 0.05 + 0.1 * t};
      if (aniso) {
        d.cov = covAlong(th, 0.05 + 0.3 * v * t, 0.05 + 0.05 * t);
        d.sigma = d.sigmaMax();
      }
      s.discs.push_back(d);
    }
    ASSERT_TRUE(engine->upsert(s));
  }
  const auto& r = engine->fuse(0);
  const auto ref = referenceProbabilityGrid(cfg.grid, engine->alignedSources(), engine->model(), cfg.policy);
  std::size_t nonzero = 0;
  for (std::size_t i = 0; i < ref.p.size(); ++i) {
    ASSERT_EQ(r.probability.p[i], ref.p[i]) << "cell " << i;
    nonzero += ref.p[i] > 0.0 ? 1 : 0;
  }
  EXPECT_GT(nonzero, 100u);
}

}  // namespace
}  // namespace fleet::risk
