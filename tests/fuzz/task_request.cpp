// The WMS adapter's task intake (POST /v1/tasks): the body as JSON, parseTasks against the site's
// stations, then what the adapter does with an accepted task. Properties besides "no crash":
//  - a refusal names at least one field, in UTF-8 (it becomes the 400's body);
//  - an accepted task's wire form parses back to the same task;
//  - the Task sample the adapter sends passes the fleet manager's edge check (otherwise the client
//    gets 201 from the adapter for a task the manager refuses).

#include <cstddef>
#include <cstdint>
#include <nlohmann/json.hpp>

#include "fleet/fleet/station_map.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/fleet/task_wire.hpp"
#include "fleet/validation/sample_checks.hpp"
#include "fleet/validation/utf8.hpp"
#include "fuzz_check.hpp"

namespace {

using fleet::fuzz::require;

fleet::StationMap makeStations() {
  // The stations the seeds name (P-1..P-2 pickup, D-1 dropoff, C-1 charging, PARK-1 parking).
  const auto doc = nlohmann::json::parse(R"([
    {"name": "P-1", "x": 1, "y": 2, "theta": 0, "kinds": ["pickup"]},
    {"name": "P-2", "x": 3, "y": 2, "theta": 0, "kinds": ["pickup", "dropoff"]},
    {"name": "D-1", "x": 5, "y": 2, "theta": 1.57, "kinds": ["dropoff"]},
    {"name": "C-1", "x": 7, "y": 2, "theta": 0, "kinds": ["charging"]},
    {"name": "PARK-1", "x": 9, "y": 2, "theta": 0, "kinds": ["parking"]}])");
  auto m = fleet::StationMap::fromJson(doc);
  require(m.has_value(), "the fuzz target's own station list is valid");
  return *m;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const fleet::StationMap stations = makeStations();
  const auto body = nlohmann::json::parse(data, data + size, nullptr, false);
  if (body.is_discarded()) {
    return 0;
  }
  auto parsed = fleet::parseTasks(body, &stations);
  if (!parsed) {
    require(!parsed.error().fields.empty(), "a refused body names a field");
    for (const auto& f : parsed.error().fields) {
      require(fleet::validation::isValidUtf8(f.path) && fleet::validation::isValidUtf8(f.reason),
              "field errors are UTF-8");
    }
    require(fleet::validation::isValidUtf8(parsed.error().message), "the error message is UTF-8");
    return 0;
  }
  for (const auto& t : *parsed) {
    const auto again = fleet::parseTask(fleet::toJson(t), &stations);
    require(again.has_value() && *again == t, "an accepted task's wire form parses back to it");
    require(!fleet::canonicalBody(t).empty(), "the canonical body is not empty");
    const auto wire = fleet::toWire(t, "fuzz-request-1", 1);
    const auto refused = fleet::validation::check(wire);
    if (refused) {
      std::fprintf(stderr, "manager refuses: %s %s\n", refused->reason.c_str(), refused->detail.c_str());
    }
    require(!refused, "the manager's edge accepts what the adapter accepted");
    auto expected = t;
    if (expected.createdNs == 0) {
      expected.createdNs = 1;  // the adapter's clock stamps a task the client did not
    }
    require(fleet::fromWire(wire, 1) == expected, "the manager reads the same task");
  }
  return 0;
}
