// A multi-stop order through the bridge: its pick and drop actions carry the load (VDA 5050
// parameter loadId), a wait holds the vehicle at its stop, and each stop is reported.

#include <gtest/gtest.h>

#include <algorithm>

#include "bridge_loop.hpp"

namespace fleet::vdabridge {
namespace {

using bridge_test::Loop;
using bridge_test::release;

/// The value of parameter `key` of the action of type `type` in `o`, or "" when there is none.
std::string parameterOf(const vda5050::Order& o, const std::string& type, const std::string& key) {
  for (const auto& n : o.nodes) {
    for (const auto& a : n.actions) {
      if (a.actionType != type) {
        continue;
      }
      for (const auto& p : a.actionParameters) {
        if (p.key == key && p.value.is_string()) {
          return p.value.get<std::string>();
        }
      }
    }
  }
  return "";
}

TEST(Vda5050BridgeLoads, PickAndDropCarryTheLoadIdAndEachStopIsReported) {
  Loop l;
  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = "m-1";
  a.goals = {{{1.0, 0.0, 0.0}, "P-1", msg::GoalAction::Load, 1.0, "L-7"},
             {{3.0, 0.0, 0.0}, "D-1", msg::GoalAction::Unload, 1.0, "L-7"},
             {{3.0, 0.0, 0.0}, "D-1", msg::GoalAction::None, 5.0, ""}};
  BridgeOutbox out;
  l.bridge.onAssignment(a, l.now, out);
  auto toPick = release({0, 1});
  toPick.ends_at_goal = true;
  l.bridge.onRelease(toPick);
  l.run(0.1);
  ASSERT_FALSE(l.orders.empty());
  EXPECT_EQ(parameterOf(l.orders.back(), "pick", "loadId"), "L-7");
  ASSERT_TRUE(l.runUntilAt("n1", 20.0));
  l.run(3.0);  // the pick's second
  auto toDrop = release({1, 2, 3});
  toDrop.seq = 2;
  toDrop.ends_at_goal = true;
  l.bridge.onRelease(toDrop);
  l.run(0.1);
  const auto drop = std::find_if(l.orders.rbegin(), l.orders.rend(), [](const vda5050::Order& o) {
    return !parameterOf(o, "drop", "loadId").empty();
  });
  ASSERT_NE(drop, l.orders.rend());
  EXPECT_EQ(parameterOf(*drop, "drop", "loadId"), "L-7");
  ASSERT_TRUE(l.runUntilAt("n3", 20.0));
  for (int k = 0; k < 100 && (l.statuses.empty() || l.statuses.back().step < 3); ++k) {
    l.run(0.1);  // the drop's second
  }
  ASSERT_FALSE(l.statuses.empty());
  ASSERT_EQ(l.statuses.back().step, 3U);
  const auto waitBegan = l.now;
  l.run(4.0);
  EXPECT_NE(l.statuses.back().state, msg::TaskState::Done) << "waiting its five seconds";
  l.run(2.0);
  EXPECT_EQ(l.statuses.back().state, msg::TaskState::Done);
  EXPECT_GE(l.statuses.back().stamp_ns - waitBegan, 5'000'000'000LL - 200'000'000LL);
  std::vector<std::uint32_t> steps;
  for (const auto& s : l.statuses) {
    if (steps.empty() || steps.back() != s.step) {
      steps.push_back(s.step);
    }
  }
  EXPECT_EQ(steps, (std::vector<std::uint32_t>{1, 2, 3}));
}

}  // namespace
}  // namespace fleet::vdabridge
