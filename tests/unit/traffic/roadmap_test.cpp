// The roadmap built from a site: the shipped sites, the lattice's fit to the robot, and the
// geometric guarantee of its conflicts, checked by sampling robot positions against the motion
// gate's own rule (written out here, independently of the library's exact region test). Zones,
// durations, stations and closures: roadmap_stations_test.cpp.

#include "fleet/traffic/roadmap.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <optional>
#include <random>
#include <sstream>

#include "fleet/site/reachability.hpp"
#include "fleet/site/site_loader.hpp"
#include "roadmap_test_support.hpp"

namespace fleet::traffic {
namespace {

using namespace test;  // NOLINT(google-build-using-namespace): the roadmap tests' shared helpers

// ---- the motion gate's rule, point by point --------------------------------------------------

struct Placed {
  Vec2 p;
  std::optional<Vec2> heading;  // driving forward along it; none: standing
};

// Centres closer than `contact`, or one robot driving with the other in its corridor ahead (centre
// ahead of it, within `corridor` of its heading line) closer than `ahead`.
bool tooClose(const Placed& a, const Placed& b, const Separation& s) {
  if (distance(a.p, b.p) < s.contact - 1e-9) {
    return true;
  }
  auto blocks = [&](const Placed& x, const Placed& y) {
    if (!x.heading) {
      return false;
    }
    const Vec2 rel = y.p - x.p;
    return rel.dot(*x.heading) > 1e-9 && std::abs(rel.cross(*x.heading)) <= s.corridor &&
           rel.norm() < s.ahead - 1e-9;
  };
  return blocks(a, b) || blocks(b, a);
}

// A robot's motion on the roadmap: standing on `from` (to == kNoNode) or driving from→to.
struct Move {
  NodeId from = kNoNode;
  NodeId to = kNoNode;
};

std::vector<Placed> samples(const Graph& g, const Move& m, int n) {
  const Vec2 a = g.position(m.from);
  if (m.to == kNoNode) {
    return {{a, std::nullopt}};
  }
  const Vec2 b = g.position(m.to);
  std::vector<Placed> out;
  for (int i = 0; i <= n; ++i) {
    out.push_back({a + (b - a) * (static_cast<double>(i) / n), (b - a).normalized()});
  }
  return out;
}

std::vector<NodeId> held(const Move& m) {
  return m.to == kNoNode ? std::vector<NodeId>{m.from} : std::vector<NodeId>{m.from, m.to};
}

// The execution rule allows the two motions at once: no node held by one conflicts with (or is)
// a node held by the other.
bool allowedTogether(const Graph& g, const Move& a, const Move& b) {
  for (const NodeId x : held(a)) {
    for (const NodeId y : held(b)) {
      if (g.conflicting(x, y)) {
        return false;
      }
    }
  }
  return true;
}

struct PropertyResult {
  std::size_t checked = 0;     // pairs of motions the execution rule allows together
  std::size_t violations = 0;  // ... of which some sampled placement breaks the separation
  std::string first;
};

// Random pairs of motions starting within 2.5 m of each other (standing or driving, either robot)
// that the conflicts allow together; every sampled placement must keep the separation `s`.
PropertyResult sampleMotions(const Graph& g, const Separation& s, std::size_t pairs, unsigned seed) {
  std::vector<std::vector<Move>> from(g.size());
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    from[static_cast<std::size_t>(v)].push_back({v, kNoNode});
    for (const auto& e : g.edges(v)) {
      from[static_cast<std::size_t>(v)].push_back({v, e.to});
    }
  }
  std::vector<std::vector<NodeId>> near(g.size());
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    for (NodeId w = 0; w < static_cast<NodeId>(g.size()); ++w) {
      if (w != v && distance(g.position(v), g.position(w)) <= 2.5) {
        near[static_cast<std::size_t>(v)].push_back(w);
      }
    }
  }
  std::mt19937 rng(seed);
  auto any = [&rng](const auto& v) {
    return v[std::uniform_int_distribution<std::size_t>(0, v.size() - 1)(rng)];
  };
  std::uniform_int_distribution<NodeId> node(0, static_cast<NodeId>(g.size()) - 1);
  PropertyResult r;
  for (std::size_t tries = 0; r.checked < pairs && tries < 100 * pairs; ++tries) {
    const NodeId v = node(rng);
    if (near[static_cast<std::size_t>(v)].empty()) {
      continue;
    }
    const Move a = any(from[static_cast<std::size_t>(v)]);
    const Move b = any(from[static_cast<std::size_t>(any(near[static_cast<std::size_t>(v)]))]);
    if (!allowedTogether(g, a, b)) {
      continue;
    }
    ++r.checked;
    bool bad = false;
    for (const auto& pa : samples(g, a, 24)) {
      for (const auto& pb : samples(g, b, 24)) {
        if (!bad && tooClose(pa, pb, s)) {
          bad = true;
          if (r.violations == 0) {
            std::ostringstream os;
            os << "robot at (" << pa.p.x << ", " << pa.p.y << ") on " << a.from << "->" << a.to
               << ", robot at (" << pb.p.x << ", " << pb.p.y << ") on " << b.from << "->" << b.to;
            r.first = os.str();
          }
        }
      }
    }
    r.violations += bad ? 1 : 0;
  }
  return r;
}

// ---- shipped sites ---------------------------------------------------------------------------

struct ShippedCase {
  const char* file;
  std::size_t minNodes;
  std::size_t maxNodes;
};

void PrintTo(const ShippedCase& c, std::ostream* os) {
  *os << c.file;
}

class ShippedSites : public ::testing::TestWithParam<ShippedCase> {};

TEST_P(ShippedSites, EveryStationIsConnectedBothWays) {
  const auto s = shipped(GetParam().file);
  const auto t0 = std::chrono::steady_clock::now();
  const Roadmap r = buildRoadmap(s);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::cout << GetParam().file << ": " << r.graph.size() << " nodes (" << r.queueNodeCount() << " queue), "
            << r.edgeCount() << " edges, " << conflictPairs(r.graph) << " conflicting pairs, spacing "
            << r.options.spacing << " m, lattice origin (" << r.latticeOrigin.x << ", " << r.latticeOrigin.y
            << "), built in " << ms << " ms\n";
  EXPECT_TRUE(r.problems.empty()) << describe(r.problems);
  EXPECT_EQ(connectedStations(r).size(), s.stations.size());
  for (const auto& st : r.stations) {
    EXPECT_NE(st.dock, kNoNode) << st.name;
    // A well-formed site: a robot resting at a parking place excludes no lane node.
    if (st.kind == site::StationKind::Parking && st.dock != kNoNode) {
      for (const NodeId w : r.graph.conflicts(st.dock)) {
        EXPECT_NE(r.kind(w), NodeKind::Lane) << st.name << " excludes lane node " << w;
      }
    }
  }
  EXPECT_GE(r.graph.size(), GetParam().minNodes);
  EXPECT_LE(r.graph.size(), GetParam().maxNodes);
}

INSTANTIATE_TEST_SUITE_P(Roadmap, ShippedSites,
                         ::testing::Values(ShippedCase{"small_warehouse.site.json", 300, 2000},
                                           ShippedCase{"ros_warehouse/site.json", 300, 2000},
                                           ShippedCase{"large_warehouse.site.json", 5000, 60000}),
                         [](const ::testing::TestParamInfo<ShippedCase>& i) {
                           std::string n = fs::path(i.param.file).parent_path().empty()
                                               ? fs::path(i.param.file).stem().stem().string()
                                               : fs::path(i.param.file).parent_path().string();
                           std::replace(n.begin(), n.end(), '-', '_');
                           return n;
                         });

// The ROS warehouse's corridor along the south wall is 1.9 m wide: with the parking places in its
// middle (y 1.25) no lane fits beside a parked robot, so the lattice clear of parked robots cuts
// the row off. The roadmap falls back to the lanes beside the parking places and says so; asked
// for that lattice it gives it without the warning.
TEST(Roadmap, ParkingInACorridorOfItsOwnWidthFallsBackToLanesBesideItWithAWarning) {
  const fs::path dir = fs::path(FLEET_SOURCE_DIR) / "sim/scenarios/ros_warehouse";
  std::ifstream in(dir / "site.json");
  auto doc = nlohmann::json::parse(in);
  for (auto& st : doc["stations"]) {
    if (st["kind"] == "parking") {
      st["pose"][1] = 1.25;
    }
  }
  const auto s = site::parseSite(doc, "ros_warehouse with its parking row at y 1.25", dir.string());
  const Roadmap r = buildRoadmap(s);
  EXPECT_FALSE(r.options.parkingClear);
  ASSERT_EQ(r.problems.size(), 1U) << describe(r.problems);
  EXPECT_EQ(r.problems[0].severity, RoadmapProblem::Severity::Warning);
  EXPECT_NE(r.problems[0].what.find("a robot parked there blocks the lanes next to it"), std::string::npos);
  EXPECT_EQ(connectedStations(r).size(), s.stations.size());
  RoadmapOptions beside;
  beside.parkingClear = false;
  const Roadmap asked = buildRoadmap(s, beside);
  EXPECT_TRUE(asked.problems.empty()) << describe(asked.problems);
  EXPECT_EQ(asked.graph.size(), r.graph.size());
}

TEST(Roadmap, SmallWarehouseAislesGetOneNodeLineOnTheirCentre) {
  const Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  EXPECT_DOUBLE_EQ(r.options.spacing, 0.5);
  // The aisle between the first two shelf rows spans y 3.5..5.0 m (cells 7..9): its centre is 4.25.
  int onCentre = 0;
  int offCentre = 0;
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    const Vec2 p = r.graph.position(v);
    if (r.kind(v) != NodeKind::Lane || p.x < 8.5 || p.x > 11.5) {
      continue;  // alongside the second shelf block (x 8..12 m), away from the cross aisles
    }
    if (p.y > 3.5 && p.y < 5.0) {
      (std::abs(p.y - 4.25) < 1e-9 ? onCentre : offCentre)++;
    }
  }
  EXPECT_EQ(onCentre, 6);  // x = 8.75 … 11.25
  EXPECT_EQ(offCentre, 0);
}

TEST(Roadmap, RosWarehouseLatticeLiesOnItsAisleCentresToo) {
  // The same warehouse at 0.1 m cells: 0.5 m spacing is 5 cells, and of the 25 ways to lay the
  // lattice on cell centres the clearance rule picks the one on the aisles' centres.
  const Roadmap r = buildRoadmap(shipped("ros_warehouse/site.json"));
  EXPECT_NEAR(r.options.spacing, 0.5, 1e-9);
  EXPECT_NEAR(std::remainder(r.latticeOrigin.x - 0.25, 0.5), 0.0, 1e-6);
  EXPECT_NEAR(std::remainder(r.latticeOrigin.y - 0.25, 0.5), 0.0, 1e-6);
}

// Lane nodes keep nodeClearance around the disc: robots stop a few centimetres off their node, and
// beside a shelf corner (5.4 cm on the small warehouse's diagonals) the stop rule then held them.
TEST(Roadmap, LaneNodesKeepTheirClearanceFromShelves) {
  const auto s = shipped("small_warehouse.site.json");
  const auto g = s.drivable();
  auto tight = [&](const Roadmap& r) {
    std::size_t n = 0;
    for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
      n += r.kind(v) == NodeKind::Lane && !site::discFits(g, r.graph.position(v), 0.3 + 0.1) ? 1 : 0;
    }
    return n;
  };
  const Roadmap r = buildRoadmap(s);
  EXPECT_NEAR(r.options.nodeClearance, 0.1, 1e-12);
  EXPECT_EQ(tight(r), 0U);
  RoadmapOptions o;
  o.nodeClearance = 0.0;
  o.edgeClearance = 0.0;  // else the nodes beside corners are left without edges and dropped
  const Roadmap before = buildRoadmap(s, o);
  EXPECT_GT(tight(before), 0U) << "without it the lattice has nodes beside shelf corners";
  EXPECT_LT(r.graph.size(), before.graph.size());
  EXPECT_TRUE(r.problems.empty() ||
              std::none_of(r.problems.begin(), r.problems.end(),
                           [](const auto& p) { return p.severity == RoadmapProblem::Severity::Error; }))
      << "every station still connected";
  o.nodeClearance = -0.1;
  EXPECT_THROW(buildRoadmap(s, o), std::invalid_argument);
}

TEST(Roadmap, EveryNodeAndEdgeFitsTheRobotsDisc) {
  const auto s = shipped("small_warehouse.site.json");
  const Roadmap r = buildRoadmap(s);
  const auto g = s.drivable();
  for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
    ASSERT_TRUE(site::discFits(g, r.graph.position(v), 0.3)) << v;
    for (const auto& e : r.graph.edges(v)) {
      ASSERT_TRUE(site::segmentFits(g, r.graph.position(v), r.graph.position(e.to), 0.3))
          << v << "->" << e.to;
    }
  }
}

// The motion gate keeps its stop gap to static points within 0.05 m of the route, so a lane edge
// keeps that much (and 0.02 m of tracking error) beyond the disc along its whole length: with
// lane nodes allowed beside shelf corners (nodeClearance 0), the edges past the corners are left out.
TEST(Roadmap, LaneEdgesKeepTheGatesCorridorClear) {
  const auto s = shipped("small_warehouse.site.json");
  const auto g = s.drivable();
  RoadmapOptions o;
  o.nodeClearance = 0.0;
  auto tight = [&](const Roadmap& r) {
    std::size_t n = 0;
    for (NodeId v = 0; v < static_cast<NodeId>(r.graph.size()); ++v) {
      for (const auto& e : r.graph.edges(v)) {
        const bool lanes = r.kind(v) == NodeKind::Lane && r.kind(e.to) == NodeKind::Lane;
        n += lanes && !site::segmentFits(g, r.graph.position(v), r.graph.position(e.to), 0.3 + 0.07) ? 1 : 0;
      }
    }
    return n;
  };
  const Roadmap r = buildRoadmap(s, o);
  EXPECT_NEAR(r.options.edgeClearance, 0.07, 1e-12);
  EXPECT_EQ(tight(r), 0U);
  o.edgeClearance = 0.0;
  EXPECT_GT(tight(buildRoadmap(s, o)), 0U) << "without it, edges pass shelf corners closer";
  o.edgeClearance = -0.01;
  EXPECT_THROW(buildRoadmap(s, o), std::invalid_argument);
}

// ---- the geometric guarantee -----------------------------------------------------------------

TEST(Roadmap, ConflictsAreSymmetricAndStandingRobotsKeepTheContactDistance) {
  const Roadmap r = buildRoadmap(shipped("small_warehouse.site.json"));
  const auto& g = r.graph;
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    for (const NodeId w : g.conflicts(v)) {
      ASSERT_TRUE(g.conflicting(w, v));
    }
    for (NodeId w = v + 1; w < static_cast<NodeId>(g.size()); ++w) {
      if (distance(g.position(v), g.position(w)) < r.separation.contact) {
        ASSERT_TRUE(g.conflicting(v, w)) << v << " " << w;
      }
    }
  }
  EXPECT_NEAR(r.separation.contact, 0.7, 1e-12);
  EXPECT_NEAR(r.separation.ahead, 1.0, 1e-12);
  EXPECT_NEAR(r.separation.corridor, 0.75, 1e-12);
}

TEST(Roadmap, MotionsTheConflictsAllowTogetherKeepTheirDistance) {
  // Small warehouse (aisles, parking row, station legs, queues) and an open hall (diagonals
  // everywhere), robots standing or driving anywhere along their edges.
  for (const auto& s : {shipped("small_warehouse.site.json"), rowsSite(hall(), twoStations())}) {
    const Roadmap r = buildRoadmap(s);
    const auto res = sampleMotions(r.graph, r.separation, 20000, 11);
    EXPECT_GT(res.checked, 19000U) << s.name;
    EXPECT_EQ(res.violations, 0U) << s.name << ": " << res.first;
  }
}

TEST(Roadmap, TheSamplingCatchesConflictsThatAreTooFew) {
  // The same check against a roadmap built for a smaller robot finds robots too close: the
  // property test above can fail.
  const auto s = shipped("small_warehouse.site.json");
  const Roadmap full = buildRoadmap(s);
  RoadmapOptions o;
  o.margin = 0.0;
  o.stopGap = 0.0;
  const Roadmap thin = buildRoadmap(s, o);
  EXPECT_LT(conflictPairs(thin.graph), conflictPairs(full.graph));
  const auto res = sampleMotions(thin.graph, full.separation, 5000, 5);
  EXPECT_GT(res.violations, 100U);
}

TEST(Roadmap, UnsafeAgreesWithTheGatesRuleOnSampledSegments) {
  // The exact region test against dense sampling, on random short segments.
  const Separation s;
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1.5, 1.5);
  std::bernoulli_distribution moving(0.7);
  int agree = 0;
  for (int i = 0; i < 4000; ++i) {
    const Motion a{{0.0, 0.0}, {u(rng) * 0.5, u(rng) * 0.5}, moving(rng)};
    const Vec2 b0{u(rng), u(rng)};
    const Motion b{b0, b0 + Vec2{u(rng) * 0.5, u(rng) * 0.5}, moving(rng)};
    bool sampled = false;
    const int n = 60;
    for (int x = 0; x <= n && !sampled; ++x) {
      for (int y = 0; y <= n && !sampled; ++y) {
        const Vec2 pa = a.moving ? a.from + (a.to - a.from) * (static_cast<double>(x) / n) : a.from;
        const Vec2 pb = b.moving ? b.from + (b.to - b.from) * (static_cast<double>(y) / n) : b.from;
        sampled = tooClose({pa, a.moving ? std::optional((a.to - a.from).normalized()) : std::nullopt},
                           {pb, b.moving ? std::optional((b.to - b.from).normalized()) : std::nullopt}, s);
      }
    }
    // Sampling can only miss a violation (a sliver between samples), never invent one.
    if (sampled) {
      EXPECT_TRUE(unsafe(a, b, s)) << i;
    }
    agree += sampled == unsafe(a, b, s) ? 1 : 0;
  }
  EXPECT_GT(agree, 3900);
}

}  // namespace
}  // namespace fleet::traffic
