#include "base_ends.hpp"

#include <gtest/gtest.h>

namespace fleet::ctl {
namespace {

// The traffic manager's per-robot counts are split between robot agents and VDA 5050 vehicles
// and summed; the line names all three causes for each.
TEST(BaseEnds, CountsAreSplitBetweenAgentsAndVehicles) {
  const nlohmann::json tm = {{"releases", 10},
                             {"base_ends_by_robot",
                              {{"r1", {{"held", 3}, {"plan_end", 1}, {"limit", 0}}},
                               {"r2", {{"held", 2}, {"plan_end", 0}, {"limit", 1}}},
                               {"r3", {{"held", 5}, {"plan_end", 2}, {"limit", 4}}}}}};
  const auto out = trafficSummaryJson(tm, {"r3"});
  EXPECT_EQ(out["releases"], 10);
  EXPECT_EQ(out["base_ends_agents"], (nlohmann::json{{"held", 5}, {"plan_end", 1}, {"limit", 1}}));
  EXPECT_EQ(out["base_ends_vehicles"], (nlohmann::json{{"held", 5}, {"plan_end", 2}, {"limit", 4}}));
  EXPECT_EQ(
      baseEndsLine(out),
      "base ends reached short of the target: agents 5 held by others, 1 at the plan's end, 1 with more "
      "free (late); VDA 5050 vehicles 5 held by others, 2 at the plan's end, 4 with more free (late)");
  // Without vehicles, or from an older traffic manager without per-robot counts.
  const auto agentsOnly = trafficSummaryJson({{"releases", 1}}, {});
  EXPECT_FALSE(agentsOnly.contains("base_ends_vehicles"));
  EXPECT_EQ(agentsOnly["base_ends_agents"]["held"], 0);
  // A summary of unexpected shape (an edited file) leaves the odd entries out instead of throwing.
  const auto odd =
      trafficSummaryJson({{"base_ends_by_robot", {{"r1", 7}, {"r2", {{"held", "x"}, {"limit", 2}}}}}}, {});
  EXPECT_EQ(odd["base_ends_agents"], (nlohmann::json{{"held", 0}, {"plan_end", 0}, {"limit", 2}}));
}

}  // namespace
}  // namespace fleet::ctl
