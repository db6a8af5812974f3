// Simulator scenarios (parseScenario: robots, people, faults, task list, an inline map or a site
// file). A bad document ends in ConfigError naming what is wrong, never in another exception, a
// crash or a hang. Sites and maps it names are looked up in sim/scenarios, next to the real ones.

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "fleet/scenario/scenario.hpp"
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto doc = nlohmann::json::parse(data, data + size, nullptr, false);
  if (doc.is_discarded() || !fleet::fuzz::staysInDataDir(doc)) {
    return 0;
  }
  try {
    (void)fleet::sim::parseScenario(doc, "fuzz.json", FLEET_FUZZ_SCENARIO_DIR);
  } catch (const fleet::ConfigError& e) {
    fleet::fuzz::require(!e.problems().empty(), "a ConfigError lists its problems");
  }
  return 0;
}
