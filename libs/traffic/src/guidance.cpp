#include "fleet/traffic/guidance.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <functional>
#include <limits>
#include <map>
#include <numbers>
#include <queue>
#include <stdexcept>

namespace fleet::traffic {

namespace {

constexpr int kBins = 8;  // directions of travel, 45° each (the lattice's eight)
using Bins = std::array<double, kBins>;

int binOf(Vec2 d) {
  const double a = std::atan2(d.y, d.x);
  const int k = static_cast<int>(std::lround(a / (std::numbers::pi / 4.0)));
  return ((k % kBins) + kBins) % kBins;
}

// Share of the flow through a node heading against bin k (more than 90° off: the three bins
// opposite) among the flow heading with or against it (k and its two neighbours): 0 when everyone
// goes the same way, 1 when everyone else comes the other way. Crossing flow is left out.
double against(const Bins& at, std::size_t k) {
  const auto bin = [&](std::size_t j) { return at[(k + j) % kBins]; };
  // Flows taken out again (re-routing) can leave rounding residue either side of 0.
  const double opp = std::max(bin(3) + bin(4) + bin(5), 0.0);
  const double same = std::max(bin(7) + bin(0) + bin(1), 0.0);
  return opp + same > 1e-12 ? opp / (opp + same) : 0.0;
}

// Cheapest ways over open edges under a cost per edge.
struct Router {
  const Graph& g;
  std::vector<std::vector<std::pair<NodeId, const Edge*>>> in;  // who drives into v, by which edge

  explicit Router(const Graph& graph) : g(graph), in(graph.size()) {
    for (std::size_t a = 0; a < g.size(); ++a) {
      for (const Edge& e : g.edges(static_cast<NodeId>(a))) {
        if (g.passable(static_cast<NodeId>(a), e))
          in[static_cast<std::size_t>(e.to)].emplace_back(static_cast<NodeId>(a), &e);
      }
    }
  }

  // Cost of every node's cheapest way to `goal`.
  template <class Cost>
  std::vector<double> to(NodeId goal, const Cost& cost) const {
    std::vector<double> dist(g.size(), std::numeric_limits<double>::infinity());
    using Item = std::pair<double, NodeId>;
    std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
    dist[static_cast<std::size_t>(goal)] = 0.0;
    open.emplace(0.0, goal);
    while (!open.empty()) {
      const auto [d, v] = open.top();
      open.pop();
      if (d > dist[static_cast<std::size_t>(v)])
        continue;
      for (const auto& [u, e] : in[static_cast<std::size_t>(v)]) {
        const double du = d + cost(u, *e);
        if (du < dist[static_cast<std::size_t>(u)]) {
          dist[static_cast<std::size_t>(u)] = du;
          open.emplace(du, u);
        }
      }
    }
    return dist;
  }

  // The cheapest way from `from` along `dist` (empty when there is none), as (node, edge out).
  template <class Cost>
  std::vector<std::pair<NodeId, const Edge*>> walk(NodeId from, NodeId goal, const std::vector<double>& dist,
                                                   const Cost& cost) const {
    std::vector<std::pair<NodeId, const Edge*>> path;
    if (!std::isfinite(dist[static_cast<std::size_t>(from)]))
      return path;
    NodeId u = from;
    while (u != goal && path.size() <= g.size()) {
      const Edge* best = nullptr;
      double bestCost = std::numeric_limits<double>::infinity();
      for (const Edge& e : g.edges(u)) {
        if (!g.passable(u, e))
          continue;
        const double c = cost(u, e) + dist[static_cast<std::size_t>(e.to)];
        if (c < bestCost) {
          bestCost = c;
          best = &e;
        }
      }
      if (best == nullptr)
        break;
      path.emplace_back(u, best);
      u = best->to;
    }
    return path;
  }
};

using Route = std::vector<std::pair<NodeId, const Edge*>>;

}  // namespace

GuidanceStats guideByFlow(Graph& graph, std::span<const Trip> trips, const GuidanceOptions& options) {
  // Refused before anything is changed.
  if (!std::isfinite(options.weight) || options.weight < 0.0)
    throw std::invalid_argument("guideByFlow: the weight must be finite and >= 0");
  if (options.rounds < 1)
    throw std::invalid_argument("guideByFlow: rounds must be at least 1");
  GuidanceStats stats;
  for (std::size_t a = 0; a < graph.size(); ++a) {
    for (const Edge& e : graph.edges(static_cast<NodeId>(a)))
      graph.setEdgeGuide(static_cast<NodeId>(a), e.to, 1.0F);
  }
  if (!(options.weight > 0.0) || trips.empty())
    return stats;
  const Router router(graph);
  // Trips by their goal: one table routes them all.
  std::map<NodeId, std::vector<const Trip*>> byGoal;
  for (const Trip& t : trips) {
    if (graph.valid(t.from) && graph.valid(t.to) && t.from != t.to && std::isfinite(t.share) && t.share > 0.0)
      byGoal[t.to].push_back(&t);
  }
  // Each edge's direction bin, worked out once: edge i of node a at first[a] + i.
  std::vector<std::size_t> first(graph.size() + 1, 0);
  std::vector<std::uint8_t> bins;
  for (std::size_t a = 0; a < graph.size(); ++a) {
    first[a] = bins.size();
    for (const Edge& e : graph.edges(static_cast<NodeId>(a)))
      bins.push_back(
          static_cast<std::uint8_t>(binOf(graph.position(e.to) - graph.position(static_cast<NodeId>(a)))));
  }
  first[graph.size()] = bins.size();
  const auto binAt = [&](NodeId a, const Edge& e) {
    const auto i = static_cast<std::size_t>(&e - graph.edges(a).data());
    return static_cast<std::size_t>(bins[first[static_cast<std::size_t>(a)] + i]);
  };
  // The flow per node and direction: a robot driving into v counts at v and at every node it
  // excludes there.
  std::vector<Bins> flow(graph.size(), Bins{});
  const auto add = [&](const Route& r, double share) {
    for (const auto& [a, e] : r) {
      const std::size_t k = binAt(a, *e);
      flow[static_cast<std::size_t>(e->to)][k] += share;
      for (NodeId x : graph.conflicts(e->to))
        flow[static_cast<std::size_t>(x)][k] += share;
    }
  };
  const auto guided = [&](NodeId a, const Edge& e) {
    return e.duration * (1.0 + options.weight * against(flow[static_cast<std::size_t>(e.to)], binAt(a, e)));
  };
  const auto plain = [](NodeId, const Edge& e) { return e.duration; };
  std::vector<std::vector<Route>> routes;  // per goal group, per trip
  const auto routeGroup = [&](const std::vector<const Trip*>& ts, NodeId goal, const auto& cost) {
    const auto dist = router.to(goal, cost);
    std::vector<Route> out;
    for (const Trip* t : ts)
      out.push_back(router.walk(t->from, goal, dist, cost));
    return out;
  };
  // Flow-weighted share of travel against the flow, and the travel's duration.
  const auto measure = [&](const std::vector<std::vector<Route>>& rs) {
    double opp = 0.0;
    double total = 0.0;
    std::size_t gi = 0;
    for (const auto& [goal, ts] : byGoal) {
      for (std::size_t i = 0; i < ts.size(); ++i) {
        for (const auto& [a, e] : rs[gi][i]) {
          opp += ts[i]->share * e->duration * against(flow[static_cast<std::size_t>(e->to)], binAt(a, *e));
          total += ts[i]->share * e->duration;
        }
      }
      ++gi;
    }
    return std::pair{total > 0.0 ? opp / total : 0.0, total};
  };
  const auto addAll = [&](const std::vector<std::vector<Route>>& rs, double sign) {
    std::size_t gi = 0;
    for (const auto& [goal, ts] : byGoal) {
      for (std::size_t i = 0; i < ts.size(); ++i)
        add(rs[gi][i], sign * ts[i]->share);
      ++gi;
    }
  };

  // Unguided: every trip's shortest way.
  for (const auto& [goal, ts] : byGoal)
    routes.push_back(routeGroup(ts, goal, plain));
  addAll(routes, 1.0);
  const auto [before, plainDuration] = measure(routes);
  stats.contraflowBefore = before;
  // Round by round, each goal's trips taken out of the flow and routed again against the rest
  // (the first round starts from nothing, so the groups routed first set the directions).
  std::fill(flow.begin(), flow.end(), Bins{});
  for (int round = 0; round < options.rounds; ++round) {
    std::size_t gi = 0;
    for (const auto& [goal, ts] : byGoal) {
      if (round > 0) {
        for (std::size_t i = 0; i < ts.size(); ++i)
          add(routes[gi][i], -ts[i]->share);
      }
      routes[gi] = routeGroup(ts, goal, guided);
      for (std::size_t i = 0; i < ts.size(); ++i)
        add(routes[gi][i], ts[i]->share);
      ++gi;
    }
  }
  // The guide from the whole flow.
  for (std::size_t a = 0; a < graph.size(); ++a) {
    for (const Edge& e : graph.edges(static_cast<NodeId>(a))) {
      const double share = against(flow[static_cast<std::size_t>(e.to)], binAt(static_cast<NodeId>(a), e));
      graph.setEdgeGuide(static_cast<NodeId>(a), e.to, static_cast<float>(1.0 + options.weight * share));
    }
  }
  // What the planner will route on it.
  addAll(routes, -1.0);
  std::size_t gi = 0;
  for (const auto& [goal, ts] : byGoal)
    routes[gi++] = routeGroup(ts, goal, [](NodeId, const Edge& e) { return e.cost(); });
  addAll(routes, 1.0);
  const auto [after, guidedDuration] = measure(routes);
  stats.contraflowAfter = after;
  stats.lengthRatio = plainDuration > 0.0 ? guidedDuration / plainDuration : 1.0;
  return stats;
}

}  // namespace fleet::traffic
