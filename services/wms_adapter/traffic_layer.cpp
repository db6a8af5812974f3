#include "traffic_layer.hpp"

#include <cmath>
#include <unordered_map>
#include <unordered_set>

namespace fleet::wms {
namespace {

using nlohmann::json;

double cm(double v) {
  return std::round(v * 100.0) / 100.0;
}

RoadmapKind kindOf(const msg::Roadmap& m, std::int32_t v) {
  return static_cast<RoadmapKind>(m.kinds[static_cast<std::size_t>(v)]);
}

std::uint64_t pairKey(std::int32_t a, std::int32_t b) {
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

/// The site's station at (x, y), or "node <dock>".
std::string stationAt(const json& stations, double x, double y, std::int32_t dock) {
  std::string best = "node " + std::to_string(dock);
  double bestD = 0.25;
  if (stations.is_array()) {
    for (const auto& s : stations) {
      if (!s.is_object() || !s.contains("x") || !s.contains("y") || !s["name"].is_string()) {
        continue;
      }
      const double d = std::hypot(s["x"].get<double>() - x, s["y"].get<double>() - y);
      if (d <= bestD) {
        bestD = d;
        best = s["name"].get<std::string>();
      }
    }
  }
  return best;
}

json flatPositions(const std::vector<msg::RouteNode>& nodes) {
  json xy = json::array();
  for (const auto& n : nodes) {
    xy.push_back(cm(n.x));
    xy.push_back(cm(n.y));
  }
  return xy;
}

json ids(const std::vector<msg::RouteNode>& nodes) {
  json out = json::array();
  for (const auto& n : nodes) {
    out.push_back(n.node);
  }
  return out;
}

}  // namespace

std::vector<StationQueue> stationQueues(const msg::Roadmap& m, const json& stations) {
  const auto n = static_cast<std::int32_t>(m.nodes.size());
  if (m.kinds.size() != m.nodes.size()) {
    return {};
  }
  // Into each node: the queue and approach nodes with an edge to it (a queue drives one way, to
  // the station; the approach's last leg goes to the dock).
  std::unordered_map<std::int32_t, std::vector<std::int32_t>> into;
  for (const auto& e : m.edges) {
    if (e.from < 0 || e.from >= n || e.to < 0 || e.to >= n) {
      continue;
    }
    const auto k = kindOf(m, e.from);
    if (k == RoadmapKind::Queue || k == RoadmapKind::Approach) {
      into[e.to].push_back(e.from);
    }
  }
  auto pred = [&](std::int32_t v, RoadmapKind kind, const std::unordered_set<std::int32_t>& seen) {
    const auto it = into.find(v);
    if (it != into.end()) {
      for (const auto u : it->second) {
        if (kindOf(m, u) == kind && !seen.contains(u)) {
          return u;
        }
      }
    }
    return std::int32_t{-1};
  };
  std::vector<StationQueue> out;
  for (std::int32_t dock = 0; dock < n; ++dock) {
    const auto k = kindOf(m, dock);
    if (k != RoadmapKind::Station && k != RoadmapKind::Parking && k != RoadmapKind::Charger) {
      continue;
    }
    std::unordered_set<std::int32_t> seen;
    const std::int32_t approach = pred(dock, RoadmapKind::Approach, seen);
    StationQueue q;
    q.dock = dock;
    for (std::int32_t v = pred(approach >= 0 ? approach : dock, RoadmapKind::Queue, seen); v >= 0;
         v = pred(v, RoadmapKind::Queue, seen)) {
      seen.insert(v);
      q.nodes.push_back(v);
    }
    if (!q.nodes.empty()) {
      const auto& d = m.nodes[static_cast<std::size_t>(dock)];
      q.station = stationAt(stations, d.x, d.y, dock);
      out.push_back(std::move(q));
    }
  }
  return out;
}

json roadmapJson(const msg::Roadmap& m, const std::vector<StationQueue>& queues) {
  if (m.nodes.size() > kMaxDrawnNodes || m.edges.size() > 2 * kMaxDrawnEdges ||
      m.kinds.size() != m.nodes.size() || m.open.size() != m.nodes.size()) {
    return nullptr;
  }
  std::vector<double> xy;
  xy.reserve(2 * m.nodes.size());
  json closed = json::array();
  for (std::size_t i = 0; i < m.nodes.size(); ++i) {
    xy.push_back(cm(m.nodes[i].x));
    xy.push_back(cm(m.nodes[i].y));
    if (!m.open[i]) {
      closed.push_back(i);
    }
  }
  // A lane driven both ways is one line on the page; a one-way lane keeps its direction.
  std::unordered_set<std::uint64_t> open;
  for (const auto& e : m.edges) {
    if (e.open) {
      open.insert(pairKey(e.from, e.to));
    }
  }
  std::vector<std::int32_t> both;
  std::vector<std::int32_t> oneWay;
  std::vector<std::int32_t> closedEdges;
  for (const auto& e : m.edges) {
    if (!e.open) {
      closedEdges.insert(closedEdges.end(), {e.from, e.to});
    } else if (!open.contains(pairKey(e.to, e.from))) {
      oneWay.insert(oneWay.end(), {e.from, e.to});
    } else if (e.from < e.to) {
      both.insert(both.end(), {e.from, e.to});
    }
  }
  json qs = json::array();
  for (const auto& q : queues) {
    qs.push_back({{"station", q.station}, {"dock", q.dock}, {"nodes", q.nodes}});
  }
  return {{"epoch", m.epoch}, {"revision", m.revision}, {"stamp_ns", m.stamp_ns},
          {"nodes", xy},      {"kinds", m.kinds},       {"closed", closed},
          {"lanes", both},    {"one_way", oneWay},      {"closed_lanes", closedEdges},
          {"queues", qs}};
}

json releaseJson(const msg::TrafficRelease& r) {
  return {{"robot", r.robot_id},
          {"epoch", r.epoch},
          {"seq", r.seq},
          {"base", ids(r.base)},
          {"horizon", ids(r.horizon)},
          {"base_xy", flatPositions(r.base)},
          {"horizon_xy", flatPositions(r.horizon)},
          {"ends_at_goal", r.ends_at_goal},
          {"stamp_ns", r.stamp_ns}};
}

json queuesJson(const std::vector<StationQueue>& queues, const msg::Roadmap& m,
                const std::vector<msg::RobotState>& robots) {
  // The robot standing on a node, if any (the nearest within the tolerance).
  auto on = [&](std::int32_t v) -> std::string {
    if (v < 0 || static_cast<std::size_t>(v) >= m.nodes.size()) {
      return {};
    }
    const auto& p = m.nodes[static_cast<std::size_t>(v)];
    std::string best;
    double bestD = kQueueTolerance;
    for (const auto& r : robots) {
      const double d = std::hypot(r.pose.x - p.x, r.pose.y - p.y);
      if (d <= bestD) {
        bestD = d;
        best = r.robot_id;
      }
    }
    return best;
  };
  json out = json::array();
  for (const auto& q : queues) {
    json waiting = json::array();
    for (const auto v : q.nodes) {
      if (auto who = on(v); !who.empty()) {
        waiting.push_back(who);
      }
    }
    out.push_back(
        {{"station", q.station}, {"at", on(q.dock)}, {"waiting", waiting}, {"length", q.nodes.size()}});
  }
  return out;
}

}  // namespace fleet::wms
