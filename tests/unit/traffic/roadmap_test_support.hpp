#pragma once

// What the roadmap tests share: the shipped sites, sites from MovingAI rows, and small checks on a
// built roadmap (roadmap_test.cpp, roadmap_stations_test.cpp).

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <functional>
#include <limits>
#include <nlohmann/json.hpp>
#include <queue>
#include <string>
#include <vector>

#include "fleet/site/site_loader.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic::test {

namespace fs = std::filesystem;
inline constexpr double kPi = 3.14159265358979323846;

inline site::Site shipped(const std::string& rel) {
  return site::loadSite((fs::path(FLEET_SOURCE_DIR) / "sim/scenarios" / rel).string());
}

// A site from MovingAI rows (first row = top), 0.5 m cells, robot radius 0.3 m.
inline site::Site rowsSite(const std::vector<std::string>& rows, nlohmann::json stations,
                           nlohmann::json zones = nlohmann::json::array()) {
  nlohmann::json doc = {{"format", "fleet-site/1"},
                        {"name", "test"},
                        {"map", {{"rows", rows}, {"resolution", 0.5}}},
                        {"robot", {{"radius", 0.3}}},
                        {"stations", std::move(stations)},
                        {"zones", std::move(zones)}};
  return site::parseSite(doc, "test.site.json", ".", false);
}

inline std::size_t errors(const Roadmap& r) {
  return static_cast<std::size_t>(std::count_if(r.problems.begin(), r.problems.end(), [](const auto& p) {
    return p.severity == RoadmapProblem::Severity::Error;
  }));
}

inline std::string describe(const std::vector<RoadmapProblem>& ps) {
  std::string s;
  for (const auto& p : ps) {
    s += p.what + "\n";
  }
  return s;
}

inline bool hasEdge(const Graph& g, NodeId a, NodeId b) {
  for (const auto& e : g.edges(a)) {
    if (e.to == b) {
      return true;
    }
  }
  return false;
}

// A 10 m × 4 m hall (0.5 m cells) with walls around.
inline std::vector<std::string> hall() {
  std::vector<std::string> rows(10, "@" + std::string(20, '.') + "@");
  rows.front() = rows.back() = std::string(22, '@');
  return rows;
}

inline nlohmann::json twoStations() {
  return {{{"name", "A"}, {"kind", "pickup"}, {"pose", {1.5, 2.5, 0.0}}},
          {{"name", "B"}, {"kind", "dropoff"}, {"pose", {9.5, 2.5, kPi}}}};
}

// Dijkstra forward from `from` over open edges by their durations, written apart from
// DistanceTable's backward search and the guidance's router: the shortest time to `to`.
inline double shortestTime(const Graph& g, NodeId from, NodeId to) {
  std::vector<double> d(g.size(), std::numeric_limits<double>::infinity());
  using Item = std::pair<double, NodeId>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  d[static_cast<std::size_t>(from)] = 0.0;
  open.push({0.0, from});
  while (!open.empty()) {
    const auto [dv, v] = open.top();
    open.pop();
    if (dv > d[static_cast<std::size_t>(v)])
      continue;
    for (const auto& e : g.edges(v)) {
      if (g.passable(v, e) && dv + e.duration < d[static_cast<std::size_t>(e.to)]) {
        d[static_cast<std::size_t>(e.to)] = dv + e.duration;
        open.push({dv + e.duration, e.to});
      }
    }
  }
  return d[static_cast<std::size_t>(to)];
}

}  // namespace fleet::traffic::test
