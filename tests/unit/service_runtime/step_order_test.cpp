// StepOrder: in lockstep a sample counts from the step after its stamp, whatever order it came in.

#include "fleet/service/step_order.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <vector>

namespace {

struct Sample {
  int id = 0;
  std::int64_t stamp_ns = 0;
};

std::vector<int> ids(const std::vector<Sample>& v) {
  std::vector<int> out;
  for (const auto& s : v) {
    out.push_back(s.id);
  }
  return out;
}

}  // namespace

TEST(StepOrder, InLockstepASampleOfThisStepWaitsForTheNextOne) {
  fleet::service::StepOrder<Sample> order(true);
  // Step 2 (t = 200): one of step 1 and one of step 2 that came early.
  EXPECT_EQ(ids(order.due({{1, 100}, {2, 200}}, 200)), std::vector<int>{1});
  EXPECT_EQ(order.waiting(), 1u);
  // Step 3: the early one is due now, before what came since; a later one waits again.
  EXPECT_EQ(ids(order.due({{3, 200}, {4, 300}}, 300)), (std::vector<int>{2, 3}));
  EXPECT_EQ(ids(order.due({}, 400)), std::vector<int>{4});
  EXPECT_EQ(order.waiting(), 0u);
}

TEST(StepOrder, OutsideLockstepEverythingIsDueAtOnce) {
  fleet::service::StepOrder<Sample> order(false);
  EXPECT_EQ(ids(order.due({{1, 500}, {2, 900}}, 100)), (std::vector<int>{1, 2}));
  EXPECT_EQ(order.waiting(), 0u);
}
