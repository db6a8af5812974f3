// The registry's edge (reliability findings of 2026-12-02): a state too large or nested too deep,
// of a protocol version it does not speak, with a position off the site or a battery outside
// 0..100 is refused with a reason and counted by kind; a vehicle list with MQTT wildcards or one
// identity twice is a configuration problem naming the key.

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "fleet/vda5050/vehicle_registry.hpp"
#include "order_fixtures.hpp"

namespace fleet::vda5050 {
namespace {

const std::string kTopic = "uagv/v2/acme/AGV-1/state";

State goodState() {
  State s;
  s.header = {1, isoTimestamp(0), kVersion, "acme", "AGV-1"};
  s.orderId = "o1";
  s.agvPosition = AgvPosition{3.0, 4.0, 0.0, "small", true};
  s.batteryState.batteryCharge = 80;
  return s;
}

VehicleRegistry registry(RegistryLimits limits = {}) {
  return VehicleRegistry("uagv", "small", {{"acme", "AGV-1", "v1"}}, limits);
}

TEST(Vda5050RegistryEdge, AnOversizedOrDeepStateIsRefusedAsTooLargeAndCounted) {
  auto r = registry({.maxMessageBytes = 4096});
  auto j = toJson(goodState());
  j["information"] = nlohmann::json::array();
  for (int i = 0; i < 200; ++i) {
    j["information"].push_back({{"infoType", "padding"}, {"infoLevel", "INFO"}});
  }
  auto out = r.onMessage(kTopic, j.dump());
  EXPECT_FALSE(out.accepted);
  EXPECT_NE(out.reason.find("max_message_bytes"), std::string::npos) << out.reason;
  EXPECT_EQ(r.refusals().at("too_large"), 1u);
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kFault);

  auto deep = registry();
  out = deep.onMessage(kTopic, std::string(100'000, '['));
  EXPECT_FALSE(out.accepted);
  EXPECT_NE(out.reason.find("max_depth"), std::string::npos) << out.reason;
  EXPECT_EQ(deep.refusals().at("too_large"), 1u);
  EXPECT_EQ(deep.refusals().count("bad_message"), 0u);
  EXPECT_TRUE(deep.onMessage(kTopic, toJson(goodState()).dump()).accepted) << "a good state still counts";
}

TEST(Vda5050RegistryEdge, AStateOfAVersionItDoesNotSpeakIsRefused) {
  for (const char* version : {"1.1.0", "3.0.0", "2.9.0", "", "x", "20.1.0"}) {
    auto r = registry();
    auto s = goodState();
    s.header.version = version;
    const auto out = r.onMessage(kTopic, toJson(s).dump());
    EXPECT_FALSE(out.accepted) << version;
    EXPECT_EQ(r.refusals().count("unsupported_version"), 1u) << version;
  }
  for (const char* version : {"2.0.0", "2.1.0", "2.1"}) {
    auto r = registry();
    auto s = goodState();
    s.header.version = version;
    EXPECT_TRUE(r.onMessage(kTopic, toJson(s).dump()).accepted) << version;
  }
}

TEST(Vda5050RegistryEdge, APositionOffTheSiteOrABatteryOutsideItsRangeIsRefused) {
  auto r = registry();
  r.setSiteBounds(-50, -50, 110, 90);
  auto s = goodState();
  s.agvPosition->x = 5000;
  auto out = r.onMessage(kTopic, toJson(s).dump());
  EXPECT_FALSE(out.accepted);
  EXPECT_NE(out.reason.find("outside the site"), std::string::npos) << out.reason;
  EXPECT_EQ(r.refusals().at("implausible_position"), 1u);
  // A number that overflows a double is refused by the parser already (never an infinite position).
  auto j = toJson(goodState()).dump();
  const auto at = j.find("\"y\":4.0");
  ASSERT_NE(at, std::string::npos) << j;
  j.replace(at, 7, "\"y\":1e999");
  EXPECT_FALSE(r.onMessage(kTopic, j).accepted);
  EXPECT_EQ(r.refusals().at("bad_message"), 1u);
  for (double charge : {-1.0, 100.5}) {
    s = goodState();
    s.batteryState.batteryCharge = charge;
    out = r.onMessage(kTopic, toJson(s).dump());
    EXPECT_FALSE(out.accepted) << charge;
    EXPECT_NE(out.reason.find("batteryCharge"), std::string::npos) << out.reason;
  }
  EXPECT_EQ(r.refusals().at("implausible_battery"), 2u);
  EXPECT_TRUE(r.onMessage(kTopic, toJson(goodState()).dump()).accepted);
  EXPECT_EQ(r.find("v1")->health, VehicleHealth::kOnline);
}

TEST(Vda5050RegistryEdge, WildcardsAndOneIdentityTwiceAreConfigurationProblemsNamingTheKey) {
  EXPECT_TRUE(vehicleEntryProblems({{"acme", "AGV-1", "v1"}, {"acme", "AGV-2", "v2"}}).empty());
  for (const char* serial : {"#", "AGV+", "a/b"}) {
    const auto p = vehicleEntryProblems({{"acme", "AGV-1", "v1"}, {"acme", serial, "v2"}});
    ASSERT_EQ(p.size(), 1u) << serial;
    EXPECT_EQ(p[0].rfind("vehicles[1].serial: ", 0), 0u) << p[0];
  }
  const auto m = vehicleEntryProblems({{"ac+me", "AGV-1", "v1"}});
  ASSERT_EQ(m.size(), 1u);
  EXPECT_EQ(m[0].rfind("vehicles[0].manufacturer: ", 0), 0u) << m[0];
  const auto twice = vehicleEntryProblems({{"acme", "AGV-1", "v1"}, {"acme", "AGV-1", "v2"}});
  ASSERT_EQ(twice.size(), 1u);
  EXPECT_NE(twice[0].find("vehicles[1].serial: vehicle acme/AGV-1 is vehicles[0] already"), std::string::npos)
      << twice[0];
  const auto sameRobot = vehicleEntryProblems({{"acme", "AGV-1", "v1"}, {"acme", "AGV-2", "v1"}});
  ASSERT_EQ(sameRobot.size(), 1u);
  EXPECT_EQ(sameRobot[0].rfind("vehicles[1].robot: ", 0), 0u);
}

}  // namespace
}  // namespace fleet::vda5050
