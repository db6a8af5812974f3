#include "fleet/traffic/roadmap_travel.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <span>
#include <utility>

#include "fleet/traffic/distance_table.hpp"
#include "fleet/traffic/station_cycle.hpp"

namespace fleet::traffic {

namespace {

// Seconds from every node to `goal` along the table's cheapest way: `cost` is the goal's table in
// route costs (durations times the flow guidance), each node's way goes on by the edge whose cost
// plus the next node's is least, and the seconds are the durations along it. The planner follows
// that way as far as other robots let it (PIBT takes the neighbour nearest in the table, which is
// the same way wherever the edges round a node cost alike). Nodes are taken cheapest first, so
// each one's successor is known before it.
std::vector<float> routeSeconds(const Graph& g, std::span<const float> cost, NodeId goal) {
  std::vector<float> sec(cost.size(), DistanceTable::kUnreachable);
  std::vector<NodeId> order(cost.size());
  std::iota(order.begin(), order.end(), 0);
  std::stable_sort(order.begin(), order.end(), [&](NodeId a, NodeId b) {
    return cost[static_cast<std::size_t>(a)] < cost[static_cast<std::size_t>(b)];
  });
  sec[static_cast<std::size_t>(goal)] = 0.0F;
  for (NodeId v : order) {
    const float cv = cost[static_cast<std::size_t>(v)];
    if (v == goal || !std::isfinite(cv))
      continue;
    const Edge* best = nullptr;
    double bestCost = std::numeric_limits<double>::infinity();
    for (const Edge& e : g.edges(v)) {
      const double c = e.cost() + static_cast<double>(cost[static_cast<std::size_t>(e.to)]);
      if (g.passable(v, e) && c < bestCost && std::isfinite(sec[static_cast<std::size_t>(e.to)])) {
        bestCost = c;
        best = &e;
      }
    }
    if (best != nullptr)
      sec[static_cast<std::size_t>(v)] =
          static_cast<float>(best->duration) + sec[static_cast<std::size_t>(best->to)];
  }
  return sec;
}

}  // namespace

RoadmapTravel::RoadmapTravel(std::shared_ptr<const Roadmap> roadmap) : roadmap_(std::move(roadmap)) {
  DistanceTable tables(roadmap_->graph);
  for (const auto& st : roadmap_->stations) {
    StationTable t;
    t.dock = st.dock;
    if (st.dock != kNoNode) {
      t.line = 1 + st.queue.size();
      t.move = traffic::dockMoveSeconds(dockGeometry(roadmap_->graph, st), roadmap_->options.radius,
                                        roadmap_->options.cruiseSpeed);
      const auto d = tables.to(st.dock);
      if (roadmap_->options.guidance > 0.0)
        t.toDock = routeSeconds(roadmap_->graph, d, st.dock);  // the guided way's seconds
      else
        t.toDock.assign(d.begin(), d.end());
    }
    stations_.emplace(st.name, std::move(t));
  }
}

const RoadmapTravel::StationTable* RoadmapTravel::find(const std::string& name) const {
  const auto it = stations_.find(name);
  return it == stations_.end() || it->second.dock == kNoNode ? nullptr : &it->second;
}

std::optional<double> RoadmapTravel::toStation(Vec2 from, const std::string& name) const {
  const StationTable* t = find(name);
  if (t == nullptr) {
    return std::nullopt;
  }
  const NodeId start = roadmap_->nearest(from);
  if (start == kNoNode) {
    return std::numeric_limits<double>::infinity();
  }
  const double leg = distance(from, roadmap_->graph.position(start)) / roadmap_->options.cruiseSpeed;
  return leg + static_cast<double>(t->toDock[static_cast<std::size_t>(start)]);
}

std::optional<double> RoadmapTravel::fromNode(NodeId from, const std::string& name) const {
  const StationTable* t = find(name);
  if (t == nullptr) {
    return std::nullopt;
  }
  if (from < 0 || static_cast<std::size_t>(from) >= t->toDock.size()) {
    return std::numeric_limits<double>::infinity();
  }
  return static_cast<double>(t->toDock[static_cast<std::size_t>(from)]);
}

std::optional<double> RoadmapTravel::between(const std::string& a, const std::string& b) const {
  const StationTable* from = find(a);
  const StationTable* to = find(b);
  if (from == nullptr || to == nullptr) {
    return std::nullopt;
  }
  return static_cast<double>(to->toDock[static_cast<std::size_t>(from->dock)]);
}

double RoadmapTravel::dockMoveSeconds(const std::string& name) const {
  const StationTable* t = find(name);
  return t == nullptr ? 0.0 : t->move;
}

std::size_t RoadmapTravel::lineCapacity(const std::string& name) const {
  const StationTable* t = find(name);
  return t == nullptr ? 0 : t->line;
}

}  // namespace fleet::traffic
