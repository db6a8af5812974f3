// A station's queue must lie off the through ways (docs/algorithms.md, "Traffic: stations as
// servers"): robots waiting in line stand there for as long as the station is busy, so a queue that
// the rest of the site's traffic must pass through cuts the site whenever the line is full.
//
// For each station with a queue, every queue node is taken as occupied — the node and every node a
// robot standing there excludes, the station's own approach, dock and exit left open (the line
// leads there) — and the other stations' docks are checked to stay reachable from each other both
// ways. A station the full line cuts off is an error naming the queue by its key path in site.json.

#include <deque>
#include <sstream>
#include <string>
#include <vector>

#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {
namespace {

std::string pointText(Vec2 p) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(2);
  os << "(" << p.x << ", " << p.y << ")";
  return os.str();
}

/// Nodes reachable from `from` (forward) or reaching it (backward), avoiding `blocked`.
std::vector<std::uint8_t> reachable(const Graph& g, const std::vector<std::vector<NodeId>>& in, NodeId from,
                                    const std::vector<std::uint8_t>& blocked, bool forward) {
  std::vector<std::uint8_t> seen(g.size(), 0);
  std::deque<NodeId> q{from};
  seen[static_cast<std::size_t>(from)] = 1;
  const auto visit = [&](NodeId w) {
    const auto i = static_cast<std::size_t>(w);
    if (!seen[i] && !blocked[i] && g.isOpen(w)) {
      seen[i] = 1;
      q.push_back(w);
    }
  };
  while (!q.empty()) {
    const NodeId v = q.front();
    q.pop_front();
    if (forward) {
      for (const auto& e : g.edges(v)) {
        if (g.passable(v, e))
          visit(e.to);
      }
    } else {
      for (const NodeId w : in[static_cast<std::size_t>(v)])
        visit(w);
    }
  }
  return seen;
}

}  // namespace

std::vector<RoadmapProblem> checkQueues(const Roadmap& r) {
  std::vector<RoadmapProblem> out;
  const Graph& g = r.graph;
  std::vector<std::vector<NodeId>> in(g.size());
  for (NodeId v = 0; static_cast<std::size_t>(v) < g.size(); ++v) {
    for (const auto& e : g.edges(v)) {
      if (g.passable(v, e))
        in[static_cast<std::size_t>(e.to)].push_back(v);
    }
  }
  // The stations connected to each other with every line empty: the ones a full line may not cut.
  const auto connected = connectedStations(r);
  const auto isConnected = [&](const std::string& name) {
    for (const auto& c : connected) {
      if (c == name)
        return true;
    }
    return false;
  };
  std::vector<std::uint8_t> blocked(g.size(), 0);
  for (std::size_t i = 0; i < r.stations.size(); ++i) {
    const auto& s = r.stations[i];
    if (s.queue.empty() || s.dock == kNoNode || !isConnected(s.name))
      continue;
    std::fill(blocked.begin(), blocked.end(), 0);
    for (const NodeId q : s.queue) {
      blocked[static_cast<std::size_t>(q)] = 1;
      for (const NodeId w : g.conflicts(q))
        blocked[static_cast<std::size_t>(w)] = 1;
    }
    for (const NodeId own : {s.approach, s.dock, s.exit}) {
      if (own != kNoNode)
        blocked[static_cast<std::size_t>(own)] = 0;
    }
    // One other connected station whose dock the line leaves free is the reference; every other
    // connected station must reach it and be reached from it.
    NodeId ref = kNoNode;
    for (const auto& o : r.stations) {
      if (&o != &s && o.dock != kNoNode && isConnected(o.name) &&
          !blocked[static_cast<std::size_t>(o.dock)]) {
        ref = o.dock;
        break;
      }
    }
    if (ref == kNoNode)
      continue;
    const auto from = reachable(g, in, ref, blocked, true);
    const auto to = reachable(g, in, ref, blocked, false);
    // Stations the full line cuts off (an error), and parking places (a warning: it traps a resting
    // robot until the line moves on, but stops no station).
    std::string cut[2];
    std::size_t count[2] = {0, 0};
    for (const auto& o : r.stations) {
      if (&o == &s || o.dock == kNoNode || !isConnected(o.name))
        continue;
      const auto d = static_cast<std::size_t>(o.dock);
      if (!from[d] || !to[d]) {
        const int k = o.kind == site::StationKind::Parking ? 1 : 0;
        cut[k] += (count[k] == 0 ? "'" : ", '") + o.name + "'";
        ++count[k];
      }
    }
    for (int k = 0; k < 2; ++k) {
      if (count[k] == 0)
        continue;
      const char* what = k == 0 ? (count[k] == 1 ? " station: " : " stations: ")
                                : (count[k] == 1 ? " parking place: " : " parking places: ");
      out.push_back({k == 0 ? RoadmapProblem::Severity::Error : RoadmapProblem::Severity::Warning, s.name,
                     g.position(s.queue.back()),
                     "stations[" + std::to_string(i) + "].queue: station '" + s.name +
                         "': robots waiting in its full line (queue from " +
                         pointText(g.position(s.queue.front())) + " to " +
                         pointText(g.position(s.queue.back())) + ") cut off " + std::to_string(count[k]) +
                         what + cut[k] + "; a queue must lie off the ways other robots need"});
    }
  }
  return out;
}

}  // namespace fleet::traffic
