// A station's queue must lie off the through ways (docs/algorithms.md, "Traffic: stations as
// servers"): robots waiting in line stand there for as long as the station is busy, so a queue that
// the rest of the site's traffic must pass through cuts the site whenever the line is full.
//
// For each station with a queue, every queue node is taken as occupied — the node and every node a
// robot standing there excludes, the station's own approach, dock and exit left open (the line
// leads there) — and the other stations' docks are checked to stay reachable from each other both
// ways. A station the full line cuts off is an error naming the queue by its key path in site.json.

#include <sstream>
#include <string>
#include <vector>

#include "fleet/traffic/roadmap.hpp"
#include "graph_reach.hpp"
#include "roadmap_geometry.hpp"

namespace fleet::traffic {

std::vector<RoadmapProblem> checkQueues(const Roadmap& r) {
  std::vector<RoadmapProblem> out;
  const Graph& g = r.graph;
  const GraphReach reach(g);
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
    // The other connected stations must still reach each other both ways. Each is checked against
    // a reference station: the first whose dock the line leaves free, or, when that one is what the
    // line traps (it reaches or is reached by few), the next — up to three — keeping the reference
    // from which most stations remain connected, so the stations named are the ones cut off.
    std::vector<std::uint8_t> from, to;
    std::size_t best = 0, tried = 0, others = 0;
    for (const auto& o : r.stations)
      others += &o != &s && o.dock != kNoNode && isConnected(o.name) ? 1 : 0;
    for (const auto& o : r.stations) {
      if (tried == 3 || best == others)
        break;
      if (&o == &s || o.dock == kNoNode || !isConnected(o.name) || blocked[static_cast<std::size_t>(o.dock)])
        continue;
      ++tried;
      const NodeId seed[] = {o.dock};
      auto f = reach.from(seed, true, blocked);
      auto t = reach.from(seed, false, blocked);
      std::size_t kept = 0;
      for (const auto& x : r.stations) {
        if (&x != &s && x.dock != kNoNode && isConnected(x.name))
          kept += f[static_cast<std::size_t>(x.dock)] && t[static_cast<std::size_t>(x.dock)] ? 1 : 0;
      }
      if (kept > best || from.empty()) {
        best = kept;
        from = std::move(f);
        to = std::move(t);
      }
    }
    if (from.empty())
      continue;
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
                         detail::pointText(g.position(s.queue.front())) + " to " +
                         detail::pointText(g.position(s.queue.back())) + ") cut off " +
                         std::to_string(count[k]) + what + cut[k] +
                         "; a queue must lie off the ways other robots need"});
    }
  }
  return out;
}

}  // namespace fleet::traffic
