#include <gtest/gtest.h>

#include <cmath>

#include "fleet/vda5050/connection.hpp"
#include "fleet/vda5050/factsheet.hpp"
#include "fleet/vda5050/instant_actions.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/state.hpp"
#include "order_fixtures.hpp"

namespace fleet::vda5050 {
namespace {

State sampleState() {
  State s;
  s.header = {7, "2026-11-26T03:00:00.000Z", kVersion, "acme", "AGV-1"};
  s.orderId = "o1";
  s.orderUpdateId = 2;
  s.lastNodeId = "n1";
  s.lastNodeSequenceId = 2;
  s.driving = true;
  s.paused = false;
  s.nodeStates.push_back({"n2", 4, true, NodePosition{2.0, 0.0, 0.5, {}, {}, "small"}});
  s.edgeStates.push_back({"e1-2", 3, true});
  s.agvPosition = AgvPosition{1.2, 0.1, 0.0, "small", true};
  s.velocity = Velocity{0.5, 0.0, 0.1};
  s.actionStates.push_back({"pick-1", std::string("pick"), "WAITING", {}});
  s.batteryState = {81.5, false};
  s.errors.push_back({"orderUpdateError", "WARNING", std::string("late"), {{"orderId", "o1"}}});
  s.safetyState = {"NONE", true};
  return s;
}

TEST(Vda5050Messages, OrderRoundTripsThroughJson) {
  auto o = test::lineOrder("o1", 3, 0, 4, 2);
  o.nodes[1].actions.push_back({"pick", "pick-1", "HARD", {}, {{"stationId", "P-1"}}});
  const auto back = parseOrder(toJson(o).dump());
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(toJson(*back), toJson(o));
  EXPECT_EQ(back->nodes[1].actions[0].actionParameters[0].value, "P-1");
  EXPECT_FALSE(back->nodes[2].released);
}

TEST(Vda5050Messages, StateRoundTripsThroughJson) {
  const auto s = sampleState();
  const auto back = parseState(toJson(s).dump());
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(toJson(*back), toJson(s));
  EXPECT_TRUE(back->safetyState.fieldViolation);
  EXPECT_EQ(back->errors[0].errorReferences[0].second, "o1");
}

TEST(Vda5050Messages, InstantActionsConnectionAndFactsheetRoundTrip) {
  InstantActions ia;
  ia.header = {1, "2026-11-26T03:00:00.000Z", kVersion, "acme", "AGV-1"};
  ia.actions.push_back({"startPause", "pause-1", "HARD", {}, {}});
  auto ia2 = parseInstantActions(toJson(ia).dump());
  ASSERT_TRUE(ia2) << ia2.error().message;
  EXPECT_EQ(toJson(*ia2), toJson(ia));

  Connection c{ia.header, "CONNECTIONBROKEN"};
  auto c2 = parseConnection(toJson(c).dump());
  ASSERT_TRUE(c2) << c2.error().message;
  EXPECT_EQ(c2->connectionState, "CONNECTIONBROKEN");

  Factsheet f;
  f.header = ia.header;
  f.seriesName = "sim";
  f.speedMax = 1.0;
  f.width = 0.6;
  f.length = 0.8;
  f.agvActions = {"pick", "drop"};
  auto f2 = parseFactsheet(toJson(f).dump());
  ASSERT_TRUE(f2) << f2.error().message;
  EXPECT_DOUBLE_EQ(f2->length, 0.8);
  EXPECT_EQ(f2->agvActions, f.agvActions);
}

// The footprint is the disc about the reference point that holds the vehicle at every heading:
// the farthest envelope point of any set, or half the diagonal of width x length without one.
TEST(Vda5050Messages, TheFactsheetsFootprintIsItsFarthestEnvelopePoint) {
  Factsheet f;
  f.header = {1, "2026-11-26T03:00:00.000Z", kVersion, "acme", "AGV-1"};
  f.seriesName = "sim";
  f.width = 0.6;
  f.length = 0.8;
  auto fp = footprint(f);
  EXPECT_DOUBLE_EQ(fp.radius, 0.5);  // 0.3, 0.4: a 3-4-5 triangle
  EXPECT_EQ(fp.source, "width x length");
  // A written factsheet without envelopes carries the rectangle, read back as an envelope.
  auto back = parseFactsheet(toJson(f).dump());
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->envelopes2d.size(), 1U);
  EXPECT_DOUBLE_EQ(footprint(*back).radius, 0.5);

  // A forklift: its reference point between the fork roots, its body behind, forks ahead.
  f.envelopes2d = {{"unloaded", {{-1.2, 0.4}, {-1.2, -0.4}, {0.0, -0.4}, {0.0, 0.4}}},
                   {"forks", {{0.0, 0.3}, {1.1, 0.3}, {1.1, -0.3}, {0.0, -0.3}}}};
  back = parseFactsheet(toJson(f).dump());
  ASSERT_TRUE(back) << back.error().message;
  ASSERT_EQ(back->envelopes2d.size(), 2U);
  EXPECT_EQ(back->envelopes2d[1].set, "forks");
  fp = footprint(*back);
  EXPECT_NEAR(fp.radius, std::hypot(1.2, 0.4), 1e-12);
  EXPECT_EQ(fp.source, "envelope 'unloaded'");

  auto j = toJson(f);
  j["agvGeometry"]["envelopes2d"][1]["polygonPoints"].erase(2);
  j["agvGeometry"]["envelopes2d"][1]["polygonPoints"].erase(1);
  const auto skipped = parseFactsheet(j);  // a polygon of 1 point outlines nothing: skipped
  ASSERT_TRUE(skipped) << skipped.error().message;
  EXPECT_EQ(skipped->envelopes2d.size(), 1U);
  // An envelope that outlines less than the vehicle's own width and length does not shrink it.
  f.envelopes2d = {{"dot", {{0.0, 0.0}, {0.01, 0.0}, {0.0, 0.01}}}};
  fp = footprint(f);
  EXPECT_DOUBLE_EQ(fp.radius, 0.4);
  EXPECT_EQ(fp.source, "width and length");
}

TEST(Vda5050Messages, RefusalNamesTheBadKey) {
  auto j = toJson(sampleState());
  j["driving"] = "yes";
  auto r = parseState(j);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("state.driving"), std::string::npos) << r.error().message;

  j = toJson(sampleState());
  j["nodeStates"][0].erase("sequenceId");
  r = parseState(j);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("state.nodeStates[0].sequenceId: missing"), std::string::npos)
      << r.error().message;

  j = toJson(sampleState());
  j["operatingMode"] = "DANCING";
  r = parseState(j);
  ASSERT_FALSE(r);
  EXPECT_NE(r.error().message.find("state.operatingMode"), std::string::npos) << r.error().message;

  auto oj = toJson(test::lineOrder("o1", 0, 0, 3, 3));
  oj["nodes"][2]["nodePosition"]["x"] = "far";
  const auto o = parseOrder(oj);
  ASSERT_FALSE(o);
  EXPECT_NE(o.error().message.find("order.nodes[2].nodePosition.x"), std::string::npos) << o.error().message;

  const auto broken = parseConnection(std::string("{not json"));
  ASSERT_FALSE(broken);
  EXPECT_EQ(broken.error().code, "vda5050.bad_json");

  const auto negative = parseOrder(nlohmann::json::parse(R"({"headerId":-1})"));
  ASSERT_FALSE(negative);
  EXPECT_NE(negative.error().message.find("order.headerId"), std::string::npos);
}

TEST(Vda5050Messages, TopicLayoutAndTimestamp) {
  EXPECT_EQ(topicName("uagv", "acme", "AGV-1", "state"), "uagv/v2/acme/AGV-1/state");
  EXPECT_EQ(vehicleSubtree("uagv", "acme", "AGV-1"), "uagv/v2/acme/AGV-1/#");
  EXPECT_EQ(isoTimestamp(1'700'000'000'123'000'000), "2023-11-14T22:13:20.123Z");
}

TEST(Vda5050Messages, TimestampsReadBackAsWritten) {
  for (const std::int64_t ns :
       {std::int64_t{0}, std::int64_t{1'700'000'000'123'000'000}, std::int64_t{1'795'000'000'999'000'000}}) {
    EXPECT_EQ(parseIsoTimestamp(isoTimestamp(ns)), ns) << isoTimestamp(ns);
  }
  EXPECT_EQ(parseIsoTimestamp("2023-11-14T22:13:20Z"), 1'700'000'000'000'000'000);
  EXPECT_EQ(parseIsoTimestamp("2023-11-14T22:13:20.5Z"), 1'700'000'000'500'000'000);
  for (const char* bad :
       {"", "2023-11-14", "2023-11-14T22:13:20", "2023-11-14T22:13:20.Z", "2023-11-14T22:13:20+01:00",
        "2023-13-14T22:13:20Z", "2023-11-14T22:13:20.123Zx", "yesterday"}) {
    EXPECT_FALSE(parseIsoTimestamp(bad).has_value()) << bad;
  }
}

}  // namespace
}  // namespace fleet::vda5050
