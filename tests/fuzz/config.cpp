// Configuration files (fleet::Config, which every service reads its --config with): every getter on
// every key of any document, then the two readers services share, the station list
// (StationMap::fromJson, the fleet manager's `stations`) and the robot description (site.json's
// `robot`). Problems are collected and end in ConfigError from finish(); nothing else may escape.

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/core/config.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/site/site_loader.hpp"
#include "fuzz_check.hpp"

namespace {

using fleet::Config;
using fleet::fuzz::require;

/// Reads every key of `c` with every getter (each records a problem when the type is wrong), and
/// recurses into objects and arrays of objects, as a service reading an unexpected file would.
void readAll(Config& c, int depth) {
  if (depth > 8 || !c.json().is_object()) {
    return;
  }
  std::vector<std::string> keys;
  for (const auto& [key, value] : c.json().items()) {
    keys.push_back(key);
  }
  for (const auto& key : keys) {
    (void)c.has(key);
    (void)c.number(key, 1.0, {0.0, 10.0});
    (void)c.number(key, 1.0, {0.0, 10.0, true});
    (void)c.integer(key, 3, {-5.0, 5.0});
    (void)c.boolean(key, false);
    (void)c.string(key, "a", {"a", "b"});
    (void)c.string(key, "free text");
    Config sub = c.child(key);
    readAll(sub, depth + 1);
    for (auto& element : c.array(key)) {
      readAll(element, depth + 1);
    }
  }
  // Dotted paths as services use them ("risk.levels").
  (void)c.number("a.b", 0.0);
  (void)c.requireInteger("id");
  (void)c.requireString("name");
  c.rejectUnknownKeys({"name", "id"});
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    Config c = Config::fromText(text, "fuzz.json");
    readAll(c, 0);
    fleet::site::RobotDescription robot;
    Config r = c.child("robot");
    fleet::site::readRobotDescription(r, robot);
    c.finish();
    require(c.ok(), "finish() throws when a problem was recorded");
  } catch (const fleet::ConfigError& e) {
    require(!e.problems().empty(), "a ConfigError lists its problems");
  }
  const auto doc = nlohmann::json::parse(text, nullptr, false);
  if (!doc.is_discarded()) {
    const auto stations = fleet::StationMap::fromJson(doc);
    if (stations) {
      for (const auto* s : stations->ofKind(fleet::StationKind::Pickup)) {
        require(stations->find(s->name) == s, "every station is found by its name");
      }
    }
  }
  return 0;
}
