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
    const double fast = gaussianCollisionProbability(mean, cov, R);
    const double polar = gaussianCollisionProbabilityPolar(mean, cov, R, 16384);
    ASSERT_NEAR(fast, polar, 1e-9) << "d=" << d << " R=" << R << " l1=" << l1 << " l2=" << l2;
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
