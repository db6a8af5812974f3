#include "fleet/vda5050/order_rules.hpp"

#include <gtest/gtest.h>

#include "order_fixtures.hpp"

namespace fleet::vda5050 {
namespace {

using test::lineOrder;

// The vehicle after accepting lineOrder("o1", 0, 0, 5, 3): base n0..n2, horizon n3..n4.
OrderProgress runningO1() {
  OrderProgress p;
  p.orderId = "o1";
  p.orderUpdateId = 0;
  p.lastNodeId = "n1";
  p.lastNodeSequenceId = 2;
  p.baseEndNodeId = "n2";
  p.baseEndSequenceId = 4;
  p.active = true;
  return p;
}

TEST(Vda5050OrderRules, AWellFormedOrderValidates) {
  EXPECT_TRUE(validateOrder(lineOrder("o1", 0, 0, 5, 3)));
  EXPECT_TRUE(validateOrder(lineOrder("o1", 0, 4, 1, 1)));
}

TEST(Vda5050OrderRules, StructuralErrorsNameTheElement) {
  auto o = lineOrder("o1", 0, 0, 4, 2);
  o.nodes[2].sequenceId = 5;
  auto r = validateOrder(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("order.nodes[2].sequenceId: expected 4, got 5"), std::string::npos);

  o = lineOrder("o1", 0, 0, 4, 2);
  o.nodes[3].released = true;  // base after horizon
  r = validateOrder(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("order.nodes[3].released"), std::string::npos);

  o = lineOrder("o1", 0, 0, 4, 2);
  o.edges[1].endNodeId = "n7";
  r = validateOrder(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("order.edges[1]"), std::string::npos);

  o = lineOrder("o1", 0, 0, 4, 2);
  o.edges[2].released = true;  // an edge into a horizon node cannot be base
  r = validateOrder(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("order.edges[2].released"), std::string::npos);

  o = lineOrder("o1", 0, 0, 4, 2);
  o.edges.pop_back();
  EXPECT_FALSE(validateOrder(o));

  o = lineOrder("o1", 0, 0, 3, 0);
  r = validateOrder(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("order.nodes[0].released"), std::string::npos);

  o = lineOrder("o1", 0, 0, 3, 3);
  o.nodes[1].nodePosition->mapId = "other";
  r = validateOrder(o);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("mapId"), std::string::npos);
}

TEST(Vda5050OrderRules, AFirstOrderIsAccepted) {
  const auto v = judgeOrder(OrderProgress{}, lineOrder("o1", 0, 0, 5, 3));
  EXPECT_EQ(v.decision, OrderDecision::kAcceptNew) << v.description;
}

TEST(Vda5050OrderRules, AnUpdateStartingAtTheBaseEndIsStitched) {
  const auto current = lineOrder("o1", 0, 0, 5, 3);
  const auto update = lineOrder("o1", 1, 2, 4, 3);  // n2 (base end) .. n5, base to n4
  const auto v = judgeOrder(runningO1(), update);
  ASSERT_EQ(v.decision, OrderDecision::kAcceptUpdate) << v.description;
  const auto merged = stitchOrder(current, update);
  EXPECT_TRUE(validateOrder(merged));
  ASSERT_EQ(merged.nodes.size(), 6U);
  EXPECT_EQ(merged.nodes[4].nodeId, "n4");
  EXPECT_TRUE(merged.nodes[4].released);
  EXPECT_FALSE(merged.nodes[5].released);
  EXPECT_EQ(merged.orderUpdateId, 1U);
  EXPECT_EQ(baseEnd(merged)->nodeId, "n4");
}

TEST(Vda5050OrderRules, AnUpdateThatDoesNotExtendTheBaseIsRejected) {
  // Starts at n3, a horizon node: the vehicle could not join it without driving unreleased edges.
  auto v = judgeOrder(runningO1(), lineOrder("o1", 1, 3, 3, 2));
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_EQ(v.errorType, "orderUpdateError");
  EXPECT_NE(v.description.find("does not extend the base"), std::string::npos);
  // Starts at n1, behind the base end: it would rewrite the released base.
  v = judgeOrder(runningO1(), lineOrder("o1", 1, 1, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  // Right node, wrong sequenceId.
  auto wrong_seq = lineOrder("o1", 1, 2, 3, 3);
  for (auto& n : wrong_seq.nodes) {
    n.sequenceId += 2;
  }
  for (auto& e : wrong_seq.edges) {
    e.sequenceId += 2;
  }
  v = judgeOrder(runningO1(), wrong_seq);
  EXPECT_EQ(v.decision, OrderDecision::kReject);
}

TEST(Vda5050OrderRules, UpdateIdsMustIncrease) {
  auto p = runningO1();
  p.orderUpdateId = 4;
  auto v = judgeOrder(p, lineOrder("o1", 4, 2, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kDiscardDuplicate);
  v = judgeOrder(p, lineOrder("o1", 3, 2, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_EQ(v.errorType, "orderUpdateError");
  v = judgeOrder(p, lineOrder("o1", 5, 2, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kAcceptUpdate);
}

TEST(Vda5050OrderRules, ANewOrderIdOnlyWhenTheOldIsFinishedOrCancelled) {
  auto p = runningO1();
  auto v = judgeOrder(p, lineOrder("o2", 0, 1, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_EQ(v.errorType, "orderError");

  p.active = false;  // finished (or cancelled) standing on n1
  v = judgeOrder(p, lineOrder("o2", 0, 1, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kAcceptNew) << v.description;
  // ... and it must start where the vehicle stands.
  v = judgeOrder(p, lineOrder("o2", 0, 3, 3, 3));
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_EQ(v.errorType, "noRouteError");
}

TEST(Vda5050OrderRules, AnInvalidOrderIsAValidationError) {
  auto o = lineOrder("o1", 0, 0, 3, 3);
  o.nodes.clear();
  o.edges.clear();
  const auto v = judgeOrder(OrderProgress{}, o);
  EXPECT_EQ(v.decision, OrderDecision::kReject);
  EXPECT_EQ(v.errorType, "validationError");
}

}  // namespace
}  // namespace fleet::vda5050
