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

TEST(Vda5050OrderBuilder, EachUpdateStartsAtTheLastBaseNodeOfThePreviousOne) {
  // The specification's stitching rule, checked by the vehicle's own rules update after update.
  auto b = builder();
  auto o = b.start("t1", release({10, 11}, {12}), 0);
  ASSERT_TRUE(o);
  Order held = *o;  // what the vehicle has
  for (int end = 12; end <= 15; ++end) {
    std::vector<int> base;
    for (int n = 11; n <= end; ++n) {
      base.push_back(n);
    }
    const auto up = b.extend(release(base, {end + 1}), 2, 0);
    ASSERT_TRUE(up && up->has_value());
    const auto prev_end = baseEnd(held);
    EXPECT_EQ((*up)->nodes.front().nodeId, prev_end->nodeId);
    EXPECT_EQ((*up)->nodes.front().sequenceId, prev_end->sequenceId);
    OrderProgress p{held.orderId, held.orderUpdateId, "n11", 2, prev_end->nodeId, prev_end->sequenceId, true};
    ASSERT_EQ(judgeOrder(p, **up).decision, OrderDecision::kAcceptUpdate) << judgeOrder(p, **up).description;
    held = stitchOrder(held, **up);
  }
  EXPECT_EQ(baseEnd(held)->nodeId, "n15");
}

TEST(Vda5050OrderBuilder, AfterARejectedUpdateTheNextStartsAtTheBaseEndTheVehicleHas) {
  auto b = builder();
  auto r = release({10, 11, 12}, {13});
  r.actions.push_back({14, {"drop", "t1-drop", "HARD", {}, {}}});
  ASSERT_TRUE(b.start("t1", r, 0));
  auto r2 = release({10, 11, 12, 13, 14}, {});
  r2.actions = r.actions;
  const auto u1 = b.extend(r2, 0, 0);
  ASSERT_TRUE(u1 && u1->has_value());
  EXPECT_EQ((*u1)->orderUpdateId, 1U);
  ASSERT_EQ((*u1)->nodes.back().actions.size(), 1U);
  // The vehicle rejected update 1 and drives on with update 0 (base end n12).
  EXPECT_FALSE(b.rollbackTo(7));
  ASSERT_TRUE(b.rollbackTo(0));
  const auto again = b.extend(r2, 2, 0);
  ASSERT_TRUE(again) << again.error().message;
  ASSERT_TRUE(again->has_value());
  EXPECT_EQ((*again)->orderUpdateId, 2U) << "a fresh orderUpdateId, not the rejected one";
  EXPECT_EQ((*again)->nodes.front().nodeId, "n12");
  EXPECT_EQ((*again)->nodes.front().sequenceId, 4U);
  ASSERT_EQ((*again)->nodes.back().nodeId, "n14");
  EXPECT_EQ((*again)->nodes.back().actions.size(), 1U) << "the drop goes again: the vehicle never had it";
  OrderProgress p{"t1", 0, "n11", 2, "n12", 4, true};  // the vehicle with update 0
  EXPECT_EQ(judgeOrder(p, **again).decision, OrderDecision::kAcceptUpdate);
}

TEST(Vda5050OrderBuilder, AReleaseAheadOfTheVehicleOnTheSentBaseIsStitched) {
  // The order began at the vehicle's last node n9, put in front of the release n10, n11: the
  // traffic layer's next release starts at n10 while the vehicle still reports n9.
  auto b = builder();
  ASSERT_TRUE(b.start("t1", release({9, 10, 11}, {}), 0));
  const auto up = b.extend(release({10, 11, 12}, {13}), 0, 0);
  ASSERT_TRUE(up) << up.error().message;
  ASSERT_TRUE(up->has_value());
  EXPECT_EQ((*up)->nodes.front().nodeId, "n11");
  EXPECT_EQ((*up)->nodes[1].nodeId, "n12");
  EXPECT_FALSE(b.extend(release({11, 14}, {}), 0, 0)) << "off the sent base after n11";
  EXPECT_FALSE(b.extend(release({20, 21}, {}), 0, 0)) << "not on the sent base at all";
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
