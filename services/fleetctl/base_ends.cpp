#include "base_ends.hpp"

#include <cstdint>
#include <cstdio>

namespace fleet::ctl {

namespace {
const char* const kKinds[] = {"held", "plan_end", "limit"};

nlohmann::json zero() {
  return {{"held", 0}, {"plan_end", 0}, {"limit", 0}};
}

std::string part(const char* who, const nlohmann::json& b) {
  char s[160];
  std::snprintf(s, sizeof s, "%s %llu held by others, %llu at the plan's end, %llu with more free (late)",
                who, static_cast<unsigned long long>(b.value("held", std::uint64_t{0})),
                static_cast<unsigned long long>(b.value("plan_end", std::uint64_t{0})),
                static_cast<unsigned long long>(b.value("limit", std::uint64_t{0})));
  return s;
}
}  // namespace

nlohmann::json trafficSummaryJson(const nlohmann::json& summary, const std::set<std::string>& vehicles) {
  nlohmann::json out = summary;
  auto agents = zero();
  auto vdas = zero();
  if (summary.contains("base_ends_by_robot") && summary["base_ends_by_robot"].is_object()) {
    for (const auto& [robot, b] : summary["base_ends_by_robot"].items()) {
      if (!b.is_object()) {
        continue;  // not what the traffic manager writes: left out rather than failing the report
      }
      auto& into = vehicles.count(robot) != 0 ? vdas : agents;
      for (const char* k : kKinds) {
        const auto n = b.find(k);
        if (n != b.end() && n->is_number_integer() && n->get<std::int64_t>() >= 0) {
          into[k] = into[k].get<std::uint64_t>() + n->get<std::uint64_t>();
        }
      }
    }
  }
  out["base_ends_agents"] = agents;
  if (!vehicles.empty()) {
    out["base_ends_vehicles"] = vdas;
  }
  return out;
}

std::string baseEndsLine(const nlohmann::json& traffic) {
  std::string line = "base ends reached short of the target: ";
  line += part("agents", traffic.value("base_ends_agents", zero()));
  if (traffic.contains("base_ends_vehicles")) {
    line += "; VDA 5050 vehicles " + part("", traffic["base_ends_vehicles"]).substr(1);
  }
  return line;
}

}  // namespace fleet::ctl
