#include "fleet/vda5050/order_builder.hpp"

#include <gtest/gtest.h>

#include "fleet/vda5050/order_rules.hpp"

namespace fleet::vda5050 {
namespace {

ReleaseInput release(std::vector<int> base, std::vector<int> horizon) {
  ReleaseInput r;
  for (int n : base) {
    r.base.push_back({n, static_cast<double>(n), 0.0});
  }
  for (int n : horizon) {
    r.horizon.push_back({n, static_cast<double>(n), 0.0});
  }
  return r;
}

OrderBuilder builder() {
  return OrderBuilder({"acme", "A1", "small", 0.2});
}

TEST(Vda5050OrderBuilder, TheFirstReleaseIsANewValidOrder) {
  auto b = builder();
  auto r = release({10, 11, 12}, {13, 14});
  r.actions.push_back({12, {"pick", "t1-pick", "HARD", {}, {}}});
  r.actions.push_back({14, {"drop", "t1-drop", "HARD", {}, {}}});
  const auto o = b.start("t1", r, 0);
  ASSERT_TRUE(o) << o.error().message;
  EXPECT_TRUE(validateOrder(*o));
  EXPECT_EQ(o->orderUpdateId, 0U);
  ASSERT_EQ(o->nodes.size(), 5U);
  EXPECT_EQ(o->nodes[2].nodeId, "n12");
  ASSERT_EQ(o->nodes[2].actions.size(), 1U);
  EXPECT_TRUE(o->nodes[4].actions.empty()) << "a horizon node carries no actions yet";
  EXPECT_EQ(o->nodes[4].nodePosition->mapId, "small");
  EXPECT_EQ(judgeOrder(OrderProgress{}, *o).decision, OrderDecision::kAcceptNew);
}

TEST(Vda5050OrderBuilder, MoreReleasedBecomesAnUpdateTheVehicleStitches) {
  auto b = builder();
  auto r = release({10, 11, 12}, {13, 14});
  r.actions.push_back({14, {"drop", "t1-drop", "HARD", {}, {}}});
  const auto first = b.start("t1", r, 0);
  ASSERT_TRUE(first);
  // The vehicle passed n11 (sequenceId 2); the traffic layer releases up to n14.
  auto r2 = release({11, 12, 13, 14}, {15});
  r2.actions = r.actions;
  const auto up = b.extend(r2, 2, 0);
  ASSERT_TRUE(up) << up.error().message;
  ASSERT_TRUE(up->has_value());
  const auto& u = **up;
  EXPECT_EQ(u.orderUpdateId, 1U);
  EXPECT_EQ(u.nodes.front().nodeId, "n12");
  EXPECT_EQ(u.nodes.front().sequenceId, 4U);
  EXPECT_TRUE(validateOrder(u));
  ASSERT_EQ(u.nodes.size(), 4U);
  EXPECT_EQ(u.nodes[2].nodeId, "n14");
  EXPECT_EQ(u.nodes[2].actions.size(), 1U) << "the drop goes with its node once released";

  OrderProgress p{"t1", 0, "n11", 2, "n12", 4, true};
  EXPECT_EQ(judgeOrder(p, u).decision, OrderDecision::kAcceptUpdate);
  const auto merged = stitchOrder(*first, u);
  EXPECT_TRUE(validateOrder(merged));
  EXPECT_EQ(baseEnd(merged)->nodeId, "n14");

  // A release that still starts behind the vehicle (its last report lagged) is aligned.
  auto r3 = release({11, 12, 13, 14, 15, 16}, {});
  const auto lagging = b.extend(r3, 8, 0);  // the vehicle passed n14 (sequenceId 8)
  ASSERT_TRUE(lagging) << lagging.error().message;
  ASSERT_TRUE(lagging->has_value());
  EXPECT_EQ((*lagging)->nodes.front().nodeId, "n14");
  EXPECT_EQ((*lagging)->nodes.back().nodeId, "n16");
  EXPECT_EQ(b.orderUpdateId(), 2U);
  EXPECT_TRUE(validateOrder(**lagging));

  // The same release again adds nothing; a shorter one neither.
  auto again = b.extend(r3, 8, 0);
  ASSERT_TRUE(again);
  EXPECT_FALSE(again->has_value());
  auto shorter = b.extend(r2, 8, 0);
  ASSERT_TRUE(shorter);
  EXPECT_FALSE(shorter->has_value());
  EXPECT_EQ(b.orderUpdateId(), 2U);
}

TEST(Vda5050OrderBuilder, AReleaseOffTheSentBaseIsRefused) {
  auto b = builder();
  ASSERT_TRUE(b.start("t1", release({10, 11, 12}, {}), 0));
  const auto bad = b.extend(release({10, 21, 22, 23}, {}), 0, 0);
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, "vda5050.cannot_stitch");
  EXPECT_NE(bad.error().message.find("n11"), std::string::npos);
  EXPECT_FALSE(b.extend(release({12, 13}, {}), 40, 0));  // progress beyond what was sent
  EXPECT_FALSE(b.start("t2", release({}, {}), 0));
}

TEST(Vda5050OrderBuilder, RoadmapNodeOfANodeId) {
  EXPECT_EQ(OrderBuilder::roadmapNode("n12"), 12);
  EXPECT_EQ(OrderBuilder::roadmapNode("n"), -1);
  EXPECT_EQ(OrderBuilder::roadmapNode("x12"), -1);
  EXPECT_EQ(OrderBuilder::roadmapNode("n12a"), -1);
  EXPECT_EQ(OrderBuilder::roadmapNode("n-3"), -1);
}

}  // namespace
}  // namespace fleet::vda5050
