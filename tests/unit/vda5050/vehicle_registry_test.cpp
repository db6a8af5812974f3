#include "fleet/vda5050/vehicle_registry.hpp"

#include <gtest/gtest.h>

#include "fleet/vda5050/connection.hpp"
#include "order_fixtures.hpp"

namespace fleet::vda5050 {
namespace {

const std::string kTopic = "uagv/v2/acme/AGV-1/";

VehicleRegistry registry() {
  return VehicleRegistry("uagv", "small", {{"acme", "AGV-1", "v1"}, {"acme", "AGV-2", "v2"}});
}

State goodState(const std::string& last_node) {
  State s;
  s.header = {1, isoTimestamp(0), kVersion, "acme", "AGV-1"};
  s.orderId = "o1";
  s.lastNodeId = last_node;
  s.agvPosition = AgvPosition{0.0, 0.0, 0.0, "small", true};
  return s;
}

TEST(Vda5050Registry, AGoodStatePutsTheVehicleOnline) {
  auto r = registry();
  const auto out = r.onMessage(kTopic + "state", toJson(goodState("")).dump());
  EXPECT_TRUE(out.accepted) << out.reason;
  EXPECT_EQ(out.robot_id, "v1");
  EXPECT_TRUE(out.health_changed);
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kOnline);
  EXPECT_EQ(r.find("v2")->health, VehicleHealth::kUnknown);
}

TEST(Vda5050Registry, ManualModeAndFatalErrorsTakeItOutOfTrafficControl) {
  auto r = registry();
  auto s = goodState("");
  s.operatingMode = "MANUAL";
  EXPECT_TRUE(r.onMessage(kTopic + "state", toJson(s).dump()).accepted);
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kManual);
  s.operatingMode = "AUTOMATIC";
  s.errors.push_back({"wheelSlip", "WARNING", {}, {}});
  r.onMessage(kTopic + "state", toJson(s).dump());
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kOnline) << "a warning is no fault";
  s.errors.push_back({"laserScannerBroken", "FATAL", {}, {}});
  r.onMessage(kTopic + "state", toJson(s).dump());
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kFault);
  EXPECT_NE(r.find("v1")->reason.find("laserScannerBroken"), std::string::npos);
}

TEST(Vda5050Registry, TheLastWillMarksItOfflineAndOnlinePlusStateBringsItBack) {
  auto r = registry();
  r.onMessage(kTopic + "state", toJson(goodState("")).dump());
  Connection c{{2, isoTimestamp(0), kVersion, "acme", "AGV-1"}, "CONNECTIONBROKEN"};
  auto out = r.onMessage(kTopic + "connection", toJson(c).dump());
  EXPECT_TRUE(out.health_changed);
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kOffline);
  c.connectionState = "ONLINE";
  r.onMessage(kTopic + "connection", toJson(c).dump());
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kUnknown);
  r.onMessage(kTopic + "state", toJson(goodState("")).dump());
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kOnline);
}

TEST(Vda5050Registry, BadInputIsRefusedCountedAndFaultsOnlyItsVehicle) {
  auto r = registry();
  r.onMessage("uagv/v2/acme/AGV-2/state", toJson([] {
                                            auto s = goodState("");
                                            s.header.serialNumber = "AGV-2";
                                            return s;
                                          }())
                                              .dump());
  ASSERT_EQ(r.find("v2")->health, VehicleHealth::kOnline);

  // A state failing the schema names the key.
  auto j = toJson(goodState(""));
  j["batteryState"].erase("charging");
  auto out = r.onMessage(kTopic + "state", j.dump());
  EXPECT_FALSE(out.accepted);
  EXPECT_NE(out.reason.find("state.batteryState.charging"), std::string::npos) << out.reason;
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kFault);
  // Not JSON at all.
  EXPECT_FALSE(r.onMessage(kTopic + "state", "\x01garbage").accepted);
  // An unknown serial: counted, no vehicle touched.
  out = r.onMessage("uagv/v2/acme/AGV-9/state", toJson(goodState("")).dump());
  EXPECT_FALSE(out.accepted);
  EXPECT_TRUE(out.robot_id.empty());
  // Another vehicle's serial on this topic.
  auto forged = goodState("");
  forged.header.serialNumber = "AGV-2";
  EXPECT_FALSE(r.onMessage(kTopic + "state", toJson(forged).dump()).accepted);
  // Another map.
  auto elsewhere = goodState("");
  elsewhere.agvPosition->mapId = "other";
  out = r.onMessage(kTopic + "state", toJson(elsewhere).dump());
  EXPECT_FALSE(out.accepted);
  EXPECT_NE(out.reason.find("other"), std::string::npos);
  // A node it was never ordered.
  r.onMessage(kTopic + "state", toJson(goodState("n0")).dump());  // before any order: its start
  ASSERT_EQ(r.find("v1")->health, VehicleHealth::kOnline);
  r.ordered("v1", test::lineOrder("o1", 0, 0, 3, 3));
  EXPECT_TRUE(r.onMessage(kTopic + "state", toJson(goodState("n2")).dump()).accepted);
  out = r.onMessage(kTopic + "state", toJson(goodState("n7")).dump());
  EXPECT_FALSE(out.accepted);
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kFault);

  EXPECT_EQ(r.refusals().at("bad_message"), 2U);
  EXPECT_EQ(r.refusals().at("unknown_serial"), 1U);
  EXPECT_EQ(r.refusals().at("wrong_serial"), 1U);
  EXPECT_EQ(r.refusals().at("other_map"), 1U);
  EXPECT_EQ(r.refusals().at("node_never_ordered"), 1U);
  EXPECT_EQ(r.find("v2")->health, VehicleHealth::kOnline) << "the other vehicle is not disturbed";
}

TEST(Vda5050Registry, TheFactsheetIsKept) {
  auto r = registry();
  Factsheet f;
  f.header = {0, isoTimestamp(0), kVersion, "acme", "AGV-1"};
  f.seriesName = "x";
  f.width = 0.7;
  f.length = 1.1;
  EXPECT_TRUE(r.onMessage(kTopic + "factsheet", toJson(f).dump()).accepted);
  ASSERT_TRUE(r.find("v1")->factsheet);
  EXPECT_DOUBLE_EQ(r.find("v1")->factsheet->length, 1.1);
}

}  // namespace
}  // namespace fleet::vda5050
