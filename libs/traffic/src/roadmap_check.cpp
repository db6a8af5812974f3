// Connectivity of a roadmap (strongly connected components by Tarjan's algorithm, iterative) and
// run-time closures, which change it.

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include "fleet/traffic/roadmap.hpp"
#include "graph_reach.hpp"
#include "roadmap_geometry.hpp"

namespace fleet::traffic {

namespace {

double cm(double v) {
  return std::round(v * 100.0) / 100.0;
}

std::string span(double lo, double hi) {
  std::ostringstream os;
  os << cm(lo) << ".." << cm(hi);
  return os.str();
}

// Component id per node over open nodes and passable edges; -1 for closed nodes.
std::vector<int> components(const Graph& g) {
  const auto n = static_cast<NodeId>(g.size());
  std::vector<int> comp(g.size(), -1);
  std::vector<int> index(g.size(), -1);
  std::vector<int> low(g.size(), 0);
  std::vector<std::uint8_t> onStack(g.size(), 0);
  std::vector<NodeId> stack;
  std::vector<std::pair<NodeId, std::size_t>> call;  // node, next out-edge to look at
  int counter = 0;
  int comps = 0;
  for (NodeId root = 0; root < n; ++root) {
    if (index[static_cast<std::size_t>(root)] >= 0 || !g.isOpen(root)) {
      continue;
    }
    call.emplace_back(root, 0);
    while (!call.empty()) {
      auto& [v, k] = call.back();
      const auto vi = static_cast<std::size_t>(v);
      if (k == 0 && index[vi] < 0) {
        index[vi] = low[vi] = counter++;
        stack.push_back(v);
        onStack[vi] = 1;
      }
      const auto out = g.edges(v);
      bool descended = false;
      while (k < out.size()) {
        const Edge& e = out[k++];
        if (!g.passable(v, e)) {
          continue;
        }
        const auto wi = static_cast<std::size_t>(e.to);
        if (index[wi] < 0) {
          call.emplace_back(e.to, 0);
          descended = true;
          break;
        }
        if (onStack[wi]) {
          low[vi] = std::min(low[vi], index[wi]);
        }
      }
      if (descended) {
        continue;
      }
      if (low[vi] == index[vi]) {
        NodeId w = kNoNode;
        do {
          w = stack.back();
          stack.pop_back();
          onStack[static_cast<std::size_t>(w)] = 0;
          comp[static_cast<std::size_t>(w)] = comps;
        } while (w != v);
        ++comps;
      }
      const NodeId done = v;
      call.pop_back();
      if (!call.empty()) {
        const auto pi = static_cast<std::size_t>(call.back().first);
        low[pi] = std::min(low[pi], low[static_cast<std::size_t>(done)]);
      }
    }
  }
  return comp;
}

// The component holding most open docks (the larger on a tie; the largest without stations).
int mainComponent(const Roadmap& r, const std::vector<int>& comp) {
  int count = 0;
  for (const int c : comp) {
    count = std::max(count, c + 1);
  }
  std::vector<std::size_t> docks(static_cast<std::size_t>(count), 0);
  std::vector<std::size_t> size(static_cast<std::size_t>(count), 0);
  for (const int c : comp) {
    if (c >= 0) {
      ++size[static_cast<std::size_t>(c)];
    }
  }
  for (const auto& s : r.stations) {
    if (s.dock != kNoNode && comp[static_cast<std::size_t>(s.dock)] >= 0) {
      ++docks[static_cast<std::size_t>(comp[static_cast<std::size_t>(s.dock)])];
    }
  }
  int best = -1;
  for (int c = 0; c < count; ++c) {
    const auto ci = static_cast<std::size_t>(c);
    if (best < 0 || docks[ci] > docks[static_cast<std::size_t>(best)] ||
        (docks[ci] == docks[static_cast<std::size_t>(best)] &&
         size[ci] > size[static_cast<std::size_t>(best)])) {
      best = c;
    }
  }
  return best;
}

}  // namespace

std::vector<RoadmapProblem> checkRoadmap(const Roadmap& r) {
  std::vector<RoadmapProblem> out;
  const Graph& g = r.graph;
  if (g.size() == 0) {
    return out;
  }
  const auto comp = components(g);
  const int main = mainComponent(r, comp);
  std::vector<NodeId> mainNodes;
  for (std::size_t v = 0; v < g.size(); ++v) {
    if (comp[v] == main)
      mainNodes.push_back(static_cast<NodeId>(v));
  }
  const GraphReach reach(g);
  const auto from = reach.from(mainNodes, true);
  const auto to = reach.from(mainNodes, false);
  std::size_t connected = 0;
  for (const auto& s : r.stations) {
    connected += s.dock != kNoNode && comp[static_cast<std::size_t>(s.dock)] == main ? 1 : 0;
  }
  const std::string others = " (" + std::to_string(connected) + " of " + std::to_string(r.stations.size()) +
                             " stations are connected to each other)";
  for (const auto& s : r.stations) {
    if (s.dock == kNoNode) {
      continue;  // reported where it was placed
    }
    const auto d = static_cast<std::size_t>(s.dock);
    const Vec2 p = g.position(s.dock);
    const std::string who = "station '" + s.name + "' (dock at " + detail::pointText(p) + ")";
    if (!g.isOpen(s.dock)) {
      out.push_back({RoadmapProblem::Severity::Error, s.name, p, who + " is closed"});
    } else if (comp[d] != main) {
      const std::string why = from[d] && !to[d]   ? " can be reached, but a robot there cannot get back"
                              : !from[d] && to[d] ? " cannot be reached (a robot there could leave it)"
                                                  : " is cut off: no way to it or from it";
      out.push_back({RoadmapProblem::Severity::Error, s.name, p,
                     who + why + " from the parking places and the other stations" + others});
    }
  }
  // Lane nodes outside the main component, one warning per group joined by edges either way.
  auto outside = [&](NodeId v) {
    const auto i = static_cast<std::size_t>(v);
    return comp[i] >= 0 && comp[i] != main && r.kind(v) == NodeKind::Lane;
  };
  std::vector<NodeId> parent(g.size());
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    parent[static_cast<std::size_t>(v)] = v;
  }
  auto find = [&](NodeId x) {
    while (parent[static_cast<std::size_t>(x)] != x) {
      parent[static_cast<std::size_t>(x)] =
          parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
      x = parent[static_cast<std::size_t>(x)];
    }
    return x;
  };
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    for (const auto& e : g.edges(v)) {
      if (g.passable(v, e) && outside(v) && outside(e.to)) {
        parent[static_cast<std::size_t>(find(v))] = find(e.to);
      }
    }
  }
  // (group root, node), sorted: one run per group. (A vector of vectors here trips GCC 12's
  // -Wfree-nonheap-object false positive in Release builds.)
  std::vector<std::pair<NodeId, NodeId>> byGroup;
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    if (outside(v)) {
      byGroup.emplace_back(find(v), v);
    }
  }
  std::sort(byGroup.begin(), byGroup.end());
  for (std::size_t first = 0; first < byGroup.size();) {
    std::size_t last = first;
    while (last < byGroup.size() && byGroup[last].first == byGroup[first].first) {
      ++last;
    }
    const NodeId v0 = byGroup[first].second;
    std::vector<NodeId> members;
    for (std::size_t i = first; i < last; ++i) {
      members.push_back(byGroup[i].second);
    }
    first = last;
    Vec2 sum;
    Vec2 lo = g.position(v0);
    Vec2 hi = lo;
    bool canEnter = false;
    bool canLeave = false;
    for (const NodeId v : members) {
      const Vec2 p = g.position(v);
      sum += p;
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
      canEnter = canEnter || from[static_cast<std::size_t>(v)];
      canLeave = canLeave || to[static_cast<std::size_t>(v)];
    }
    const Vec2 c = sum / static_cast<double>(members.size());
    const std::string how = canEnter && !canLeave   ? "robots can drive in but not back out (a dead end)"
                            : !canEnter && canLeave ? "robots can leave them but never get there"
                                                    : "no way in or out";
    out.push_back({RoadmapProblem::Severity::Warning, "", c,
                   std::to_string(members.size()) + " lane node" + (members.size() == 1 ? "" : "s") +
                       " around " + detail::pointText(c) + " (x " + span(lo.x, hi.x) + ", y " +
                       span(lo.y, hi.y) + ") are outside the component that holds the stations: " + how});
  }
  return out;
}

std::vector<std::string> connectedStations(const Roadmap& r) {
  std::vector<std::string> out;
  if (r.graph.size() == 0) {
    return out;
  }
  const auto comp = components(r.graph);
  const int main = mainComponent(r, comp);
  for (const auto& s : r.stations) {
    if (s.dock != kNoNode && comp[static_cast<std::size_t>(s.dock)] == main) {
      out.push_back(s.name);
    }
  }
  return out;
}

Closure Roadmap::close(std::vector<NodeId> nodes, std::vector<std::pair<NodeId, NodeId>> edges) {
  const auto before = connectedStations(*this);
  Closure c;
  for (const NodeId v : nodes) {
    if (!graph.valid(v)) {
      continue;
    }
    if (nodeClosures_[static_cast<std::size_t>(v)]++ == 0) {
      graph.setOpen(v, false);
    }
    c.nodes.push_back(v);
  }
  for (const auto& [a, b] : edges) {
    if (!graph.valid(a)) {
      continue;
    }
    const auto out = graph.edges(a);
    for (std::size_t k = 0; k < out.size(); ++k) {
      if (out[k].to == b) {
        if (edgeClosures_[static_cast<std::size_t>(a)][k]++ == 0) {
          graph.setEdgeOpen(a, b, false);
        }
        c.edges.emplace_back(a, b);
      }
    }
  }
  const auto after = connectedStations(*this);
  const std::set<std::string> still(after.begin(), after.end());
  for (const auto& s : before) {
    if (!still.contains(s)) {
      c.cutOff.push_back(s);
    }
  }
  return c;
}

std::optional<std::string> closureProblem(const Roadmap& r, const std::string& id,
                                          const std::vector<NodeId>& nodes,
                                          const std::vector<std::pair<NodeId, NodeId>>& lanes) {
  const auto& g = r.graph;
  for (const auto v : nodes) {
    if (!g.valid(v)) {
      return "closure \"" + id + "\": node " + std::to_string(v) + " is not on the roadmap (0.." +
             std::to_string(g.size() - 1) + ")";
    }
  }
  for (const auto& [a, b] : lanes) {
    const bool edge =
        g.valid(a) && g.valid(b) &&
        std::any_of(g.edges(a).begin(), g.edges(a).end(), [&](const Edge& x) { return x.to == b; });
    if (!edge) {
      return "closure \"" + id + "\": there is no roadmap edge " + std::to_string(a) + " -> " +
             std::to_string(b);
    }
  }
  return std::nullopt;
}

Closure Roadmap::closeNodes(const std::vector<NodeId>& nodes) {
  return close(nodes, {});
}

Closure Roadmap::closeEdges(const std::vector<std::pair<NodeId, NodeId>>& edges) {
  return close({}, edges);
}

Closure Roadmap::closeArea(const std::vector<Vec2>& polygon) {
  std::vector<NodeId> nodes;
  std::vector<std::uint8_t> closed(graph.size(), 0);
  const double r = options.radius;
  for (NodeId v = 0; v < static_cast<NodeId>(graph.size()); ++v) {
    const Vec2 p = graph.position(v);
    if (detail::segmentPolygonDistance(p, p, polygon) < r) {
      nodes.push_back(v);
      closed[static_cast<std::size_t>(v)] = 1;
    }
  }
  // Edges between two nodes outside whose sweep still crosses the area.
  std::vector<std::pair<NodeId, NodeId>> edges;
  for (NodeId v = 0; v < static_cast<NodeId>(graph.size()); ++v) {
    for (const auto& e : graph.edges(v)) {
      if (!closed[static_cast<std::size_t>(v)] && !closed[static_cast<std::size_t>(e.to)] &&
          detail::segmentPolygonDistance(graph.position(v), graph.position(e.to), polygon) < r) {
        edges.emplace_back(v, e.to);
      }
    }
  }
  return close(std::move(nodes), std::move(edges));
}

void Roadmap::reopen(const Closure& c) {
  for (const NodeId v : c.nodes) {
    if (!graph.valid(v)) {
      continue;
    }
    auto& n = nodeClosures_[static_cast<std::size_t>(v)];
    if (n > 0 && --n == 0) {
      graph.setOpen(v, true);
    }
  }
  for (const auto& [a, b] : c.edges) {
    if (!graph.valid(a)) {
      continue;
    }
    const auto out = graph.edges(a);
    for (std::size_t k = 0; k < out.size(); ++k) {
      auto& n = edgeClosures_[static_cast<std::size_t>(a)][k];
      if (out[k].to == b && n > 0 && --n == 0) {
        graph.setEdgeOpen(a, b, true);
      }
    }
  }
}

}  // namespace fleet::traffic
