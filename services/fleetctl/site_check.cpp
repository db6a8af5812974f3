#include "site_check.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <fstream>
#include <iostream>
#include <sstream>

#include "fleet/core/config.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/site/site_report.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "site_svg.hpp"

namespace fleet::ctl {

namespace {

struct RoadmapSummary {
  std::size_t nodes = 0;
  std::size_t edges = 0;
  std::size_t conflictPairs = 0;
  std::size_t queueNodes = 0;
  std::array<std::size_t, 7> byKind{};
  std::size_t connected = 0;
  double buildMs = 0.0;
};

RoadmapSummary summarise(const traffic::Roadmap& r, double buildMs) {
  RoadmapSummary s;
  s.nodes = r.graph.size();
  s.edges = r.edgeCount();
  s.conflictPairs = traffic::conflictPairs(r.graph);
  s.queueNodes = r.queueNodeCount();
  for (const auto k : r.kinds) {
    ++s.byKind[static_cast<std::size_t>(k)];
  }
  s.connected = traffic::connectedStations(r).size();
  s.buildMs = buildMs;
  return s;
}

std::string formatRoadmap(const traffic::Roadmap& r, const RoadmapSummary& s) {
  std::ostringstream os;
  os << "  roadmap: " << s.nodes << " nodes (";
  for (std::size_t k = 0; k < s.byKind.size(); ++k) {
    os << (k ? ", " : "") << s.byKind[k] << " " << traffic::toString(static_cast<traffic::NodeKind>(k));
  }
  os << "), " << s.edges << " edges";
  if (r.oneWayDropped > 0) {
    os << " (" << r.oneWayDropped << " left out against one-way zones)";
  }
  os << ", " << s.conflictPairs << " conflicting node pairs; built in " << static_cast<long>(s.buildMs + 0.5)
     << " ms\n";
  os << "    lattice " << r.options.spacing << " m from (" << r.latticeOrigin.x << ", " << r.latticeOrigin.y
     << "), 8-connected where the disc fits";
  if (r.droppedLatticeNodes > 0) {
    os << "; " << r.droppedLatticeNodes << " lattice points in pockets no station reaches left out";
  }
  os << "\n    robots keep " << r.separation.contact << " m apart (centres), " << r.separation.ahead
     << " m to one in the corridor ahead; queue nodes " << r.options.followingDistance << " m apart\n";
  os << "    stations connected both ways: " << s.connected << " of " << r.stations.size() << "\n";
  for (const auto& p : r.problems) {
    os << "  roadmap " << (p.severity == traffic::RoadmapProblem::Severity::Error ? "problem" : "warning")
       << ": " << p.what << "\n";
  }
  return os.str();
}

nlohmann::json roadmapJson(const traffic::Roadmap& r, const RoadmapSummary& s) {
  nlohmann::json kinds = nlohmann::json::object();
  for (std::size_t k = 0; k < s.byKind.size(); ++k) {
    kinds[traffic::toString(static_cast<traffic::NodeKind>(k))] = s.byKind[k];
  }
  const auto connected = traffic::connectedStations(r);
  nlohmann::json stations = nlohmann::json::array();
  for (const auto& st : r.stations) {
    stations.push_back(
        {{"name", st.name},
         {"dock", st.dock},
         {"approach", st.approach},
         {"queue", st.queue},
         {"exit", st.exit},
         {"queue_generated", st.queueGenerated},
         {"connected", std::find(connected.begin(), connected.end(), st.name) != connected.end()}});
  }
  nlohmann::json problems = nlohmann::json::array();
  for (const auto& p : r.problems) {
    problems.push_back(
        {{"severity", p.severity == traffic::RoadmapProblem::Severity::Error ? "error" : "warning"},
         {"station", p.station},
         {"at", {p.at.x, p.at.y}},
         {"what", p.what}});
  }
  return {{"nodes", s.nodes},
          {"nodes_by_kind", kinds},
          {"edges", s.edges},
          {"one_way_dropped", r.oneWayDropped},
          {"conflict_pairs", s.conflictPairs},
          {"queue_nodes", s.queueNodes},
          {"spacing", r.options.spacing},
          {"lattice_origin", {r.latticeOrigin.x, r.latticeOrigin.y}},
          {"dropped_lattice_nodes", r.droppedLatticeNodes},
          {"separation", {{"contact", r.separation.contact}, {"ahead", r.separation.ahead}}},
          {"following_distance", r.options.followingDistance},
          {"stations_connected", s.connected},
          {"stations", stations},
          {"problems", problems},
          {"build_ms", s.buildMs}};
}

}  // namespace

int siteCheck(const std::string& file, double radius, double mapResolution, bool asJson,
              const std::string& svgFile) {
  // Geometry is left to the report, so a site with an unreachable station still shows the rest.
  auto site = fleet::loadSiteFile(file, false, mapResolution);
  if (!site) {
    std::cerr << site.error().message << "\n";
    return 2;
  }
  const auto report = site::analyseSite(*site, radius);
  traffic::RoadmapOptions options;
  options.radius = report.radius;
  const auto t0 = std::chrono::steady_clock::now();
  traffic::Roadmap roadmap;
  try {
    roadmap = traffic::buildRoadmap(*site, options);
  } catch (const ConfigError& e) {  // a site too large for the lattice
    for (const auto& p : e.problems()) {
      std::cerr << site->origin << ": " << p << "\n";
    }
    return 2;
  }
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  const auto summary = summarise(roadmap, ms);
  if (asJson) {
    auto j = site::reportJson(report);
    j["roadmap"] = roadmapJson(roadmap, summary);
    std::cout << j.dump(1) << "\n";
  } else {
    std::cout << site::formatReport(report) << formatRoadmap(roadmap, summary);
  }
  for (const auto& p : report.problems) {
    std::cerr << site->origin << ": " << p.key << ": " << p.what << "\n";
  }
  bool roadmapError = false;
  for (const auto& p : roadmap.problems) {
    const bool error = p.severity == traffic::RoadmapProblem::Severity::Error;
    roadmapError = roadmapError || error;
    std::cerr << site->origin << ": roadmap" << (error ? "" : " warning") << ": " << p.what << "\n";
  }
  if (!svgFile.empty()) {
    std::ofstream out(svgFile);
    out << siteSvg(*site, roadmap);
    if (!out) {
      std::cerr << svgFile << ": cannot write the drawing\n";
      return 2;
    }
  }
  return report.problems.empty() && !roadmapError ? 0 : 2;
}

}  // namespace fleet::ctl
