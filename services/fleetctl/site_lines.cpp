#include "site_lines.hpp"

#include <fstream>
#include <iostream>

#include "fleet/core/config.hpp"
#include "fleet/fleet/site_stations.hpp"

namespace fleet::ctl {

namespace {

nlohmann::ordered_json point(const traffic::Roadmap& r, traffic::NodeId v) {
  const Vec2 p = r.graph.position(v);
  // Exact, not rounded: a site built again from the result must give the same roadmap. A station
  // heading that is not exactly a right angle (1.5708) puts derived points micrometres off the
  // round figures, and a join to the lattice or a conflict at a threshold can turn on that.
  return nlohmann::ordered_json::array({p.x, p.y});
}

}  // namespace

nlohmann::ordered_json spellOutLines(nlohmann::ordered_json site, const traffic::Roadmap& roadmap) {
  if (!site.contains("stations") || !site["stations"].is_array()) {
    return site;
  }
  for (auto& st : site["stations"]) {
    const auto* sn = roadmap.station(st.value("name", ""));
    if (sn == nullptr || sn->dock == traffic::kNoNode || sn->kind == site::StationKind::Parking) {
      continue;
    }
    st.erase("approach");
    st.erase("queue");
    st.erase("exit");
    if (sn->approach != traffic::kNoNode) {
      st["approach"] = point(roadmap, sn->approach);
    }
    if (!sn->queue.empty()) {
      auto q = nlohmann::ordered_json::array();
      for (const auto v : sn->queue) {
        q.push_back(point(roadmap, v));
      }
      st["queue"] = q;
    }
    if (sn->exit != traffic::kNoNode) {
      st["exit"] = point(roadmap, sn->exit);
    } else if (sn->kind != site::StationKind::Charging) {
      st["exit"] = "entry";
    }
  }
  return site;
}

namespace {

/// The spelled-out text of the site file, or every problem found, one per line.
Expected<std::string> spelledOut(const std::string& file) {
  auto site = fleet::loadSiteFile(file);
  if (!site) {
    return unexpected(site.error());
  }
  std::ifstream in(file);
  nlohmann::ordered_json doc;
  try {
    doc = nlohmann::ordered_json::parse(in);
  } catch (const nlohmann::json::exception& e) {
    return unexpected("site", file + ": " + e.what());
  }
  if (!doc.is_object() || !doc.contains("stations")) {
    return unexpected("site",
                      file + ": not a site.json with stations (give the site file itself, not a scenario)");
  }
  traffic::RoadmapOptions options;
  options.radius = site->robot.radius;
  traffic::Roadmap roadmap;
  std::string problems;
  try {
    roadmap = traffic::buildRoadmap(*site, options);
  } catch (const ConfigError& e) {
    for (const auto& p : e.problems()) {
      problems += file + ": " + p + "\n";
    }
  }
  for (const auto& p : roadmap.problems) {
    if (p.severity == traffic::RoadmapProblem::Severity::Error) {
      problems += file + ": roadmap: " + p.what + "\n";
    }
  }
  if (!problems.empty()) {
    return unexpected("site", problems + file + ": the lines of a roadmap with problems are not the site's");
  }
  return spellOutLines(std::move(doc), roadmap).dump(1) + "\n";
}

}  // namespace

int siteLines(const std::string& file, const std::string& out) {
  const auto text = spelledOut(file);
  if (!text) {
    std::cerr << text.error().message << "\n"
              << "nothing written\n";
    return 2;
  }
  if (out == "-") {
    std::cout << *text;
    return 0;
  }
  std::ofstream o(out);
  o << *text;
  if (!o) {
    std::cerr << out << ": cannot write the site\n";
    return 2;
  }
  return 0;
}

Expected<void> spellOutLinesInPlace(const std::string& file) {
  auto text = spelledOut(file);
  if (!text) {
    return unexpected(text.error());
  }
  std::ofstream o(file);
  o << *text;
  if (!o) {
    return unexpected("site", file + ": cannot write the site");
  }
  return {};
}

}  // namespace fleet::ctl
