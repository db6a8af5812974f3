// The simulator's record of how far the robots' own estimates are from the truth.

#include "fleet/sim/localization_error.hpp"

#include <gtest/gtest.h>

namespace fleet::sim {
namespace {

constexpr std::int64_t kStep = 100'000'000;  // 0.1 s

TEST(LocalizationErrorLog, ComparesEachEstimateWithTheTruthOfItsOwnInstant) {
  LocalizationErrorLog log(1.0, {{1.0, 2.0}});
  // Two robots moving along x at 1 m/s; estimates arrive a step late but carry their stamp.
  for (int k = 0; k < 30; ++k) {
    const double x = 0.1 * k;
    log.truth(k * kStep, {{x, 0.0, 0.0}, {x, 5.0, 0.0}});
    if (k > 0) {
      const double prev = 0.1 * (k - 1);
      log.estimate(0, (k - 1) * kStep, {prev + 0.03, 0.04, 0.0});  // 5 cm off
      log.estimate(1, (k - 1) * kStep, {prev, 5.0, 0.1});          // on the spot, 0.1 rad off
    }
  }
  log.estimate(0, 999 * kStep, {0, 0, 0});  // an instant never seen
  EXPECT_EQ(log.samples(), 58u);
  EXPECT_EQ(log.unmatched(), 1u);
  const auto j = log.toJson();
  ASSERT_EQ(j["series"].size(), 3u);  // bins [0,1), [1,2), [2,3)
  EXPECT_NEAR(j["series"][0]["pos_mean"].get<double>(), 0.025, 1e-9);
  EXPECT_NEAR(j["series"][0]["pos_max"].get<double>(), 0.05, 1e-9);
  EXPECT_NEAR(j["series"][0]["head_max"].get<double>(), 0.1, 1e-9);
  EXPECT_FALSE(j["series"][0]["hidden"].get<bool>());
  EXPECT_TRUE(j["series"][1]["hidden"].get<bool>());
  EXPECT_EQ(j["hidden_stretches"]["samples"].get<std::size_t>(), 20u);
  EXPECT_NEAR(j["overall"]["pos_max"].get<double>(), 0.05, 1e-6);
}

TEST(LocalizationErrorLog, KeepsOnlyTheRecentInstants) {
  LocalizationErrorLog log;
  for (int k = 0; k < 100; ++k) {
    log.truth(k * kStep, {{0, 0, 0}});
  }
  log.estimate(0, 99 * kStep, {0, 0, 0});
  log.estimate(0, (100 - static_cast<int>(LocalizationErrorLog::kHistory) - 1) * kStep, {0, 0, 0});
  log.estimate(3, 99 * kStep, {0, 0, 0});  // no such robot
  EXPECT_EQ(log.samples(), 1u);
  EXPECT_EQ(log.unmatched(), 2u);
}

}  // namespace
}  // namespace fleet::sim
