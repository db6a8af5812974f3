// The bridge's edge (reliability findings of 2026-12-02): an oversized or deeply nested state, a
// state of a version it does not speak, or one that puts the vehicle off the roadmap's site is
// refused, counted by kind and logged with its reason.

#include <gtest/gtest.h>

#include <algorithm>

#include "bridge_node.hpp"
#include "fleet/vda5050/state.hpp"

namespace fleet::vdabridge {
namespace {

const std::string kTopic = "uagv/v2/acme/AGV-1/state";

vda5050::State state(double x, double y) {
  vda5050::State s;
  s.header = {1, vda5050::isoTimestamp(0), vda5050::kVersion, "acme", "AGV-1"};
  s.agvPosition = vda5050::AgvPosition{x, y, 0.0, "small", true};
  s.batteryState.batteryCharge = 50;
  return s;
}

BridgeNode bridge() {
  BridgeSettings s{"uagv", "small", {{"acme", "AGV-1", "r1"}}, 0.2};
  s.max_message_bytes = 8192;
  s.site_margin = 10;
  BridgeNode b(std::move(s));
  msg::Roadmap m;  // nodes from (0, 0) to (20, 5): the site is [-10, 30] x [-10, 15]
  m.nodes.push_back({0, 0.0, 0.0});
  m.nodes.push_back({1, 20.0, 5.0});
  b.onRoadmap(m);
  return b;
}

TEST(Vda5050BridgeEdge, AStateOffTheSiteOrOfAnotherVersionIsRefusedAndCounted) {
  auto b = bridge();
  BridgeOutbox out;
  b.onMqtt(kTopic, vda5050::toJson(state(25, 12)).dump(), out);
  EXPECT_EQ(b.counters().refused_messages, 0u) << (out.warnings.empty() ? "" : out.warnings[0]);
  b.onMqtt(kTopic, vda5050::toJson(state(35, 0)).dump(), out);
  EXPECT_EQ(b.counters().refused_messages, 1u);
  EXPECT_EQ(b.registry().refusals().at("implausible_position"), 1u);
  EXPECT_TRUE(std::any_of(out.warnings.begin(), out.warnings.end(), [](const std::string& w) {
    return w.find("r1: refused: agvPosition (35, 0") != std::string::npos;
  }));
  auto old = state(1, 1);
  old.header.version = "1.1.0";
  b.onMqtt(kTopic, vda5050::toJson(old).dump(), out);
  EXPECT_EQ(b.registry().refusals().at("unsupported_version"), 1u);
}

TEST(Vda5050BridgeEdge, AnOversizedOrDeepStateIsRefusedAsTooLarge) {
  auto b = bridge();
  BridgeOutbox out;
  b.onMqtt(kTopic, std::string(20000, ' ') + vda5050::toJson(state(1, 1)).dump(), out);
  b.onMqtt(kTopic, std::string(4000, '['), out);
  EXPECT_EQ(b.registry().refusals().at("too_large"), 2u);
  EXPECT_EQ(b.counters().refused_messages, 2u);
  ASSERT_EQ(out.warnings.size() >= 2, true);
  EXPECT_NE(out.warnings[0].find("max_message_bytes"), std::string::npos) << out.warnings[0];
}

}  // namespace
}  // namespace fleet::vdabridge
