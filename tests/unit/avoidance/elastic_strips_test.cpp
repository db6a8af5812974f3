#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "fleet/avoidance/elastic_strips.hpp"
#include "test_support.hpp"

namespace fleet::avoidance {
namespace {

// Seed 000 §7 worked values (units as in the thesis: mm).
TEST(ElasticStrips, InternalForceWorkedExample) {
  const Vec2 f = elasticInternalForce({0, 0}, {1, 1}, {2, 0}, 0.8);
  EXPECT_NEAR(f.x, 0.0, 1e-12);
  EXPECT_NEAR(f.y, -0.8, 1e-12);
  const Vec2 z = elasticInternalForce({0, 0}, {1, 1}, {2, 2}, 0.8);  // collinear, evenly spaced
  EXPECT_NEAR(z.x, 0.0, 1e-12);
  EXPECT_NEAR(z.y, 0.0, 1e-12);
}

TEST(ElasticStrips, OriginalExternalForceWorkedExample) {
  // d_safe 1000, d_r 350 -> d_o 1350; d_obs,min 1000, K_r 0.6 -> |F| = 210, from obstacle to robot.
  const Vec2 f = elasticExternalForce({0, 1000}, {0, 0}, 1000.0, 1000.0 + 350.0, 0.6);
  EXPECT_NEAR(f.x, 0.0, 1e-9);
  EXPECT_NEAR(f.y, 210.0, 1e-9);
  EXPECT_EQ(elasticExternalForce({0, 1350}, {0, 0}, 1350.0, 1350.0, 0.6), (Vec2{0, 0}));
  EXPECT_EQ(elasticExternalForce({0, 2000}, {0, 0}, 2000.0, 1350.0, 0.6), (Vec2{0, 0}));
}

TEST(ElasticStrips, TwoSidedExternalForceWorkedExample) {
  // d_L 800, threshold d_safe 1000, K_r 0.6 -> 120.
  const Vec2 f = elasticExternalForce({800, 0}, {0, 0}, 800.0, 1000.0, 0.6);
  EXPECT_NEAR(f.x, 120.0, 1e-9);
  EXPECT_EQ(elasticExternalForce({1000, 0}, {0, 0}, 1000.0, 1000.0, 0.6), (Vec2{0, 0}));
}

TEST(ElasticStrips, LeftRightMinimumWorkedExample) {
  const std::vector<double> a{1200, 900, 1500, 700};
  const auto m = leftRightMinimum(a, 1000.0);
  EXPECT_TRUE(m.found);
  EXPECT_EQ(m.min_left, 900.0);
  EXPECT_EQ(m.min_right, 700.0);
  EXPECT_EQ(m.left_index, 1);
  EXPECT_EQ(m.right_index, 3);
  const std::vector<double> far{1200, 1000, 1500, 1700};
  EXPECT_FALSE(leftRightMinimum(far, 1000.0).found);
}

// Table 2.3 case 1 in metres: start (0, 0), goal (3.5, 5), K_c 0.8, K_r 0.6, d_safe 1 m, d_r 0.35 m.
// The thesis gives no obstacle; we put a 0.3 m disc centred on the start–goal line (documented).
TEST(ElasticStrips, Table23Case1TwoSidedVariantReachesGoal) {
  const Vec2 goal{3.5, 5.0};
  const auto obstacle = test::ring(goal * 0.5, 0.3, 48);
  ElasticStripsPlanner improved(ElasticVariant::kBvhTwoSided);
  const auto r = test::drive(improved, {0, 0, std::atan2(5.0, 3.5)}, {goal}, obstacle, 1500, {}, 0.35);
  EXPECT_TRUE(r.reached);
  EXPECT_GT(r.min_clearance, 0.0);
}

TEST(ElasticStrips, Table23Case1OriginalDoesNotGetPast) {
  // The original's single external force is collinear with the internal one on the line: the
  // robot stalls in front of the obstacle or hits it (thesis Fig. 2.26), never reaching the goal.
  const Vec2 goal{3.5, 5.0};
  const auto obstacle = test::ring(goal * 0.5, 0.3, 48);
  ElasticStripsPlanner original(ElasticVariant::kOriginal);
  const auto r = test::drive(original, {0, 0, std::atan2(5.0, 3.5)}, {goal}, obstacle, 1500, {}, 0.35);
  EXPECT_FALSE(r.reached);
}

}  // namespace
}  // namespace fleet::avoidance
