#include "closure_request.hpp"

#include <cmath>
#include <variant>

#include "fleet/core/bounded_json.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/validation/sample_checks.hpp"

namespace fleet::wms {

using nlohmann::json;

namespace {

constexpr std::size_t kMaxArea = 256;  // the TrafficClosure sequence bounds (fleet.idl)
constexpr std::size_t kMaxNodes = 4096;
constexpr std::size_t kMaxReason = 255;

/// A non-negative node id below `nodes` (when known); the problem otherwise.
std::optional<std::string> nodeProblem(const json& v, std::optional<std::size_t> nodes, std::int32_t& out) {
  if (!v.is_number_integer()) {
    return "must be an integer node id";
  }
  const auto n = v.get<std::int64_t>();
  if (n < 0 || n > 0x7fffffff) {
    return "must be a node id >= 0";
  }
  if (nodes && static_cast<std::size_t>(n) >= *nodes) {
    return "is not on the roadmap (node ids 0.." + std::to_string(*nodes - 1) + ")";
  }
  out = static_cast<std::int32_t>(n);
  return std::nullopt;
}

}  // namespace

std::variant<msg::TrafficClosure, std::vector<FieldError>> parseClosure(
    const std::string& id, const std::string& body, std::optional<std::size_t> roadmapNodes,
    std::int64_t nowNs) {
  std::vector<FieldError> errors;
  auto bad = [&](const std::string& path, const std::string& why) { errors.push_back({path, why}); };
  if (!isValidId(id)) {
    bad("id", "is not a valid id (1..63 of [A-Za-z0-9_.:-])");
  }
  // An area is a polygon of a few points, nodes and lanes short lists: bounded before parsing.
  const auto parsed = parseBoundedJson(body, {.maxBytes = 64 * 1024, .maxDepth = 8, .maxElements = 20'000});
  if (!parsed) {
    bad("",
        parsed.error().code == "json.invalid" ? "the body must be a JSON object" : parsed.error().message);
    return errors;
  }
  const json& j = *parsed;
  if (!j.is_object()) {
    bad("", "the body must be a JSON object");
    return errors;
  }
  msg::TrafficClosure c;
  c.closure_id = id;
  c.active = true;
  c.stamp_ns = nowNs;
  for (const auto& [key, value] : j.items()) {
    if (key != "area" && key != "nodes" && key != "lanes" && key != "reason") {
      bad(key, "unknown field (known: area, nodes, lanes, reason)");
    }
  }
  if (j.contains("area")) {
    const auto& a = j["area"];
    if (!a.is_array() || a.size() < 3 || a.size() > kMaxArea) {
      bad("area", "must be a polygon of 3.." + std::to_string(kMaxArea) + " corners [x, y] (m, map frame)");
    } else {
      for (std::size_t i = 0; i < a.size(); ++i) {
        const auto& p = a[i];
        const bool ok = p.is_array() && p.size() == 2 && p[0].is_number() && p[1].is_number() &&
                        std::isfinite(p[0].get<double>()) && std::isfinite(p[1].get<double>()) &&
                        std::abs(p[0].get<double>()) <= validation::kMaxCoordinate &&
                        std::abs(p[1].get<double>()) <= validation::kMaxCoordinate;
        if (!ok) {
          bad("area[" + std::to_string(i) + "]", "must be [x, y] in metres (finite, |v| <= 1e6)");
        } else {
          c.area.push_back({p[0].get<double>(), p[1].get<double>()});
        }
      }
    }
  }
  if (j.contains("nodes")) {
    const auto& a = j["nodes"];
    if (!a.is_array() || a.size() > kMaxNodes) {
      bad("nodes", "must be an array of at most " + std::to_string(kMaxNodes) + " roadmap node ids");
    } else {
      for (std::size_t i = 0; i < a.size(); ++i) {
        std::int32_t v = 0;
        if (auto why = nodeProblem(a[i], roadmapNodes, v)) {
          bad("nodes[" + std::to_string(i) + "]", *why);
        } else {
          c.nodes.push_back(v);
        }
      }
    }
  }
  if (j.contains("lanes")) {
    const auto& a = j["lanes"];
    if (!a.is_array() || a.size() > kMaxNodes) {
      bad("lanes", "must be an array of at most " + std::to_string(kMaxNodes) + " [from, to] node pairs");
    } else {
      for (std::size_t i = 0; i < a.size(); ++i) {
        const std::string path = "lanes[" + std::to_string(i) + "]";
        if (!a[i].is_array() || a[i].size() != 2) {
          bad(path, "must be [from, to] (a directed edge: give both directions to close a lane both ways)");
          continue;
        }
        msg::NodePair e;
        auto w1 = nodeProblem(a[i][0], roadmapNodes, e.from);
        auto w2 = nodeProblem(a[i][1], roadmapNodes, e.to);
        if (w1 || w2) {
          bad(path, w1 ? "from " + *w1 : "to " + *w2);
        } else {
          c.lanes.push_back(e);
        }
      }
    }
  }
  if (j.contains("reason")) {
    if (!j["reason"].is_string() || j["reason"].get<std::string>().size() > kMaxReason) {
      bad("reason", "must be a string of at most " + std::to_string(kMaxReason) + " bytes");
    } else {
      c.reason = j["reason"].get<std::string>();
    }
  }
  if (!j.contains("area") && !j.contains("nodes") && !j.contains("lanes")) {
    bad("", "a closure needs an area, nodes or lanes");
  } else if (errors.empty() && c.area.empty() && c.nodes.empty() && c.lanes.empty()) {
    bad("", "a closure needs an area, nodes or lanes (all given are empty)");
  }
  if (!errors.empty()) {
    return errors;
  }
  return c;
}

json closureJson(const msg::TrafficClosure& c) {
  json area = json::array();
  for (const auto& p : c.area) {
    area.push_back({p.x, p.y});
  }
  json lanes = json::array();
  for (const auto& e : c.lanes) {
    lanes.push_back({e.from, e.to});
  }
  return {{"id", c.closure_id}, {"area", area},       {"nodes", c.nodes},
          {"lanes", lanes},     {"reason", c.reason}, {"stamp_ns", c.stamp_ns}};
}

}  // namespace fleet::wms
