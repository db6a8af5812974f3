#include "fleet/risk/reference_algorithm.hpp"

#include <gtest/gtest.h>

#include "fleet/risk/gaussian.hpp"
#include "fleet/risk/overlap_ratio.hpp"
#include "fleet/risk/thesis_cases.hpp"

#include <algorithm>

namespace fleet::risk {
namespace {

AlignedSource track(SourceKind kind, std::vector<Disc> discs) {
  AlignedSource s{kind, {}};
  for (const auto& d : discs) {
    s.steps.emplace_back(d);
  }
  return s;
}

TEST(ReferenceAlgorithm, TwoStaticDiscs) {
  const GridSpec spec{-3.0, -3.0, 0.1, 60, 60};
  const std::vector<AlignedSource> src{track(SourceKind::kRobot, {{0, 0, 1, 0}}),
                                       track(SourceKind::kRobot, {{1, 0, 1, 0}})};
  const auto g = referenceProbabilityGrid(spec, src, OverlapRatio{});
  const double p = discOverlapRatio(1, 1, 1);
  for (int j = 0; j < spec.height; ++j) {
    for (int i = 0; i < spec.width; ++i) {
      const double x = spec.cellCentreX(i), y = spec.cellCentreY(j);
      const bool in = x * x + y * y <= 1.0 || (x - 1) * (x - 1) + y * y <= 1.0;
      ASSERT_EQ(g.p[spec.index(i, j)], in ? p : 0.0);
    }
  }
}

TEST(ReferenceAlgorithm, TimeMaximumOfAPassingDisc) {
  // Disc 2 passes through disc 1 along the x axis; the centre cell sees the concentric moment (p = 1).
  const GridSpec spec{-4.05, -2.05, 0.1, 81, 41};
  std::vector<Disc> moving;
  for (int k = 0; k <= 40; ++k) {
    moving.push_back({-2.0 + 0.1 * k, 0, 1, 0});
  }
  const std::vector<AlignedSource> src{track(SourceKind::kRobot, std::vector<Disc>(41, Disc{0, 0, 1, 0})),
                                       track(SourceKind::kHuman, moving)};
  const auto g = referenceProbabilityGrid(spec, src, OverlapRatio{});
  EXPECT_DOUBLE_EQ(g.p[spec.index(40, 20)], 1.0);  // (0, 0)
  // Cell (-2.5, 0) is only inside the moving disc while its centre is in [-2, -1.5]: max p at d = 1.5.
  EXPECT_DOUBLE_EQ(g.p[spec.index(15, 20)], discOverlapRatio(1, 1, 1.5));
  EXPECT_EQ(g.p[spec.index(0, 0)], 0.0);
  const auto scene = referenceSceneIndex(src);
  ASSERT_EQ(scene.size(), 41u);
  EXPECT_DOUBLE_EQ(scene[20], 1.0);
  EXPECT_EQ(scene[0], 0.0);  // tangent at d = 2
}

TEST(ReferenceAlgorithm, PairPolicySkipsHumanPairsByDefault) {
  const GridSpec spec{-2, -2, 0.5, 8, 8};
  const std::vector<AlignedSource> src{track(SourceKind::kHuman, {{0, 0, 1, 0}}),
                                       track(SourceKind::kHuman, {{0.5, 0, 1, 0}})};
  const auto none = referenceProbabilityGrid(spec, src, OverlapRatio{});
  for (double v : none.p) {
    EXPECT_EQ(v, 0.0);
  }
  const auto some = referenceProbabilityGrid(spec, src, OverlapRatio{}, PairPolicy{true});
  EXPECT_GT(some.p[spec.index(4, 4)], 0.0);
}

TEST(ReferenceAlgorithm, GaussianScoresDiscsThatDoNotTouch) {
  const GridSpec spec{-2, -2, 0.1, 60, 40};
  const std::vector<AlignedSource> src{track(SourceKind::kRobot, {{0, 0, 0.4, 0.2}}),
                                       track(SourceKind::kRobot, {{1.0, 0, 0.4, 0.2}})};
  EXPECT_EQ(referenceProbabilityGrid(spec, src, OverlapRatio{}).p[spec.index(20, 20)], 0.0);
  const auto g = referenceProbabilityGrid(spec, src, Gaussian{1e-4});
  EXPECT_NEAR(g.p[spec.index(20, 20)], gaussianCollisionProbability(1.0, 0.8, std::sqrt(0.08)), 1e-13);
}

TEST(ReferenceAlgorithm, Spheres3D) {
  const GridSpec3 spec{-2, -2, -2, 0.25, 17, 17, 17};
  const std::vector<std::vector<Sphere>> tracks{{{0, 0, 0, 1}, {0, 0, 0, 1}}, {{0, 0, 1, 1}, {0, 0, 0, 1}}};
  const auto g = referenceProbabilityGrid3(spec, tracks);
  EXPECT_DOUBLE_EQ(g[spec.index(8, 8, 8)], 1.0);  // concentric at step 1
  EXPECT_DOUBLE_EQ(g[spec.index(8, 8, 15)],
                   sphereOverlapRatio(1, 1, 1));  // z = 1.75 only in sphere 2 at step 0
  EXPECT_EQ(g[spec.index(0, 0, 0)], 0.0);
}

}  // namespace
}  // namespace fleet::risk

namespace fleet::risk {
namespace {

TEST(ThesisCases, MaximaAreTheAnalyticValuesOfTheDocumentedTrajectories) {
  const auto cases = thesisCases();
  ASSERT_EQ(cases.size(), 7u);
  auto maxOf = [](const ThesisCase& c) {
    const auto g = referenceProbabilityGrid(c.grid, c.sources, OverlapRatio{}, PairPolicy{true});
    return *std::max_element(g.p.begin(), g.p.end());
  };
  EXPECT_DOUBLE_EQ(maxOf(cases[0]), 0.36);                           // r 30 inside r 50 at t = 40
  EXPECT_DOUBLE_EQ(maxOf(cases[1]), 1.0);                            // identical discs meet at t = 25
  EXPECT_NEAR(maxOf(cases[2]), 50.0 * 50.0 / (60.0 * 60.0), 1e-12);  // containment on the arc
  EXPECT_NEAR(maxOf(cases[4]), 4.0 / 9.0, 1e-12);                    // r 20 inside r 30
  EXPECT_EQ(cases[0].grid.width, 81);                                // N + 1 points
  EXPECT_NEAR(cases[0].grid.cellCentreX(80), 400.0, 1e-9);           // x_N = xmax
}

}  // namespace
}  // namespace fleet::risk
