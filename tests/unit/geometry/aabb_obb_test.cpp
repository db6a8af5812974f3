#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <Eigen/Geometry>
#include <random>
#include <set>

#include "fleet/core/angles.hpp"
#include "fleet/geometry/aabb.hpp"
#include "fleet/geometry/obb.hpp"

using namespace fleet::geometry;
using Eigen::Vector3d;

namespace {

Eigen::Matrix3d randomRotation(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  Eigen::Quaterniond q(n(rng), n(rng), n(rng), n(rng));
  q.normalize();
  return q.toRotationMatrix();
}

Obb3 randomBox(std::mt19937& rng, const Vector3d& c) {
  std::uniform_real_distribution<double> h(0.2, 1.5);
  return {c, randomRotation(rng), Vector3d(h(rng), h(rng), h(rng))};
}

Vector3d axisVector(const Obb3& a, const Obb3& b, int axis) {
  if (axis < 3) {
    return a.axes.col(axis);
  }
  if (axis < 6) {
    return b.axes.col(axis - 3);
  }
  return a.axes.col((axis - 6) / 3).cross(b.axes.col((axis - 6) % 3));
}

// Independent check of a separation claim: project all 8 vertices of each box on the axis.
bool verticesSeparated(const Obb3& a, const Obb3& b, const Vector3d& v) {
  auto range = [&](const Obb3& o) {
    double lo = 1e300, hi = -1e300;
    for (int s = 0; s < 8; ++s) {
      Vector3d p = o.center;
      for (int k = 0; k < 3; ++k) {
        p += ((s >> k) & 1 ? 1.0 : -1.0) * o.half(k) * o.axes.col(k);
      }
      lo = std::min(lo, p.dot(v));
      hi = std::max(hi, p.dot(v));
    }
    return std::pair{lo, hi};
  };
  const auto [alo, ahi] = range(a);
  const auto [blo, bhi] = range(b);
  return ahi < blo || bhi < alo;
}

// Independent check of an intersection claim: alternating projections find a common point.
bool commonPoint(const Obb3& a, const Obb3& b, double tol) {
  Vector3d p = 0.5 * (a.center + b.center);
  auto clampTo = [](const Obb3& o, const Vector3d& x) {
    Vector3d l = o.axes.transpose() * (x - o.center);
    l = l.cwiseMax(-o.half).cwiseMin(o.half);
    return Vector3d(o.center + o.axes * l);
  };
  for (int k = 0; k < 20000; ++k) {
    p = clampTo(b, clampTo(a, p));
    if (a.contains(p, tol) && b.contains(p, tol)) {
      return true;
    }
  }
  return false;
}

}  // namespace

TEST(Aabb, ThesisCornerTestMissesCrossOverlap) {
  const Aabb3 a = Aabb3::fromCenterSize(Vector3d::Zero(), Vector3d(10, 2, 2));
  const Aabb3 b = Aabb3::fromCenterSize(Vector3d::Zero(), Vector3d(2, 10, 2));
  EXPECT_TRUE(overlaps(a, b));
  EXPECT_FALSE(overlapsThesisCorner(a, b));  // the thesis rule (2.2) says "no collision"
}

TEST(Aabb, CornerTestImpliesIntervalTestAndSeparationIsExact) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-3, 3), s(0.1, 4);
  int crossCases = 0;
  for (int k = 0; k < 5000; ++k) {
    const Aabb3 a = Aabb3::fromCenterSize({u(rng), u(rng), u(rng)}, {s(rng), s(rng), s(rng)});
    const Aabb3 b = Aabb3::fromCenterSize({u(rng), u(rng), u(rng)}, {s(rng), s(rng), s(rng)});
    const bool correct = overlaps(a, b);
    if (overlapsThesisCorner(a, b)) {
      EXPECT_TRUE(correct);
    } else if (correct) {
      ++crossCases;
    }
    // Reference: the intersection box is non-empty.
    const Vector3d lo = a.min.cwiseMax(b.min);
    const Vector3d hi = a.max.cwiseMin(b.max);
    EXPECT_EQ(correct, (lo.array() <= hi.array()).all());
  }
  EXPECT_GT(crossCases, 0);
}

TEST(Aabb2, RayEntryAndDistance) {
  const Aabb2 b{{1, 1}, {3, 2}};
  EXPECT_DOUBLE_EQ(*b.rayEntry({0, 1.5}, {1, 0}, 10), 1.0);
  EXPECT_FALSE(b.rayEntry({0, 1.5}, {-1, 0}, 10).has_value());
  EXPECT_DOUBLE_EQ(b.distanceTo({0, 1.5}), 1.0);
  EXPECT_DOUBLE_EQ(b.distanceTo({2, 1.5}), 0.0);
  EXPECT_DOUBLE_EQ(b.distanceTo({6, 6}), 5.0);
}

TEST(ObbSat, SeedDistanceCases) {
  const Obb3 a{};
  EXPECT_TRUE(satTest(a, a.translated({1.9, 0, 0})).intersect);
  const auto far = satTest(a, a.translated({2.1, 0, 0}));
  EXPECT_FALSE(far.intersect);
  EXPECT_EQ(far.separatingAxis, 0);
  EXPECT_TRUE(satTest(a, a.translated({2.0, 0, 0})).intersect);  // touching is contact (strict R > R0+R1)
}

TEST(ObbSat, ParallelEdgesNeverFalselySeparate) {
  const Obb3 a{};
  Obb3 b = a.translated({1.5, 1.5, 0.0});
  EXPECT_TRUE(satTest(a, b).intersect);
  b.axes = Eigen::AngleAxisd(1e-12, Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_TRUE(satTest(a, b).intersect);
  b.axes = Eigen::AngleAxisd(fleet::kPi / 2, Vector3d::UnitY()).toRotationMatrix();
  EXPECT_TRUE(satTest(a, b).intersect);
}

TEST(ObbSat, RandomBoxesAgreeWithIndependentChecks) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-2.5, 2.5);
  int sep = 0, inter = 0, edgeEdge = 0;
  for (int k = 0; k < 3000; ++k) {
    const Obb3 a = randomBox(rng, Vector3d::Zero());
    const Obb3 b = randomBox(rng, {u(rng), u(rng), u(rng)});
    const SatResult r = satTest(a, b, 0.0);
    if (r.intersect) {
      ++inter;
      EXPECT_TRUE(commonPoint(a, b, 1e-7)) << "case " << k;
    } else {
      ++sep;
      EXPECT_TRUE(verticesSeparated(a, b, axisVector(a, b, r.separatingAxis))) << "case " << k;
      // The first 6 axes did not separate when a cross axis is reported.
      if (r.separatingAxis >= 6) {
        ++edgeEdge;
        for (int ax = 0; ax < 6; ++ax) {
          EXPECT_FALSE(verticesSeparated(a, b, axisVector(a, b, ax)));
        }
      }
    }
  }
  EXPECT_GT(sep, 300);
  EXPECT_GT(inter, 300);
  EXPECT_GT(edgeEdge, 0);  // edge-edge-only separations occur and are caught
}

TEST(ObbContact, FaceVertexIsTheVertexOfB) {
  const Obb3 a{};
  Obb3 b;
  b.axes = (Eigen::AngleAxisd(0.4, Vector3d::UnitZ()) * Eigen::AngleAxisd(0.3, Vector3d::UnitY()) *
            Eigen::AngleAxisd(0.2, Vector3d::UnitX()))
               .toRotationMatrix();
  b.half = {0.5, 0.7, 0.9};
  Vector3d y;
  for (int j = 0; j < 3; ++j) {
    y(j) = -(b.axes(0, j) > 0 ? 1.0 : -1.0) * b.half(j);  // y_j = -sigma sgn(c_0j) b_j, sigma = +1
  }
  const Vector3d vertex(1.0, 0.2, -0.3);
  b.center = vertex - b.axes * y;
  const Vector3d p = contactPoint(a, b, 0);
  EXPECT_NEAR((p - vertex).norm(), 0.0, 1e-12);
}

TEST(ObbContact, FaceFaceGivesPointInPatch) {
  const Obb3 a{};
  Obb3 b = a.translated({2.0, 0.5, 0.3});
  b.axes = Eigen::AngleAxisd(0.3, Vector3d::UnitX()).toRotationMatrix();
  b.center = {2.0, 0.5, 0.3};
  const Vector3d p = contactPoint(a, b, 0);
  EXPECT_TRUE(a.contains(p, 1e-9));
  EXPECT_TRUE(b.contains(p, 1e-9));
}

TEST(ObbContact, RandomFirstContactsLieInBothBoxesOnAll15Axes) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0, 1);
  std::set<int> axesSeen;
  for (int k = 0; k < 3000; ++k) {
    const Obb3 a = randomBox(rng, Vector3d::Zero());
    Obb3 b = randomBox(rng, Vector3d::Zero());
    const Vector3d dir = Vector3d(n(rng), n(rng), n(rng)).normalized();
    double lo = 0.0, hi = 10.0;  // b at lo*dir intersects, at hi*dir is separated
    for (int it = 0; it < 200 && hi - lo > 1e-13; ++it) {
      const double mid = 0.5 * (lo + hi);
      (satTest(a, b.translated(mid * dir), 0.0).intersect ? lo : hi) = mid;
    }
    const int axis = satTest(a, b.translated(hi * dir), 0.0).separatingAxis;
    ASSERT_GE(axis, 0);
    axesSeen.insert(axis);
    const Obb3 bt = b.translated(lo * dir);
    const Vector3d p = contactPoint(a, bt, axis);
    const double tol = 1e-9 * 10.0;
    EXPECT_TRUE(a.contains(p, tol) && bt.contains(p, tol)) << "case " << k << " axis " << axis;
  }
  EXPECT_EQ(axesSeen.size(), 15u);
}

TEST(ObbContact, FirstContactOfApproachingCubes) {
  const Obb3 a{};
  const Obb3 b = a.translated({5.0, 0.2, 0.0});
  const auto fc = firstContact(a, Vector3d::Zero(), b, Vector3d(-1, 0, 0), 0.1, 10.0);
  ASSERT_TRUE(fc.has_value());
  EXPECT_NEAR(fc->time, 3.0, 1e-9);
  EXPECT_EQ(fc->axis, 0);
  EXPECT_NEAR(fc->point.x(), 1.0, 1e-9);
  EXPECT_FALSE(firstContact(a, Vector3d::Zero(), b, Vector3d(1, 0, 0), 0.1, 10.0).has_value());
}

TEST(Obb2, SeparatingAxes) {
  const Obb2 a{{0, 0}, 0.0, {1, 1}};
  EXPECT_TRUE(overlaps(a, Obb2{{1.9, 0}, 0.0, {1, 1}}));
  EXPECT_FALSE(overlaps(a, Obb2{{2.1, 0}, 0.0, {1, 1}}));
  // Rotated by 45 degrees: its corner reaches sqrt(2) along x.
  EXPECT_TRUE(overlaps(a, Obb2{{2.4, 0}, fleet::kPi / 4, {1, 1}}));
  EXPECT_FALSE(overlaps(a, Obb2{{2.45, 0}, fleet::kPi / 4, {1, 1}}));
}
