// fleetctl site lines: the lines the roadmap derives, spelled out in site.json, give the same
// roadmap; a site whose roadmap has problems is not spelled out.
#include "site_lines.hpp"

#include <gtest/gtest.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "fleet/site/site_loader.hpp"

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::ordered_json;

fs::path tempFile(const std::string& name) {
  return fs::temp_directory_path() / ("site-lines-" + name + "-" + std::to_string(::getpid()) + ".site.json");
}

ordered_json readJson(const fs::path& p) {
  std::ifstream in(p);
  return ordered_json::parse(in);
}

traffic::Roadmap roadmapOf(const fs::path& p) {
  const auto site = site::loadSite(p.string());
  traffic::RoadmapOptions o;
  o.radius = site.robot.radius;
  return traffic::buildRoadmap(site, o);
}

/// `v`'s out-neighbours and the nodes it excludes, each sorted.
std::pair<std::vector<traffic::NodeId>, std::vector<traffic::NodeId>> around(const traffic::Graph& g,
                                                                             traffic::NodeId v) {
  std::vector<traffic::NodeId> out;
  for (const auto& e : g.edges(v)) {
    out.push_back(e.to);
  }
  std::vector<traffic::NodeId> excludes(g.conflicts(v).begin(), g.conflicts(v).end());
  std::sort(out.begin(), out.end());
  std::sort(excludes.begin(), excludes.end());
  return {out, excludes};
}

/// Every node whose position, kind, edges or conflicts differ between two roadmaps, one per line.
std::string differences(const traffic::Roadmap& a, const traffic::Roadmap& b) {
  std::ostringstream d;
  if (a.graph.size() != b.graph.size()) {
    d << "nodes " << a.graph.size() << " vs " << b.graph.size() << "\n";
    return d.str();
  }
  for (traffic::NodeId v = 0; v < static_cast<traffic::NodeId>(a.graph.size()); ++v) {
    const Vec2 p = a.graph.position(v);
    const auto [outA, exA] = around(a.graph, v);
    const auto [outB, exB] = around(b.graph, v);
    const bool same = (p - b.graph.position(v)).norm() <= 1e-12 &&
                      a.kinds[static_cast<std::size_t>(v)] == b.kinds[static_cast<std::size_t>(v)];
    if (!same || outA != outB || exA != exB) {
      d << "node " << v << " at (" << p.x << ", " << p.y << "):" << (same ? "" : " position or kind")
        << (outA == outB ? "" : " edges") << (exA == exB ? "" : " conflicts") << " differ\n";
    }
  }
  return d.str();
}

// The shipped small warehouse with its stations bare (no approach, queue or exit): the roadmap
// derives them; spelled out, the site gives the same roadmap, node for node.
TEST(SiteLines, SpelledOutLinesGiveTheRoadmapTheyWereReadFrom) {
  for (const std::string name : {"small_warehouse", "aisle_crossing", "passage_head_on"}) {
    SCOPED_TRACE(name);
    auto doc = readJson(std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/" + name + ".site.json");
    for (auto& st : doc["stations"]) {
      st.erase("approach");
      st.erase("queue");
      st.erase("exit");
    }
    const auto bare = tempFile(name + "-bare");
    std::ofstream(bare) << doc.dump(1);
    const auto derived = roadmapOf(bare);
    const auto spelled = tempFile(name + "-spelled");
    ASSERT_EQ(siteLines(bare.string(), spelled.string()), 0);
    const auto out = readJson(spelled);
    std::size_t lines = 0;
    for (const auto& st : out["stations"]) {
      if (st["kind"] == "pickup" || st["kind"] == "dropoff") {
        EXPECT_TRUE(st.contains("queue")) << st.dump();
        EXPECT_TRUE(st.contains("exit")) << st.dump();
        ++lines;
      } else if (st["kind"] == "parking") {
        EXPECT_FALSE(st.contains("queue") || st.contains("exit")) << st.dump();
      }
    }
    EXPECT_GT(lines, 0U);
    EXPECT_EQ(out["map"], doc["map"]);  // the rest of the site as it was
    EXPECT_EQ(differences(derived, roadmapOf(spelled)), "");
    fs::remove(bare);
    fs::remove(spelled);
  }
}

// A dead end with no room for a way out: refused, nothing written, until the site says the
// station is left by its way in; then it is spelled out as such.
TEST(SiteLines, ARoadmapWithProblemsIsNotSpelledOut) {
  ordered_json doc = {{"format", "fleet-site/1"},
                      {"name", "dead-end"},
                      {"map",
                       {{"rows",
                         {"@@@@@@@@@@@@@@@@@@@@@@", "@.............@@@@@@@@", "@.............@@@@@@@@",
                          "@.............@@@@@@@@", "@.....................", "@.....................",
                          "@.............@@@@@@@@", "@.............@@@@@@@@", "@.............@@@@@@@@",
                          "@@@@@@@@@@@@@@@@@@@@@@"}},
                        {"resolution", 0.5}}},
                      {"robot", {{"radius", 0.3}, {"wheel_base", 0.4}, {"limits", {{"v_max", 1.0}}}}},
                      {"stations",
                       {{{"name", "A"}, {"kind", "pickup"}, {"pose", {2.0, 2.5, 0.0}}},
                        {{"name", "B"}, {"kind", "dropoff"}, {"pose", {10.0, 2.5, 3.1416}}}}}};
  const auto in = tempFile("dead-end");
  const auto out = tempFile("dead-end-out");
  std::ofstream(in) << doc.dump(1);
  fs::remove(out);
  EXPECT_EQ(siteLines(in.string(), out.string()), 2);
  EXPECT_FALSE(fs::exists(out));
  doc["stations"][1]["exit"] = "entry";
  std::ofstream(in) << doc.dump(1);
  ASSERT_EQ(siteLines(in.string(), out.string()), 0);
  EXPECT_EQ(readJson(out)["stations"][1]["exit"], "entry");
  EXPECT_EQ(differences(roadmapOf(in), roadmapOf(out)), "");
  fs::remove(in);
  fs::remove(out);
}

}  // namespace
}  // namespace fleet::ctl
