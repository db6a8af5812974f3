#include "fleet/risk/overlap_ratio.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace fleet::risk {
namespace {

constexpr double kPi = std::numbers::pi;

// Independent check: the intersection area as ∫ (length of the vertical chord common to both discs) dx,
// integrated with composite Simpson on many panels. Shares no formula with the lens expression.
double numericIntersectionArea(double r1, double r2, double d) {
  auto chord = [](double r, double cx, double x, double& lo, double& hi) {
    const double u = r * r - (x - cx) * (x - cx);
    if (u <= 0.0) {
      lo = hi = 0.0;
      return false;
    }
    lo = -std::sqrt(u);
    hi = std::sqrt(u);
    return true;
  };
  const double a = std::max(-r1, d - r2);
  const double b = std::min(r1, d + r2);
  if (b <= a) {
    return 0.0;
  }
  const int n = 200000;
  const double h = (b - a) / n;
  double sum = 0.0;
  for (int i = 0; i <= n; ++i) {
    const double x = a + h * i;
    double l1 = 0, h1 = 0, l2 = 0, h2 = 0;
    double f = 0.0;
    if (chord(r1, 0.0, x, l1, h1) && chord(r2, d, x, l2, h2)) {
      f = std::max(0.0, std::min(h1, h2) - std::max(l1, l2));
    }
    const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
    sum += w * f;
  }
  return sum * h / 3.0;
}

// Literal thesis eq. (3.2) with the corrected cap heights h = r − x.
double thesisArea(double r1, double r2, double d) {
  const double h1 = r1 - (r1 * r1 + d * d - r2 * r2) / (2 * d);
  const double h2 = r2 - (r2 * r2 + d * d - r1 * r1) / (2 * d);
  return r1 * r1 * std::acos((r1 - h1) / r1) - (r1 - h1) * std::sqrt(r1 * r1 - (r1 - h1) * (r1 - h1)) +
         r2 * r2 * std::acos((r2 - h2) / r2) - (r2 - h2) * std::sqrt(r2 * r2 - (r2 - h2) * (r2 - h2));
}

TEST(OverlapRatio2D, ThesisSpecialCases) {
  EXPECT_DOUBLE_EQ(discOverlapRatio(1.0, 1.0, 0.0), 1.0);     // identical discs
  EXPECT_DOUBLE_EQ(discOverlapRatio(0.5, 0.3, 0.8), 0.0);     // tangent
  EXPECT_DOUBLE_EQ(discOverlapRatio(0.5, 0.3, 5.0), 0.0);     // apart
  EXPECT_DOUBLE_EQ(discOverlapRatio(0.5, 0.3, 0.1), 0.36);    // containment: (0.3/0.5)²
  EXPECT_DOUBLE_EQ(discOverlapRatio(50.0, 30.0, 0.0), 0.36);  // Table 3.1 case 1 radii, concentric
  EXPECT_DOUBLE_EQ(discIntersectionArea(0.5, 0.3, 0.1), kPi * 0.09);
  // Two unit discs at distance 1: lens area 2π/3 − √3/2.
  const double lens = 2.0 * kPi / 3.0 - std::sqrt(3.0) / 2.0;
  EXPECT_NEAR(discIntersectionArea(1.0, 1.0, 1.0), lens, 1e-14);
  EXPECT_NEAR(discOverlapRatio(1.0, 1.0, 1.0), lens / (2 * kPi - lens), 1e-14);
}

TEST(OverlapRatio2D, MatchesNumericIntegrationAndThesisFormula) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> ur(0.1, 2.0);
  for (int i = 0; i < 40; ++i) {
    const double r1 = ur(rng);
    const double r2 = ur(rng);
    std::uniform_real_distribution<double> ud(std::abs(r1 - r2) + 1e-3, r1 + r2 - 1e-3);
    const double d = ud(rng);
    const double a = discIntersectionArea(r1, r2, d);
    EXPECT_NEAR(a, numericIntersectionArea(r1, r2, d), 1e-7 * (r1 * r1 + r2 * r2))
        << r1 << " " << r2 << " " << d;
    EXPECT_NEAR(a, thesisArea(r1, r2, d), 1e-10 * (r1 * r1 + r2 * r2));
  }
}

TEST(OverlapRatio2D, SymmetricBoundedAndMonotoneInDistance) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> ur(0.05, 3.0);
  for (int i = 0; i < 200; ++i) {
    const double r1 = ur(rng);
    const double r2 = ur(rng);
    double prev = 2.0;
    for (double d = 0.0; d <= r1 + r2 + 0.1; d += (r1 + r2) / 97.0) {
      const double p = discOverlapRatio(r1, r2, d);
      ASSERT_GE(p, 0.0);
      ASSERT_LE(p, 1.0);
      ASSERT_EQ(p, discOverlapRatio(r2, r1, d));
      ASSERT_LE(p, prev + 1e-15) << r1 << " " << r2 << " " << d;
      prev = p;
    }
  }
}

TEST(OverlapRatio2D, ContinuousAtTangencyAndContainment) {
  for (double r2 : {0.3, 0.5, 0.999999, 1.0}) {
    const double r1 = 1.0;
    const double dc = std::abs(r1 - r2);
    const double inner = discOverlapRatio(r1, r2, dc);
    for (double eps : {1e-3, 1e-6, 1e-9, 1e-12}) {
      const double p = discOverlapRatio(r1, r2, dc + eps);
      ASSERT_TRUE(std::isfinite(p));
      EXPECT_NEAR(p, inner, 10.0 * std::sqrt(eps)) << r2 << " " << eps;
      const double t = discOverlapRatio(r1, r2, r1 + r2 - eps);
      ASSERT_TRUE(std::isfinite(t));
      EXPECT_GE(t, 0.0);
      EXPECT_LT(t, 10.0 * std::pow(eps, 1.5) + 1e-15);
    }
  }
}

TEST(OverlapRatio3D, SpecialCasesAndNumericVolume) {
  EXPECT_DOUBLE_EQ(sphereOverlapRatio(1.0, 1.0, 0.0), 1.0);
  EXPECT_DOUBLE_EQ(sphereOverlapRatio(1.0, 1.0, 2.0), 0.0);
  EXPECT_DOUBLE_EQ(sphereOverlapRatio(0.5, 0.25, 0.1), 0.125);
  // Two unit spheres at distance 1: lens volume 5π/12.
  EXPECT_NEAR(sphereIntersectionVolume(1.0, 1.0, 1.0), 5.0 * kPi / 12.0, 1e-14);
  // Volume as ∫ (area of the common cross-section disc) dx, Simpson.
  auto numeric = [](double r1, double r2, double d) {
    const double a = std::max(-r1, d - r2);
    const double b = std::min(r1, d + r2);
    const int n = 100000;
    const double h = (b - a) / n;
    double s = 0.0;
    for (int i = 0; i <= n; ++i) {
      const double x = a + h * i;
      const double q = std::min(r1 * r1 - x * x, r2 * r2 - (x - d) * (x - d));
      const double w = (i == 0 || i == n) ? 1.0 : (i % 2 == 1 ? 4.0 : 2.0);
      s += w * (q > 0 ? kPi * q : 0.0);
    }
    return s * h / 3.0;
  };
  for (auto [r1, r2, d] : std::vector<std::array<double, 3>>{{1, 1, 1}, {0.5, 0.6, 0.7}, {2, 0.5, 1.8}}) {
    EXPECT_NEAR(sphereIntersectionVolume(r1, r2, d), numeric(r1, r2, d), 1e-8);
  }
  double prev = 1.0;
  for (double d = 0.0; d < 1.2; d += 0.01) {
    const double p = sphereOverlapRatio(0.5, 0.6, d);
    EXPECT_LE(p, prev + 1e-15);
    EXPECT_EQ(p, sphereOverlapRatio(0.6, 0.5, d));
    EXPECT_TRUE(std::isfinite(sphereOverlapRatio(0.5, 0.6, 1.1 - 1e-12)));
    prev = p;
  }
}

TEST(OverlapRatioScene, ReducesToPairAndIsBounded) {
  const std::vector<Disc> two{{0, 0, 1, 0}, {1, 0, 1, 0}};
  EXPECT_NEAR(sceneOverlapRatio(two), discOverlapRatio(1, 1, 1), 1e-15);
  const std::vector<Disc> one{{0, 0, 1, 0}};
  EXPECT_EQ(sceneOverlapRatio(one), 0.0);
  // Three discs: by hand, Σ∩ / Σ∪ over the three pairs.
  const std::vector<Disc> three{{0, 0, 1, 0}, {1, 0, 1, 0}, {5, 0, 0.5, 0}};
  const double lens = discIntersectionArea(1, 1, 1);
  const double den = (2 * kPi - lens) + (kPi + 0.25 * kPi) + (kPi + 0.25 * kPi);
  EXPECT_NEAR(sceneOverlapRatio(three), lens / den, 1e-15);
  const std::vector<Sphere> s2{{0, 0, 0, 1}, {0, 0, 1, 1}};
  EXPECT_NEAR(sceneOverlapRatio(s2), sphereOverlapRatio(1, 1, 1), 1e-15);
}

TEST(OverlapRatioModel, CullDistanceIsExact) {
  OverlapRatio m;
  const Disc a{0, 0, 0.4, 0.1};
  const Disc b{0.7, 0, 0.3, 0.1};
  EXPECT_EQ(m.cullDistance(a, b), 0.7);
  EXPECT_EQ(m.pair(a, b), 0.0);
  EXPECT_GT(m.pair(a, Disc{0.69, 0, 0.3, 0}), 0.0);
  EXPECT_GE(m.reach(a) + m.reach(b), m.cullDistance(a, b));
}

}  // namespace
}  // namespace fleet::risk
