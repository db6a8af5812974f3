// site.json as every service loads it (parseSite with the geometry checks). A bad document must end
// in ConfigError naming what is wrong, never in another exception, a crash or a hang. Map and mask
// files are looked up in tests/fuzz/data.

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "fleet/site/site_loader.hpp"
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto doc = nlohmann::json::parse(data, data + size, nullptr, false);
  if (doc.is_discarded() || !fleet::fuzz::staysInDataDir(doc)) {
    return 0;
  }
  try {
    const auto site = fleet::site::parseSite(doc, "fuzz.site.json", fleet::fuzz::dataDir());
    fleet::fuzz::require(site.map.size() > 0, "a site that loads has a map");
  } catch (const fleet::ConfigError& e) {
    fleet::fuzz::require(!e.problems().empty(), "a ConfigError lists its problems");
  }
  return 0;
}
