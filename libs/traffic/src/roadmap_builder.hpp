#pragma once

// The roadmap under construction (internal): buildRoadmap (roadmap.cpp) lays the lattice
// (roadmap_lattice.cpp), places the stations with their ways in and out and their queues
// (roadmap_stations.cpp), then keeps what a robot can reach.

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "fleet/site/reachability.hpp"
#include "fleet/site/site.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic::detail {

inline constexpr double kPi = 3.14159265358979323846;

inline double angleBetween(Vec2 a, Vec2 b) {
  const double c = a.normalized().dot(b.normalized());
  return std::acos(std::clamp(c, -1.0, 1.0));
}

// Undirected pair of nodes with the directions a robot may drive it.
struct Link {
  NodeId a = kNoNode;
  NodeId b = kNoNode;
  bool ab = true;
  bool ba = true;
};

struct RoadmapBuilder {
  const site::Site& site;
  RoadmapOptions opt;
  planning::OccupancyGrid grid;  // the drivable map: no-go cells blocked
  std::vector<Vec2> pos;
  std::vector<NodeKind> kind;
  std::vector<Link> links;
  std::vector<RoadmapProblem> problems;
  std::vector<StationNodes> stations;
  std::size_t latticeCount = 0;  // nodes [0, latticeCount) are the lattice
  std::vector<std::uint8_t>
      latticeLinked;  // per lattice node: it has a lattice edge (stations join only those)
  Vec2 latticeOrigin;

  NodeId add(Vec2 p, NodeKind k) {
    pos.push_back(p);
    kind.push_back(k);
    return static_cast<NodeId>(pos.size() - 1);
  }
  [[nodiscard]] bool fits(Vec2 p) const { return site::discFits(grid, p, opt.radius); }
  [[nodiscard]] bool latticeFits(Vec2 p) const {
    return site::discFits(grid, p, opt.radius + opt.nodeClearance);
  }
  // Parking places (robots rest there for long) with RoadmapOptions::parkingClear: the lattice
  // keeps its nodes and edges clear of a robot parked there, so that it excludes no lane (a
  // "well-formed" site, docs/algorithms.md "Parked robots block no lane"). Chargers are not in
  // it: on the shipped sites they stand in a corridor along the wall that the rule would cut off.
  std::vector<Vec2> resting;  // sorted by x
  Separation sep;             // set before the lattice is laid
  /// Neither standing at `a` (a == b) nor driving a→b or b→a comes too close to a robot resting
  /// (roadmap_conflicts.hpp, unsafe()).
  [[nodiscard]] bool clearOfResting(Vec2 a, Vec2 b) const;
  [[nodiscard]] bool sweeps(Vec2 a, Vec2 b) const { return site::segmentFits(grid, a, b, opt.radius); }
  [[nodiscard]] bool passes(Vec2 a, Vec2 b) const {
    return site::segmentFits(grid, a, b, opt.radius + opt.edgeClearance);
  }
  void problem(RoadmapProblem::Severity sev, const std::string& station, Vec2 p, const std::string& what) {
    problems.push_back({sev, station, p, what});
  }
  /// The key path of a field of `st` (one of site.stations) in site.json, as problems name it:
  /// "stations[2].exit: ...".
  [[nodiscard]] std::string keyOf(const site::Station& st, const char* field) const {
    return "stations[" + std::to_string(&st - site.stations.data()) + "]." + field + ": ";
  }

  // roadmap_lattice.cpp: the lattice and the joins to it.
  Vec2 chooseLatticeOrigin(int k);
  void buildLattice();
  enum class Join { Both, Out, In };
  int joinToLattice(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how);
  /// A station's entry or exit: edges that keep the corridor's clearance (`passes`) in the cone of
  /// `dirs`, else such edges in any direction, and only then edges that clear the disc alone (in
  /// the cone, then anywhere). A robot a few centimetres off its node on an edge that clears only
  /// its disc is held there by the motion gate for good.
  int joinClear(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how);
  int joinToLattice(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how, bool wide);

  // Queues keep a following distance from every station node placed so far.
  [[nodiscard]] bool clearOfStations(Vec2 p, double keep) const {
    for (std::size_t v = latticeCount; v < pos.size(); ++v) {
      if (distance(p, pos[v]) < keep - 1e-9) {
        return false;
      }
    }
    return true;
  }

  // roadmap_stations.cpp: docks, approach points, ways out and queues.
  std::vector<Vec2> generateQueue(Vec2 base, const std::vector<Vec2>& dirs);
  [[nodiscard]] NodeId entryOf(const StationNodes& sn) const {
    return sn.approach != kNoNode ? sn.approach : sn.dock;
  }

  [[nodiscard]] std::optional<Vec2> nextPlaces(site::StationKind k) const;
  [[nodiscard]] std::optional<Vec2> placeExit(const site::Station& st, const StationNodes& sn) const;
  void placeStations();
  void placeQueue(const site::Station& st, StationNodes& sn);
  void joinQueue(const StationNodes& sn);

  // roadmap.cpp: the zones' say on an edge.
  bool allowed(Vec2 a, Vec2 b) const;
  double driveTime(Vec2 a, Vec2 b) const;
};

}  // namespace fleet::traffic::detail
