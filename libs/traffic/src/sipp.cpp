#include "fleet/traffic/sipp.hpp"

#include <algorithm>
#include <queue>

namespace fleet::traffic {

namespace {
constexpr std::size_t kSippHeuristics = 512;

struct SippOpen {
  double f;
  double g;
  std::int32_t state;
  bool operator<(const SippOpen& o) const {
    // std::priority_queue pops the largest: least f first, then the later arrival (deeper).
    return f != o.f ? f > o.f : g < o.g;
  }
};
}  // namespace

Sipp::Sipp(const Graph& graph, TurnTime turn, std::size_t maxExpansions)
    : graph_(graph), turn_(std::move(turn)), maxExpansions_(maxExpansions) {}

const std::vector<float>& Sipp::heuristic(NodeId goal) {
  if (auto it = heuristics_.find(goal); it != heuristics_.end())
    return it->second;
  if (reverse_.size() != graph_.size()) {
    reverse_.assign(graph_.size(), {});
    for (NodeId v = 0; static_cast<std::size_t>(v) < graph_.size(); ++v) {
      for (const Edge& e : graph_.edges(v))
        reverse_[static_cast<std::size_t>(e.to)].emplace_back(v, static_cast<float>(e.duration));
    }
  }
  if (heuristics_.size() >= kSippHeuristics)
    heuristics_.clear();
  std::vector<float> d(graph_.size(), std::numeric_limits<float>::infinity());
  using Item = std::pair<float, NodeId>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> heap;
  d[static_cast<std::size_t>(goal)] = 0.0F;
  heap.emplace(0.0F, goal);
  while (!heap.empty()) {
    const auto [dv, v] = heap.top();
    heap.pop();
    if (dv > d[static_cast<std::size_t>(v)])
      continue;
    for (const auto& [u, dur] : reverse_[static_cast<std::size_t>(v)]) {
      const Edge* e = graph_.edge(u, v);
      if (e == nullptr || !graph_.passable(u, *e))
        continue;
      // Rounded down a little: float sums must not overestimate the double-precision search's.
      const float du = (dv + dur) * (1.0F - 1e-6F);
      if (du < d[static_cast<std::size_t>(u)]) {
        d[static_cast<std::size_t>(u)] = du;
        heap.emplace(du, u);
      }
    }
  }
  return heuristics_.emplace(goal, std::move(d)).first->second;
}

double Sipp::drivingTime(NodeId v, NodeId goal) {
  if (!graph_.valid(v) || !graph_.valid(goal))
    return kForever;
  const float h = heuristic(goal)[static_cast<std::size_t>(v)];
  return h == std::numeric_limits<float>::infinity() ? kForever : static_cast<double>(h);
}

const std::vector<Interval>& Sipp::intervals(const ReservationTable& table, NodeId v, double from) {
  const auto i = static_cast<std::size_t>(v);
  if (intervalStamp_[i] != stamp_) {
    intervalStamp_[i] = stamp_;
    intervals_[i] = table.safe(v, from);
  }
  return intervals_[i];
}

std::optional<TimedPath> Sipp::plan(const ReservationTable& table, const SippQuery& q) {
  ++stats_.searches;
  const bool refuge = q.goal == kNoNode;
  if (!graph_.valid(q.start) || (!refuge && !graph_.valid(q.goal))) {
    ++stats_.failures;
    return std::nullopt;
  }
  if (intervalStamp_.size() != graph_.size()) {
    intervalStamp_.assign(graph_.size(), 0);
    intervals_.assign(graph_.size(), {});
    stamp_ = 0;
  }
  ++stamp_;
  // A refuge has no heuristic (Dijkstra in time).
  const std::vector<float>* h = refuge ? nullptr : &heuristic(q.goal);
  auto hOf = [&](NodeId v) {
    return h == nullptr ? 0.0 : static_cast<double>((*h)[static_cast<std::size_t>(v)]);
  };
  auto isGoal = [&](NodeId v) {
    return refuge ? (q.avoid == nullptr || (*q.avoid)[static_cast<std::size_t>(v)] == 0) : v == q.goal;
  };
  states_.clear();
  best_.clear();
  auto key = [](NodeId v, NodeId from, std::int32_t k) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(v)) << 40) ^
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(from + 1)) << 16) ^
           static_cast<std::uint64_t>(k);
  };
  // The start's interval: the one holding the start time.
  const auto& startIv = intervals(table, q.start, q.startTime);
  if (startIv.empty() || startIv.front().from > q.startTime || hOf(q.start) == kForever) {
    ++stats_.failures;
    return std::nullopt;
  }
  std::priority_queue<SippOpen> open;
  states_.push_back({q.start, q.cameFrom, 0, -1, q.startTime, q.startTime, startIv.front().to});
  open.push({q.startTime + hOf(q.start), q.startTime, 0});
  std::size_t expanded = 0;
  std::int32_t found = -1;
  while (!open.empty()) {
    const SippOpen top = open.top();
    open.pop();
    const State s = states_[static_cast<std::size_t>(top.state)];
    if (top.g > best_.try_emplace(key(s.node, s.from, s.interval), top.g).first->second)
      continue;  // reached earlier since
    if (isGoal(s.node) && s.intervalEnd >= q.holdUntil) {
      found = top.state;
      break;
    }
    if (++expanded > maxExpansions_)
      break;
    for (const Edge& e : graph_.edges(s.node)) {
      if (!graph_.passable(s.node, e))
        continue;
      const NodeId w = e.to;
      const double hw = hOf(w);
      if (hw == kForever)
        continue;
      const double turn = (turn_ && s.from != kNoNode) ? turn_(s.from, s.node, w) : 0.0;
      const double earliest = s.arrive + turn;
      // It stands on its node until it has arrived at the next.
      const double latest = s.intervalEnd - e.duration;
      if (earliest > latest)
        continue;
      const auto& ivs = intervals(table, w, q.startTime);
      for (std::size_t j = 0; j < ivs.size(); ++j) {
        const Interval& iw = ivs[j];
        if (iw.from > latest)
          break;
        const double depart = std::max(earliest, iw.from);
        const double arrive = depart + e.duration;
        if (depart > latest || arrive > iw.to)
          continue;
        const auto k = key(w, s.node, static_cast<std::int32_t>(j));
        auto [it, fresh] = best_.try_emplace(k, arrive);
        if (!fresh) {
          if (arrive >= it->second)
            continue;
          it->second = arrive;
        }
        states_.push_back({w, s.node, static_cast<std::int32_t>(j), top.state, arrive, depart, iw.to});
        open.push({arrive + hw, arrive, static_cast<std::int32_t>(states_.size() - 1)});
      }
    }
  }
  stats_.expanded += expanded;
  if (found < 0) {
    ++stats_.failures;
    return std::nullopt;
  }
  TimedPath path;
  for (std::int32_t i = found; i >= 0; i = states_[static_cast<std::size_t>(i)].parent) {
    const State& s = states_[static_cast<std::size_t>(i)];
    path.push_back({s.node, s.depart, s.arrive, kForever});
  }
  std::reverse(path.begin(), path.end());
  for (std::size_t i = 0; i + 1 < path.size(); ++i)
    path[i].leave = path[i + 1].enter;
  path.back().leave = q.holdUntil;
  return path;
}

}  // namespace fleet::traffic
