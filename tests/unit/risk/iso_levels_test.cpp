#include "fleet/risk/iso_levels.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace fleet::risk {
namespace {

TEST(IsoLevels, DefinitionBoundaries) {
  EXPECT_EQ(isoLevel(0.0, 10), 0);  // p = 0 is level 0
  EXPECT_EQ(isoLevel(-0.1, 10), 0);
  EXPECT_EQ(isoLevel(std::nan(""), 10), 0);
  EXPECT_EQ(isoLevel(1e-300, 10), 1);  // 0 < p <= 0.1
  EXPECT_EQ(isoLevel(0.1, 10), 1);     // upper bound belongs to the level
  EXPECT_EQ(isoLevel(std::nextafter(0.1, 1.0), 10), 2);
  EXPECT_EQ(isoLevel(0.3, 10), 3);  // ceil(0.3·10) = 4 would be wrong
  EXPECT_EQ(isoLevel(0.7, 10), 7);
  EXPECT_EQ(isoLevel(1.0, 10), 10);
  EXPECT_EQ(isoLevel(1.0, 5), 5);
  EXPECT_EQ(isoLevel(0.5, 5), 3);  // 0.4 < 0.5 <= 0.6
  EXPECT_EQ(isoLevel(0.95, 20), 19);
}

TEST(IsoLevels, EveryLevelIsTheIntervalOfDefinition36) {
  for (int K : {1, 5, 10, 15, 20, 255}) {
    for (int n = 0; n <= 100000; ++n) {
      const double p = n / 100000.0;
      const int l = isoLevel(p, K);
      if (p == 0.0) {
        ASSERT_EQ(l, 0);
        continue;
      }
      ASSERT_GE(l, 1);
      ASSERT_LE(l, K);
      ASSERT_GT(p, levelUpperBound(l - 1, K)) << p << " K=" << K;
      ASSERT_LE(p, levelUpperBound(l, K)) << p << " K=" << K;
    }
  }
}

TEST(IsoLevels, ClassifyAndComplement) {
  ProbabilityGrid g{GridSpec{0, 0, 1, 3, 1}, {0.0, 0.25, 1.0}};
  const LevelGrid l = classifyLevels(g, 4);
  EXPECT_EQ(l.level, (std::vector<std::uint8_t>{0, 1, 4}));
  EXPECT_EQ(complementMap(g), (std::vector<double>{1.0, 0.75, 0.0}));
}

}  // namespace
}  // namespace fleet::risk
