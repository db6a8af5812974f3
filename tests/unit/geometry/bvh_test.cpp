#include <gtest/gtest.h>

#include <random>

#include "fleet/geometry/bvh.hpp"

using namespace fleet;
using namespace fleet::geometry;

namespace {

std::vector<Primitive> randomPrims(std::mt19937& rng, int n, double world) {
  std::uniform_real_distribution<double> u(0, world), s(0.05, 2.0);
  std::vector<Primitive> prims;
  for (int i = 0; i < n; ++i) {
    const Vec2 c{u(rng), u(rng)};
    if (i % 3 == 0) {
      prims.push_back(Primitive::makeDisc(c, 0.5 * s(rng)));
    } else {
      prims.push_back(Primitive::makeBox(Aabb2::fromCenterSize(c, {s(rng), s(rng)})));
    }
  }
  return prims;
}

}  // namespace

TEST(Bvh, StructureInvariants) {
  std::mt19937 rng(1);
  for (int n : {1, 2, 5, 17, 1000}) {
    const Bvh2 bvh(randomPrims(rng, n, 100.0), 4);
    EXPECT_TRUE(bvh.checkInvariants()) << n;
    EXPECT_LE(bvh.depth(), 2 + static_cast<int>(std::ceil(std::log2(std::max(1, n)))));
  }
}

TEST(Bvh, QueriesMatchBruteForce) {
  std::mt19937 rng(2);
  const auto prims = randomPrims(rng, 3000, 200.0);
  const Bvh2 bvh(prims, 4);
  std::uniform_real_distribution<double> u(-10, 210), s(0.1, 15), a(-3.2, 3.2);
  for (int k = 0; k < 1000; ++k) {
    const Aabb2 q = Aabb2::fromCenterSize({u(rng), u(rng)}, {s(rng), s(rng)});
    EXPECT_EQ(bvh.overlapping(q), bruteOverlapping(prims, q));
    const Vec2 p{u(rng), u(rng)};
    const auto nb = bvh.nearest(p);
    const auto nr = bruteNearest(prims, p);
    EXPECT_DOUBLE_EQ(nb.distance, nr.distance);
    const double r = s(rng);
    std::vector<int> discRef;
    for (std::size_t i = 0; i < prims.size(); ++i) {
      if (prims[i].overlapsDisc(p, r)) {
        discRef.push_back(static_cast<int>(i));
      }
    }
    EXPECT_EQ(bvh.overlappingDisc(p, r), discRef);
    EXPECT_EQ(bvh.anyOverlapDisc(p, r), !discRef.empty());
    const double ang = a(rng);
    const Vec2 dir{std::cos(ang), std::sin(ang)};
    const auto rb = bvh.raycast(p, dir, 50.0);
    const auto rr = bruteRaycast(prims, p, dir, 50.0);
    ASSERT_EQ(rb.has_value(), rr.has_value());
    if (rb) {
      EXPECT_DOUBLE_EQ(rb->range, rr->range);
    }
  }
}

TEST(Bvh, TreeVsTreeMatchesBrutePairsWithLeafCase) {
  std::mt19937 rng(3);
  int hits = 0;
  for (int k = 0; k < 200; ++k) {
    const auto pa = randomPrims(rng, 20, 60.0);
    auto pb = randomPrims(rng, 20, 60.0);
    const Bvh2 a(pa, 2), b(pb, 2);
    bool brute = false;
    for (const auto& x : pa) {
      for (const auto& y : pb) {
        brute = brute ||
                (y.kind == Primitive::Kind::Box ? x.overlaps(y.box) : x.overlapsDisc(y.center, y.radius));
      }
    }
    std::int64_t tests = 0;
    EXPECT_EQ(a.intersects(b, &tests), brute);
    EXPECT_LE(tests, 1 + static_cast<std::int64_t>(a.nodeCount()) * b.nodeCount());
    hits += brute ? 1 : 0;
  }
  EXPECT_GT(hits, 10);
  EXPECT_LT(hits, 190);
  // Two single-leaf trees that overlap: the literal pseudocode would answer false.
  const Bvh2 one({Primitive::makeBox({{0, 0}, {1, 1}})}), two({Primitive::makeDisc({1.2, 0.5}, 0.3)});
  EXPECT_TRUE(one.intersects(two));
  // Disjoint roots: exactly one bounding-volume test.
  const Bvh2 far({Primitive::makeBox({{10, 10}, {11, 11}}), Primitive::makeBox({{12, 10}, {13, 11}})});
  std::int64_t tests = 0;
  EXPECT_FALSE(one.intersects(far, &tests));
  EXPECT_EQ(tests, 1);
}
