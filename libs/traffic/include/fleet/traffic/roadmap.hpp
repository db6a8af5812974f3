#pragma once

// The roadmap of a site: the graph robots are planned on (docs/algorithms.md, "Traffic: roadmap").
//
// - Lane nodes on a square lattice over the free floor, wherever the robot's disc fits (no-go zones
//   are blocked); lattice points are cell centres, `spacing` a whole number of cells (0.5 m by
//   default: on the small warehouse's 0.5 m cells every 1.5 m aisle gets one node line on its
//   centre; on finer maps the lattice is laid so its lines run down the middle of most aisles).
//   Neighbours are joined when the disc fits along the straight step, diagonals included. Passages
//   the lattice misses (narrower than a spacing plus the disc, off its lines) get nodes half a
//   spacing off the lattice. Pockets no station reaches are left out.
// - Per station: a dock node at its pose, an approach node at its approach point joined to the dock
//   by the straight last leg (stations approached along a row have none: the dock itself is joined
//   to the nearest lattice nodes the disc reaches in a straight line), and queue nodes where robots
//   wait in line, nearest first: the site's queue points, or generated one following distance
//   apart back from the approach point (or along the row) while the disc fits. A queue is a line:
//   one way toward the station (tail → … → head → approach), entered at its tail from behind, left
//   sideways from any of its nodes, so no robot joining or leaving drives at those waiting.
// - Edge durations: length at the cruise speed (slower in speed-limit zones) plus the least turning
//   any way into the edge's start needs (exact where a node has one way in, e.g. the 180° turn out
//   of a dock; zero inside the lattice, where a straight way in exists); extraTurn() gives the rest
//   for a planner that knows where a robot came from. Turns are timed as the agent takes them
//   (bendTime): corners on the spot, the lattice's 45° bends driven round.
// - One-way zones drop every edge that runs against the zone's direction (> 90° off) anywhere.
// - Conflicts: roadmap_conflicts.hpp (the guarantee is stated there).
//
// Closures (closeArea / closeNodes / closeEdges / reopen) close and open nodes and edges of `graph`
// at run time; they nest (an element closed by two closures opens when both are reopened), so close
// and reopen through the Roadmap, not graph.setOpen. Each closure names the stations it cut off;
// checkRoadmap() tells the state of the whole roadmap.

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/control/cruise.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/site/site.hpp"
#include "fleet/traffic/graph.hpp"
#include "fleet/traffic/guidance.hpp"
#include "fleet/traffic/roadmap_conflicts.hpp"

namespace fleet::traffic {

/// At most 2^22 (4,194,304) lattice points: 2 km x 2 km at 1 m spacing. A larger lattice (a huge
/// site, a tiny spacing) is refused before anything is allocated for it.
inline constexpr double kMaxLatticePoints = 4194304.0;

struct RoadmapOptions {
  double spacing = 0.0;        ///< m between lattice nodes; 0: `targetSpacing` snapped to whole cells
  double targetSpacing = 0.5;  ///< m
  bool diagonals = true;       ///< 8-connected lattice (4-connected when false)
  double radius = 0.0;         ///< m; 0: the site's robot
  double cruiseSpeed = control::kAgentCruiseSpeed;  ///< m/s: the robot agent's cruise speed
  /// Free space (m) the motion gate needs ahead of a driving robot not to hold it: its stop gap
  /// to another robot in reserved traffic (control::kAgentRobotStopGap) plus 1 s of headway at the
  /// 0.05 m/s below which it counts as held.
  double stopGap = control::kAgentRobotStopGap + 0.05;
  double corridorSlack = 0.05;  ///< the gate's corridor is 2·radius + this wide, each side
  double margin = 0.1;          ///< m of tracking error of the two robots together
  /// m of free space a lattice node keeps around the robot's disc: a robot stops a few
  /// centimetres off its node, and one stopped that close to a shelf corner its route leads past
  /// is held there by the stop rule for good.
  double nodeClearance = 0.1;
  /// m of free space a lane edge (and an edge joining a station's, queue's or parking place's node
  /// to the lanes) keeps around the disc along its whole length: the motion gate stops for static
  /// points within `corridorSlack` of the route, so an edge closer than that to a shelf corner
  /// holds the robot at its start for good (100 robots: 0.035 m beyond the disc). This
  /// is the corridor plus 0.02 m of tracking error. A station whose nodes cannot be joined with it
  /// is joined by edges that clear the disc only (the dock's own edge always is: docking lets
  /// static points come closer).
  double edgeClearance = 0.07;
  int queueLength = 3;             ///< generated queue nodes per station (pickup, drop-off, charger)
  double followingDistance = 0.0;  ///< m between generated queue nodes; 0: the `ahead` separation
  /// true: the lattice keeps its nodes and edges clear of robots parked at the parking places, so
  /// a parked robot excludes no lane (buildRoadmap falls back to false, with a warning, on a site
  /// that leaves no room for it); false: the lattice as the map allows.
  bool parkingClear = true;
  /// Flow guidance (guidance.hpp): driving against the flow of the trips between the site's
  /// pickups and drop-offs costs routes 1 + this times the edge's duration; 0: none. 0.5 since
  /// 2026-12-05: with heading tables it gains on the small warehouse and the site for 300 and
  /// loses nothing beyond the seeds' spread on the site for 100 (docs/algorithms.md, "Traffic:
  /// flow guidance").
  double guidance = 0.5;
};

enum class NodeKind : std::uint8_t { Lane, Station, Approach, Queue, Parking, Charger, Exit };
const char* toString(NodeKind k);

/// A station's nodes. `dock` is kNoNode when the robot's disc does not fit at the station.
struct StationNodes {
  std::string name;
  site::StationKind kind = site::StationKind::Pickup;
  NodeId dock = kNoNode;
  NodeId approach = kNoNode;    ///< kNoNode: approached along a row (the dock is joined to the lattice)
  std::vector<NodeId> queue;    ///< nearest to the station first
  NodeId exit = kNoNode;        ///< the way out (dock → exit one way); kNoNode: left by the way in
  bool queueGenerated = false;  ///< true: generated; false: the site's queue points (or none)
};

struct RoadmapProblem {
  enum class Severity { Error, Warning };
  Severity severity = Severity::Error;
  std::string station;  ///< the station it is about, empty for lattice problems
  Vec2 at;              ///< where
  std::string what;     ///< names and positions, ready to print
};

/// What a closure covers (elements already closed by another closure included).
struct Closure {
  std::vector<NodeId> nodes;
  std::vector<std::pair<NodeId, NodeId>> edges;  ///< directed a→b
  std::vector<std::string> cutOff;               ///< stations connected before the closure and not after it
};

class Roadmap;
namespace detail {
/// buildRoadmap without its fall-back (RoadmapOptions::parkingClear as given).
Roadmap buildRoadmapOnce(const site::Site& site, const RoadmapOptions& options);
}  // namespace detail

class Roadmap {
 public:
  Graph graph;
  GuidanceStats guidance;              ///< what the flow guidance did (RoadmapOptions::guidance)
  std::vector<NodeKind> kinds;         ///< per node
  std::vector<StationNodes> stations;  ///< in the site's order
  RoadmapOptions options;              ///< as used: spacing, radius and following distance resolved
  Separation separation;
  Vec2 latticeOrigin;                    ///< position of lattice point (0, 0)
  std::size_t droppedLatticeNodes = 0;   ///< in pockets no station reaches
  std::size_t oneWayDropped = 0;         ///< directed edges left out by one-way zones
  std::vector<RoadmapProblem> problems;  ///< at build time: placement problems plus checkRoadmap()

  [[nodiscard]] NodeKind kind(NodeId v) const { return kinds[static_cast<std::size_t>(v)]; }
  [[nodiscard]] const StationNodes* station(const std::string& name) const;
  /// The node nearest to `p` (open ones only by default), kNoNode when there is none.
  [[nodiscard]] NodeId nearest(Vec2 p, bool openOnly = true) const;
  /// Turning time at `at` between prev→at and at→next beyond what at→next's duration includes.
  [[nodiscard]] double extraTurn(NodeId prev, NodeId at, NodeId next) const;
  /// The whole time the bend prev→at→(at's out-edge `out`) costs, as the agent takes it
  /// (fleet/core/bends.hpp): a corner (sharper than bends::kDrivenRound, or than bends::kTight
  /// where the disc has little room, or onto or off a dock) turned on the spot, turnTime(angle);
  /// a bend driven round, what turning by the angle takes beyond driving the two half edges at
  /// cruise (0 for most).
  [[nodiscard]] double bendTime(NodeId prev, NodeId at, std::size_t out) const;
  /// An edge's duration without the turning folded into it.
  [[nodiscard]] double baseDuration(NodeId from, NodeId to) const;
  /// Time to turn on the spot by `angle` rad with the site robot's limits.
  [[nodiscard]] double turnTime(double angle) const;
  [[nodiscard]] std::size_t edgeCount() const;  ///< directed edges
  [[nodiscard]] std::size_t queueNodeCount() const;

  /// Closes every node the robot's disc would overlap `polygon` at, and every edge whose sweep
  /// would; `cutOff` names the stations that it disconnects.
  Closure closeArea(const std::vector<Vec2>& polygon);
  /// Closes the given nodes (and so every edge at them).
  Closure closeNodes(const std::vector<NodeId>& nodes);
  /// Closes the given directed edges (a lane one way: give both directions to close it both ways).
  Closure closeEdges(const std::vector<std::pair<NodeId, NodeId>>& edges);
  /// Undoes a closure (once); elements another closure still covers stay closed.
  void reopen(const Closure& c);

 private:
  friend Roadmap detail::buildRoadmapOnce(const site::Site&, const RoadmapOptions&);
  Closure close(std::vector<NodeId> nodes, std::vector<std::pair<NodeId, NodeId>> edges);
  double turnRate_ = 1.5;   ///< rad/s
  double turnAccel_ = 3.0;  ///< rad/s²
  // Nearest-node lookup: node ids bucketed on a square grid.
  Vec2 bucketOrigin_;
  double bucketSize_ = 1.0;
  int bucketW_ = 0;
  int bucketH_ = 0;
  std::vector<std::vector<NodeId>> buckets_;
  std::vector<std::uint16_t> nodeClosures_;               ///< closures covering each node
  std::vector<std::vector<std::uint16_t>> edgeClosures_;  ///< per node, per out-edge
  std::vector<std::vector<double>> turnIncluded_;         ///< per node, per out-edge: s of turning
  std::vector<std::vector<double>> baseDuration_;         ///< per node, per out-edge: s of driving
  std::vector<std::uint8_t> tightBend_;                   ///< per node: the disc has little room
};

/// Builds the roadmap of `site` (its map with no-go zones blocked, its stations and zones). What
/// The site does not allow (a station the disc does not fit at, one that cannot be joined or is
/// cut off) is in `problems`; options out of range throw std::invalid_argument, a lattice of more
/// than kMaxLatticePoints throws ConfigError (the site is too large for the spacing).
Roadmap buildRoadmap(const site::Site& site, const RoadmapOptions& options = {});

/// Connectivity over the open graph: stations (docks) outside the strongly connected component
/// that holds most of them — cannot be reached from the parking places and the other stations, or
/// cannot get back (errors) — and lattice nodes outside it: dead ends one-way zones or closures
/// make (warnings, one per group).
std::vector<RoadmapProblem> checkRoadmap(const Roadmap& r);

/// Stations whose full line cuts the site: with robots standing on every node of a station's queue,
/// another station connected before can no longer be reached from the rest or cannot get back
/// (errors naming `stations[i].queue`; a parking place cut off is a warning: it traps a resting
/// robot but stops no station; queue_check.cpp). Done once when the roadmap is built.
std::vector<RoadmapProblem> checkQueues(const Roadmap& r);

/// Names of the stations whose dock is in that main component.
std::vector<std::string> connectedStations(const Roadmap& r);

/// What is wrong with run-time closure `id` of `nodes` and directed `lanes` on `r`: a node that is
/// not on the roadmap or a lane that is not one of its edges (the first found, named), or nullopt.
/// Checked before a closure changes anything: it is applied whole or not at all.
std::optional<std::string> closureProblem(const Roadmap& r, const std::string& id,
                                          const std::vector<NodeId>& nodes,
                                          const std::vector<std::pair<NodeId, NodeId>>& lanes);

}  // namespace fleet::traffic
