#include "fleet/risk/gaussian.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>
#include <sstream>
#include <string>

namespace fleet::risk {
namespace {

struct McResult {
  double p;
  double se;
};

// Seeded Monte Carlo: x ~ N(mean, cov) via a Cholesky factor; fraction inside the disc of radius R.
McResult monteCarlo(Vec2 mean, const Cov2& cov, double R, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> nd;
  const double l11 = std::sqrt(cov.xx);
  const double l21 = cov.xy / l11;
  const double l22 = std::sqrt(cov.yy - l21 * l21);
  int hits = 0;
  for (int i = 0; i < n; ++i) {
    const double z1 = nd(rng);
    const double z2 = nd(rng);
    const double x = mean.x + l11 * z1;
    const double y = mean.y + l21 * z1 + l22 * z2;
    hits += (x * x + y * y <= R * R) ? 1 : 0;
  }
  const double p = static_cast<double>(hits) / n;
  return {p, std::sqrt(std::max(p * (1 - p), 1.0 / n) / n)};
}

TEST(GaussianIsotropic, MatchesScipyNcx2Reference) {
  std::ifstream in(std::string(FLEET_SOURCE_DIR) + "/tests/unit/risk/gaussian_reference.csv");
  ASSERT_TRUE(in.good());
  std::string line;
  int rows = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') {
      continue;
    }
    std::istringstream ss(line);
    double d = 0, R = 0, s = 0, p = 0;
    char c = 0;
    ss >> d >> c >> R >> c >> s >> c >> p;
    const double got = gaussianCollisionProbability(d, R, s);
    EXPECT_NEAR(got, p, 1e-12 + 1e-9 * p) << "d=" << d << " R=" << R << " sigma=" << s;
    ++rows;
  }
  EXPECT_GT(rows, 100);
}

TEST(GaussianIsotropic, SpecialCasesBoundsAndMonotonicity) {
  EXPECT_NEAR(gaussianCollisionProbability(0.0, 1.0, 1.0), 1.0 - std::exp(-0.5), 1e-15);  // Rayleigh CDF
  EXPECT_EQ(gaussianCollisionProbability(0.5, 1.0, 0.0), 1.0);  // no uncertainty: indicator
  EXPECT_EQ(gaussianCollisionProbability(1.5, 1.0, 0.0), 0.0);
  EXPECT_EQ(gaussianCollisionProbability(0.5, 0.0, 0.3), 0.0);
  for (double s : {0.01, 0.1, 0.5, 2.0}) {
    double prev = 1.0;
    for (double d = 0.0; d < 6.0; d += 0.05) {
      const double p = gaussianCollisionProbability(d, 1.0, s);
      ASSERT_GE(p, 0.0);
      ASSERT_LE(p, 1.0);
      ASSERT_LE(p, prev + 1e-13) << s << " " << d;
      // Tail bound used for culling: P <= exp(−(d−R)²/(2σ²)) beyond R.
      if (d > 1.0) {
        ASSERT_LE(p, std::exp(-(d - 1.0) * (d - 1.0) / (2 * s * s)) + 1e-15);
      }
      prev = p;
    }
  }
  // Large arguments stay finite and sensible.
  EXPECT_NEAR(gaussianCollisionProbability(3.0, 1.0, 0.01), 0.0, 1e-300);
  EXPECT_NEAR(gaussianCollisionProbability(0.5, 1.0, 0.005), 1.0, 1e-12);
  // Far from the origin the disc edge is nearly a half-plane one sigma away: Φ(−1) = 0.1587.
  EXPECT_NEAR(gaussianCollisionProbability(100.0, 99.0, 1.0), 0.158655, 0.003);
  EXPECT_NEAR(gaussianCollisionProbability(100.0, 99.0, 1.0), 0.15744234516055491, 1e-10);  // scipy ncx2
}

// The isotropic series is summed upwards from j = 0 for b = R²/(2σ²) <= 150 and downwards from the
// truncation point (with lgamma) above: two independent summations, which must meet at the switch.
TEST(GaussianIsotropic, UpwardAndDownwardSeriesAgreeAtTheSwitch) {
  const double sigma = 0.1;
  const double rSwitch = std::sqrt(2.0 * 150.0) * sigma;
  for (double d = 0.0; d < rSwitch + 1.0; d += 0.01) {
    const double below = gaussianCollisionProbability(d, rSwitch * (1.0 - 1e-13), sigma);
    const double above = gaussianCollisionProbability(d, rSwitch * (1.0 + 1e-13), sigma);
    ASSERT_NEAR(below, above, 2e-12 + 1e-10 * above) << "d=" << d;
  }
}

TEST(GaussianIsotropic, MonteCarloMillionSamples) {
  for (auto [d, R, s] :
       std::vector<std::array<double, 3>>{{1.0, 0.6, 0.3}, {0.4, 0.8, 0.5}, {1.5, 0.9, 0.2}}) {
    const auto mc = monteCarlo({d, 0.0}, {s * s, 0.0, s * s}, R, 1'000'000, 42);
    EXPECT_NEAR(gaussianCollisionProbability(d, R, s), mc.p, 5.0 * mc.se) << d << " " << R << " " << s;
  }
}

TEST(GaussianAnisotropic, ReducesToIsotropic) {
  for (double d : {0.0, 0.3, 1.0, 1.7, 3.0}) {
    for (double s : {0.05, 0.3, 1.0}) {
      const double iso = gaussianCollisionProbability(d, 1.0, s);
      const double q = gaussianCollisionProbability(Vec2{d * 0.6, d * 0.8}, Cov2{s * s, 0.0, s * s}, 1.0);
      EXPECT_NEAR(q, iso, 1e-10 + 1e-8 * iso) << d << " " << s;
      const double qp =
          gaussianCollisionProbabilityPolar(Vec2{d * 0.6, d * 0.8}, Cov2{s * s, 0.0, s * s}, 1.0);
      EXPECT_NEAR(qp, iso, 1e-10 + 1e-8 * iso) << d << " " << s;
    }
  }
}

TEST(GaussianAnisotropic, MonteCarloMillionSamples) {
  struct Case {
    Vec2 mean;
    Cov2 cov;
    double R;
  };
  const Case cases[] = {{{1.0, 0.2}, {0.09, 0.02, 0.01}, 0.6},
                        {{0.0, 1.2}, {0.5, -0.1, 0.04}, 0.8},
                        {{0.7, -0.7}, {0.01, 0.0, 0.25}, 0.5},
                        {{2.0, 0.0}, {1.0, 0.9, 1.0}, 1.0}};
  std::uint64_t seed = 1;
  for (const auto& c : cases) {
    const auto mc = monteCarlo(c.mean, c.cov, c.R, 1'000'000, seed++);
    const double q = gaussianCollisionProbability(c.mean, c.cov, c.R);
    EXPECT_NEAR(q, mc.p, 5.0 * mc.se) << c.mean.x << "," << c.mean.y;
    // Rotation invariance: rotating mean and covariance together leaves P unchanged.
    const double th = 0.7;
    const double cs = std::cos(th), sn = std::sin(th);
    const Vec2 m2{cs * c.mean.x - sn * c.mean.y, sn * c.mean.x + cs * c.mean.y};
    const double a = c.cov.xx, b = c.cov.xy, e = c.cov.yy;
    const Cov2 r{cs * cs * a - 2 * cs * sn * b + sn * sn * e, cs * sn * (a - e) + (cs * cs - sn * sn) * b,
                 sn * sn * a + 2 * cs * sn * b + cs * cs * e};
    EXPECT_NEAR(gaussianCollisionProbability(m2, r, c.R), q, 1e-10);
    // The polar (Foster-style) quadrature with many steps agrees: two independent methods.
    EXPECT_NEAR(gaussianCollisionProbabilityPolar(c.mean, c.cov, c.R, 16384), q, 1e-10);
    EXPECT_NEAR(gaussianCollisionProbabilityPolar(c.mean, c.cov, c.R), q, 1e-10);
  }
}

// The previous production path (whitened rays) against the Foster-style polar quadrature.
TEST(GaussianAnisotropic, WhitenedAndPolarQuadratureAgreeOnRandomCases) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> ud(0.0, 2.5), ua(0.0, 6.283185307179586), us(0.02, 0.6),
      ue(0.05, 1.0), ur(0.3, 1.5);
  for (int t = 0; t < 400; ++t) {
    const double d = ud(rng), th = ua(rng), R = ur(rng);
    const double l1 = us(rng) * us(rng) + 1e-4, l2 = l1 * ue(rng), rot = ua(rng);
    const double c = std::cos(rot), s = std::sin(rot);
    const Cov2 cov{c * c * l1 + s * s * l2, c * s * (l1 - l2), s * s * l1 + c * c * l2};
    const Vec2 mean{d * std::cos(th), d * std::sin(th)};
    const double whitened = gaussianCollisionProbabilityWhitened(mean, cov, R);
    const double polar = gaussianCollisionProbabilityPolar(mean, cov, R, 16384);
    ASSERT_NEAR(whitened, polar, 1e-9) << "d=" << d << " R=" << R << " l1=" << l1 << " l2=" << l2;
  }
}

// A random covariance with eigenvalues l1 >= l2 = l1·ratio at a random orientation.
Cov2 rotatedCov(double l1, double l2, double rot) {
  const double c = std::cos(rot), s = std::sin(rot);
  return {c * c * l1 + s * s * l2, c * s * (l1 - l2), s * s * l1 + c * c * l2};
}

// Polar quadrature with enough angle steps for the narrowest Gaussian seen from the disc centre.
double finePolar(Vec2 mean, const Cov2& cov, double R, double smin) {
  int steps = 16384;
  while (steps < 16.0 * 3.15 * (mean.norm() + R) / smin && steps < (1 << 21)) {
    steps *= 2;
  }
  return gaussianCollisionProbabilityPolar(mean, cov, R, steps);
}

// The production path (eigen-axis trapezoid) against both earlier methods on the same random cases.
TEST(GaussianAnisotropic, TrapezoidMatchesPolarAndWhitenedOnRandomCases) {
  std::mt19937_64 rng(77);
  std::uniform_real_distribution<double> ud(0.0, 2.5), ua(0.0, 6.283185307179586), us(0.02, 0.6),
      ue(0.05, 1.0), ur(0.3, 1.5);
  for (int t = 0; t < 400; ++t) {
    const double d = ud(rng), th = ua(rng), R = ur(rng);
    const double l1 = us(rng) * us(rng) + 1e-4, l2 = l1 * ue(rng);
    const Cov2 cov = rotatedCov(l1, l2, ua(rng));
    const Vec2 mean{d * std::cos(th), d * std::sin(th)};
    const double fast = gaussianCollisionProbability(mean, cov, R);
    ASSERT_NEAR(fast, gaussianCollisionProbabilityPolar(mean, cov, R, 16384), 1e-10)
        << "d=" << d << " R=" << R << " l1=" << l1 << " l2=" << l2;
    ASSERT_NEAR(fast, gaussianCollisionProbabilityWhitened(mean, cov, R), 1e-9);
  }
}

// Sigma ratios 1e-1 … 1e-3 and sigmas from 0.01 R to 2 R, against the polar quadrature with enough
// angle steps for the narrow axis. (At these ratios the polar quadrature itself carries ~1e-10 near
// P = 1, and the whitened reference up to ~1e-6 with the mean near the rim: see algorithms.md.)
TEST(GaussianAnisotropic, ExtremeAnisotropyMatchesFinePolar) {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> ud(0.0, 2.5), ua(0.0, 6.283185307179586), us(0.01, 1.2),
      ul(std::log(1e-6), std::log(1e-2)), ur(0.3, 1.5);
  int nonTrivial = 0;
  for (int t = 0; t < 40; ++t) {
    const double d = ud(rng), th = ua(rng), R = ur(rng);
    const double l1 = us(rng) * us(rng) * R * R, l2 = l1 * std::exp(ul(rng));
    const Cov2 cov = rotatedCov(l1, l2, ua(rng));
    const Vec2 mean{d * std::cos(th), d * std::sin(th)};
    const double fast = gaussianCollisionProbability(mean, cov, R);
    ASSERT_NEAR(fast, finePolar(mean, cov, R, std::sqrt(l2)), 3e-10)
        << "d=" << d << " R=" << R << " l1=" << l1 << " l2=" << l2;
    nonTrivial += (fast > 1e-6 && fast < 1.0 - 1e-6) ? 1 : 0;
  }
  EXPECT_GT(nonTrivial, 15);
}

// As the minor variance goes to 0 the probability tends to the singular covariance's closed form
// P(|m2 + s2 z| ≤ √(R² − m1²)) (mass on the line x1 = m1), linearly in λmin away from the rim and like
// √s1 where the line is tangent to the circle.
TEST(GaussianAnisotropic, NearDegenerateCovarianceTendsToTheLineLimit) {
  const double R = 1.0, s2 = 0.4, rot = 0.3;
  for (const double m1 : {0.0, 0.5, 0.9, -0.97}) {
    for (const double m2 : {0.0, 0.3, 1.1}) {
      const Vec2 mean{std::cos(rot) * m2 - std::sin(rot) * m1, std::sin(rot) * m2 + std::cos(rot) * m1};
      const double w = std::sqrt(R * R - m1 * m1);
      const double line =
          0.5 * (std::erf((w - m2) / (s2 * std::sqrt(2.0))) + std::erf((w + m2) / (s2 * std::sqrt(2.0))));
      // (The rotated covariance's determinant rounds to ±1e-18, not 0: then the trapezoid runs, whose
      // aliasing error at the chosen step is ~2e-12 relative.)
      EXPECT_NEAR(gaussianCollisionProbability(mean, rotatedCov(s2 * s2, 0.0, rot), R), line, 5e-12);
      EXPECT_NEAR(gaussianCollisionProbability(Vec2{m1, m2}, Cov2{0.0, 0.0, s2 * s2}, R), line, 1e-15);
      double prevErr = 1.0;
      for (const double s1 : {1e-2, 1e-4, 1e-6, 1e-9}) {
        const double p = gaussianCollisionProbability(mean, rotatedCov(s2 * s2, s1 * s1, rot), R);
        const double err = std::abs(p - line);
        EXPECT_LE(err, 1.0 * s1 * s1 / ((1.0 - std::abs(m1)) * (1.0 - std::abs(m1))) + 5e-12)
            << m1 << " " << m2 << " " << s1;
        EXPECT_LE(err, prevErr + 5e-12);
        prevErr = err;
      }
    }
  }
  // Line tangent to the circle (m1 = R): the singular limit is 0, approached like √(s1 R).
  const double pTangentCoarse = gaussianCollisionProbability(Vec2{0.0, 1.0}, Cov2{s2 * s2, 0.0, 1e-8}, R);
  const double pTangentFine = gaussianCollisionProbability(Vec2{0.0, 1.0}, Cov2{s2 * s2, 0.0, 1e-16}, R);
  EXPECT_GT(pTangentCoarse, 0.0);
  EXPECT_NEAR(pTangentFine / pTangentCoarse, 1e-2, 2e-3);  // s1 down 1e4 → P down ~1e2
  // And a near-degenerate case against a million-sample Monte Carlo.
  const Vec2 mean{0.2, 0.95};
  const Cov2 cov = rotatedCov(0.16, 1e-10, 0.4);
  const auto mc = monteCarlo(mean, cov, R, 1'000'000, 9);
  EXPECT_NEAR(gaussianCollisionProbability(mean, cov, R), mc.p, 5.0 * mc.se);
}

TEST(GaussianAnisotropic, SymmetriesBoundsMonotoneInRadiusAndFloor) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ud(0.0, 2.0), ua(0.0, 6.283185307179586), us(0.02, 0.8),
      ul(std::log(1e-4), 0.0), ur(0.2, 1.2);
  for (int t = 0; t < 300; ++t) {
    const double d = ud(rng), th = ua(rng), R = ur(rng);
    const double l1 = us(rng) * us(rng), l2 = l1 * std::exp(ul(rng)), rot = ua(rng);
    const Cov2 cov = rotatedCov(l1, l2, rot);
    const Vec2 mean{d * std::cos(th), d * std::sin(th)};
    const double p = gaussianCollisionProbability(mean, cov, R);
    ASSERT_GE(p, 0.0);
    ASSERT_LE(p, 1.0);
    // Point reflection, mirror image and rotation of the whole configuration leave P unchanged.
    EXPECT_NEAR(gaussianCollisionProbability(Vec2{-mean.x, -mean.y}, cov, R), p, 1e-12);
    EXPECT_NEAR(gaussianCollisionProbability(Vec2{mean.x, -mean.y}, Cov2{cov.xx, -cov.xy, cov.yy}, R), p,
                1e-12);
    const Vec2 rotated{std::cos(1.1) * mean.x - std::sin(1.1) * mean.y,
                       std::sin(1.1) * mean.x + std::cos(1.1) * mean.y};
    EXPECT_NEAR(gaussianCollisionProbability(rotated, rotatedCov(l1, l2, rot + 1.1), R), p, 1e-11);
    // A larger disc contains the smaller one.
    ASSERT_GE(gaussianCollisionProbability(mean, cov, R * 1.05), p - 1e-12);
    // The floor early-out only ever drops probabilities below the floor.
    const double floored = gaussianCollisionProbability(mean, cov, R, 1e-4);
    ASSERT_TRUE(floored == p || (floored == 0.0 && p < 1e-4)) << p << " " << floored;
  }
}

TEST(GaussianModel, SymmetricFlooredAndCullIsSafe) {
  Gaussian m(1e-4);
  const Disc a{0, 0, 0.3, 0.1};
  const Disc b{0.9, 0.1, 0.4, 0.2};
  EXPECT_EQ(m.pair(a, b), m.pair(b, a));
  EXPECT_GT(m.pair(a, b), 0.0);  // discs do not touch (gap 0.2 m) but are uncertain: not 0
  EXPECT_GE(m.reach(a) + m.reach(b), m.cullDistance(a, b));
  // Just beyond the cull distance the exact probability is already below the floor.
  const double c = m.cullDistance(a, b);
  const double sigma = std::sqrt(0.1 * 0.1 + 0.2 * 0.2);
  EXPECT_LT(gaussianCollisionProbability(c, 0.7, sigma), 1e-4);
  EXPECT_EQ(m.pair(a, Disc{c, 0, 0.4, 0.2}), 0.0);
  // Far apart: 0; concentric with small sigma: ~1.
  EXPECT_EQ(m.pair(a, Disc{5, 0, 0.4, 0.2}), 0.0);
  EXPECT_NEAR(m.pair(Disc{0, 0, 0.5, 0.01}, Disc{0, 0, 0.5, 0.01}), 1.0, 1e-12);
}

}  // namespace
}  // namespace fleet::risk
