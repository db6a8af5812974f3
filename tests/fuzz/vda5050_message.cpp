// The VDA 5050 bridge's edge: a message from the broker (its first byte picks the topic: state,
// connection, factsheet, or another) through VehicleRegistry::onMessage, which parses, checks and
// refuses. Properties besides "no crash":
//  - a refusal names its reason;
//  - an accepted state has a finite position on the site and a battery within 0..100, and a
//    protocol version of 2.0 or 2.1.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fleet/vda5050/vehicle_registry.hpp"
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using fleet::fuzz::require;
  if (size == 0) {
    return 0;
  }
  static const char* const kTopics[] = {"state", "connection", "factsheet", "visualization"};
  const std::string topic = std::string("uagv/v2/acme/AGV-1/") + kTopics[data[0] % 4];
  const std::string payload(reinterpret_cast<const char*>(data + 1), size - 1);
  fleet::vda5050::VehicleRegistry registry("uagv", "small", {{"acme", "AGV-1", "v1"}},
                                           {.maxMessageBytes = 64 * 1024});
  registry.setSiteBounds(-50, -50, 150, 150);
  const auto out = registry.onMessage(topic, payload);
  if (!out.accepted) {
    require(!out.reason.empty(), "a refusal names its reason");
    return 0;
  }
  const auto* v = registry.find("v1");
  require(v != nullptr, "the configured vehicle is known");
  if (v->state && data[0] % 4 == 0) {
    const auto& s = *v->state;
    require(fleet::vda5050::speaksVersion(s.header.version), "an accepted state speaks 2.0 or 2.1");
    const double b = s.batteryState.batteryCharge;
    require(std::isfinite(b) && b >= 0 && b <= 100, "an accepted battery is within 0..100");
    if (s.agvPosition) {
      const auto& p = *s.agvPosition;
      require(
          std::isfinite(p.x) && std::isfinite(p.y) && p.x >= -50 && p.x <= 150 && p.y >= -50 && p.y <= 150,
          "an accepted position is on the site");
    }
  }
  return 0;
}
