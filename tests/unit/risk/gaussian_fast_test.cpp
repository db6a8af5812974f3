// The Gaussian model's fast path against the exact series and quadrature (and, through them, the
// scipy reference the exact isotropic series is checked against in gaussian_test.cpp).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

#include "fleet/risk/gaussian.hpp"

namespace fleet::risk {
namespace {

TEST(GaussianFast, TableWithinToleranceOfTheExactSeriesOverItsDomain) {
  // A sweep off the table's nodes (steps of 1/16 in R/σ and (d − R)/σ) plus random points.
  double worst = 0.0;
  for (double v = 0.013; v < kGaussianTableMaxRatio; v += 0.0517) {
    for (double w = -9.3; w < 9.3; w += 0.0291) {
      const double d = std::max(0.0, v + w);
      const double exact = gaussianCollisionProbability(d, v, 1.0);
      worst = std::max(worst, std::abs(gaussianCollisionProbabilityTabulated(d, v, 1.0) - exact));
    }
  }
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ud(0.0, 3.0), ur(0.2, 1.5), us(0.01, 1.5);
  for (int i = 0; i < 200000; ++i) {
    const double d = ud(rng), R = ur(rng), s = us(rng);
    worst = std::max(worst, std::abs(gaussianCollisionProbabilityTabulated(d, R, s) -
                                     gaussianCollisionProbability(d, R, s)));
  }
  std::printf("largest |table - exact| = %.3g\n", worst);
  RecordProperty("max_abs_diff", std::to_string(worst));
  EXPECT_LT(worst, kGaussianTableTolerance);
  EXPECT_GT(worst, 0.0);  // it is an interpolation: not the exact series in disguise
}

TEST(GaussianFast, TableMatchesTheScipyReferenceWithinTolerance) {
  std::ifstream in(std::string(FLEET_SOURCE_DIR) + "/tests/unit/risk/gaussian_reference.csv");
  ASSERT_TRUE(in);
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::stringstream ss(line);
    double d = 0, R = 0, s = 0, p = 0;
    char c = 0;
    ss >> d >> c >> R >> c >> s >> c >> p;
    EXPECT_NEAR(gaussianCollisionProbabilityTabulated(d, R, s), p, kGaussianTableTolerance)
        << d << " " << R << " " << s;
    ++rows;
  }
  EXPECT_GT(rows, 100);
}

TEST(GaussianFast, ModelPairsWithinToleranceAndFloorConsistent) {
  const Gaussian exact(1e-4, GaussianEvaluation::kExact);
  const Gaussian fast(1e-4, GaussianEvaluation::kFast);
  std::mt19937_64 rng(4);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int i = 0; i < 100000; ++i) {
    const Disc a{0, 0, 0.3 + 0.3 * u(rng), 0.01 + 0.5 * u(rng)};
    const double th = 6.283 * u(rng), d = 3.0 * u(rng);
    Disc b{d * std::cos(th), d * std::sin(th), 0.3 + 0.3 * u(rng), 0.01 + 0.5 * u(rng)};
    if (i % 2 == 0) {  // anisotropic half
      const double l1 = std::pow(0.02 + 0.6 * u(rng), 2), l2 = l1 * (0.05 + 0.95 * u(rng)),
                   t = 3.1416 * u(rng);
      const double c = std::cos(t), s = std::sin(t);
      b.cov = Cov2{c * c * l1 + s * s * l2, c * s * (l1 - l2), s * s * l1 + c * c * l2};
      b.sigma = b.sigmaMax();
    }
    const double pe = exact.pair(a, b), pf = fast.pair(a, b);
    EXPECT_EQ(fast.pair(b, a), pf);
    // Either both within tolerance, or the exact value lies within tolerance of the floor (one of them
    // is then reported as 0).
    if (std::abs(pe - 1e-4) > kGaussianTableTolerance) {
      ASSERT_NEAR(pf, pe, kGaussianTableTolerance) << i;
      worst = std::max(worst, std::abs(pf - pe));
    }
  }
  std::printf("largest |fast - exact| over model pairs = %.3g\n", worst);
}

}  // namespace
}  // namespace fleet::risk

namespace fleet::risk {
namespace {

TEST(GaussianFast, AnisotropicQuadratureWithinToleranceOfTheExactOne) {
  // Eigenvalue ratios down to 1e-6 (the exact quadrature is itself checked against the polar and
  // whitened references and Monte Carlo in gaussian_test.cpp), every orientation, means inside, on and
  // outside the rim.
  std::mt19937_64 rng(6);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  double worst = 0.0;
  for (int i = 0; i < 100000; ++i) {
    const double R = 0.3 + 1.0 * u(rng);
    const double s2 = 0.01 + 1.0 * u(rng);
    const double ratio = std::exp(std::log(1e-6) * u(rng));
    const double l1 = s2 * s2, l2 = l1 * ratio, t = 3.1416 * u(rng), c = std::cos(t), s = std::sin(t);
    const Cov2 cov{c * c * l1 + s * s * l2, c * s * (l1 - l2), s * s * l1 + c * c * l2};
    const double d = (R + 4.0 * s2) * 1.2 * u(rng), th = 6.2832 * u(rng);
    const Vec2 mean{d * std::cos(th), d * std::sin(th)};
    const double exact = gaussianCollisionProbability(mean, cov, R);
    const double fast = gaussianCollisionProbabilityFast(mean, cov, R);
    ASSERT_NEAR(fast, exact, kGaussianTableTolerance)
        << i << " R " << R << " s2 " << s2 << " ratio " << ratio;
    worst = std::max(worst, std::abs(fast - exact));
  }
  std::printf("largest |anisotropic fast - exact| = %.3g\n", worst);
  EXPECT_GT(worst, 0.0);
}

}  // namespace
}  // namespace fleet::risk

#include "fleet/risk/fusion_engine.hpp"

namespace fleet::risk {
namespace {

// The service's configuration (fast path) against the exact model on the same mixed scene, cell for
// cell: within the stated tolerance, a level only changing where p is that close to a boundary.
TEST(GaussianFast, FusedMapWithinToleranceOfTheExactModel) {
  FusionConfig cfg;
  cfg.grid = GridSpec{0.0, 0.0, 0.1, 200, 120};
  cfg.steps = 20;
  std::vector<Source> scene;
  std::mt19937_64 rng(21);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 120; ++i) {
    Source s;
    s.id = "s";
    s.id += std::to_string(i);
    s.kind = u(rng) < 0.25 ? SourceKind::kHuman : SourceKind::kRobot;
    const double x = 20 * u(rng), y = 12 * u(rng), th = 6.283 * u(rng), v = 0.3 + 1.2 * u(rng);
    for (int k = 0; k < 20; ++k) {
      const double t = 0.1 * k;
      Disc d{x + v * std::cos(th) * t, y + v * std::sin(th) * t, 0.3 + 0.2 * u(rng), 0.03 + 0.05 * t};
      if (s.kind == SourceKind::kRobot && i % 2 == 0) {
        const double l1 = std::pow(0.03 + 0.2 * v * t, 2), l2 = std::pow(0.03 + 0.05 * t, 2);
        const double c = std::cos(th), sn = std::sin(th);
        d.cov = Cov2{c * c * l1 + sn * sn * l2, c * sn * (l1 - l2), sn * sn * l1 + c * c * l2};
        d.sigma = d.sigmaMax();
      }
      s.discs.push_back(d);
    }
    scene.push_back(std::move(s));
  }
  auto run = [&](GaussianEvaluation e) {
    auto engine = FusionEngine::create(cfg, std::make_shared<Gaussian>(1e-4, e));
    EXPECT_TRUE(engine.has_value());
    for (const auto& s : scene) {
      EXPECT_TRUE(engine->upsert(s));
    }
    return engine->fuse(0);
  };
  const FusionResult exact = run(GaussianEvaluation::kExact);
  const FusionResult fast = run(GaussianEvaluation::kFast);
  double worst = 0.0;
  std::size_t nonzero = 0;
  for (std::size_t c = 0; c < exact.probability.p.size(); ++c) {
    const double pe = exact.probability.p[c], pf = fast.probability.p[c];
    nonzero += pe > 0.0 ? 1 : 0;
    worst = std::max(worst, std::abs(pe - pf));
    ASSERT_NEAR(pf, pe, kGaussianTableTolerance) << "cell " << c;
    if (exact.levels.level[c] != fast.levels.level[c]) {
      const double boundary = std::round(pe * 10.0) / 10.0;
      EXPECT_NEAR(pe, boundary, kGaussianTableTolerance) << "cell " << c;
    }
  }
  EXPECT_GT(nonzero, 2000u);
  std::printf("fused map: largest |fast - exact| = %.3g over %zu non-zero cells\n", worst, nonzero);
}

}  // namespace
}  // namespace fleet::risk
