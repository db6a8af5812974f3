#include "fleet/traffic/sipp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>
#include <utility>

namespace fleet::traffic {

namespace {
/// Bytes of goal heuristics kept, least recently used dropped first (one goal on the site for 300
/// robots: ~0.6 MB).
constexpr std::size_t kSippHeuristicBytes = std::size_t{256} << 20;

/// f is ordered in steps of this many s, counted from the start's f and rounded to the nearest:
/// states whose f differs by less than the sums' rounding are ties, taken deepest first (a lattice
/// has many ways of the same length; with an exact heuristic they all have the start's f, in the
/// middle of its step whatever the durations — a grid of steps fixed in time split them whenever
/// their f fell on a step's edge, e.g. 0.1 s edges from a whole second).
constexpr double kFStep = 1e-3;
/// The heap's order (std::push_heap keeps the largest on top): least f first, then the later
/// arrival (deeper).
constexpr auto kLaterFirst = [](const auto& a, const auto& b) { return a.f != b.f ? a.f > b.f : a.g < b.g; };
/// The float at or below `d` (a goal table's values never exceed the sums they stand for).
float down(double d) {
  const auto f = static_cast<float>(d);
  return static_cast<double>(f) > d ? std::nextafter(f, 0.0F) : f;
}
std::int64_t fKey(double f, double f0) {
  return static_cast<std::int64_t>(std::llround((f - f0) / kFStep));
}
}  // namespace

Sipp::Sipp(const Graph& graph, TurnTime turn, std::size_t maxExpansions)
    : graph_(graph), turn_(std::move(turn)), maxExpansions_(maxExpansions) {}

void Sipp::index() {
  if (edgeStart_.size() == graph_.size() + 1)
    return;
  if (!cost_.empty() && cost_.size() != graph_.size())
    cost_.clear();  // the graph grew: costs per node are given again for its new size
  edgeStart_.assign(graph_.size() + 1, 0);
  for (std::size_t v = 0; v < graph_.size(); ++v)
    edgeStart_[v + 1] = edgeStart_[v] + graph_.edges(static_cast<NodeId>(v)).size();
  edgeTail_.assign(edgeStart_.back(), kNoNode);
  inPos_.assign(edgeStart_.back(), 0);
  reverse_.assign(graph_.size(), {});
  for (NodeId v = 0; static_cast<std::size_t>(v) < graph_.size(); ++v) {
    const auto out = graph_.edges(v);
    for (std::size_t k = 0; k < out.size(); ++k) {
      const std::size_t e = edgeStart_[static_cast<std::size_t>(v)] + k;
      edgeTail_[e] = v;
      auto& in = reverse_[static_cast<std::size_t>(out[k].to)];
      inPos_[e] = static_cast<std::uint32_t>(in.size());
      in.push_back(static_cast<std::uint32_t>(e));
    }
  }
  turnStart_.assign(graph_.size() + 1, 0);
  for (std::size_t v = 0; v < graph_.size(); ++v)
    turnStart_[v + 1] = turnStart_[v] + reverse_[v].size() * graph_.edges(static_cast<NodeId>(v)).size();
  turns_.assign(turnStart_.back(), -1.0F);
  bestStamp_.assign(edgeTail_.size() + graph_.size(), 0);
  bestHead_.assign(edgeTail_.size() + graph_.size(), -1);
}

double Sipp::turnAt(NodeId from, std::int32_t inEdge, NodeId at, std::size_t out) {
  if (!turn_ || from == kNoNode)
    return 0.0;
  if (inEdge < 0)  // `from` is no edge's tail: measured each time
    return turn_(from, at, graph_.edges(at)[out].to);
  // Computed once per (way in, way out) at each node: the turn function measures angles.
  const std::size_t k = inPos_[static_cast<std::size_t>(inEdge)];
  float& t = turns_[turnStart_[static_cast<std::size_t>(at)] + k * graph_.edges(at).size() + out];
  if (t < 0.0F)
    t = static_cast<float>(turn_(from, at, graph_.edges(at)[out].to));
  return static_cast<double>(t);
}

bool Sipp::usable(std::uint32_t e) const {
  const NodeId u = edgeTail_[e];
  const Edge& edge = graph_.edges(u)[e - edgeStart_[static_cast<std::size_t>(u)]];
  return edge.open && graph_.isOpen(edge.to);
}

std::int64_t Sipp::edgeIndex(NodeId from, NodeId to) const {
  if (!graph_.valid(from))
    return -1;
  const auto out = graph_.edges(from);
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (out[k].to == to)
      return static_cast<std::int64_t>(edgeStart_[static_cast<std::size_t>(from)] + k);
  }
  return -1;
}

Sipp::Heuristic& Sipp::heuristic(NodeId goal) {
  ++useClock_;
  if (auto it = heuristics_.find(goal); it != heuristics_.end()) {
    it->second.used = useClock_;
    return it->second;
  }
  index();
  ++stats_.heuristics;
  // Every table's values and what is left of its search's heap, with a new one's values.
  const auto held = [&] {
    std::size_t b = sizeof(float) * (graph_.size() + edgeTail_.size());
    for (const auto& [g, table] : heuristics_) {
      b += sizeof(float) * (table.node.size() + table.edge.size()) +
           sizeof(std::pair<double, std::uint32_t>) * table.heap.capacity();
    }
    return b;
  };
  while (!heuristics_.empty() && held() > kSippHeuristicBytes) {
    NodeId oldest = kNoNode;
    std::uint64_t oldestUse = std::numeric_limits<std::uint64_t>::max();
    for (const auto& [g, table] : heuristics_) {
      if (table.used < oldestUse) {
        oldest = g;
        oldestUse = table.used;
      }
    }
    heuristics_.erase(oldest);
  }
  // Backward over the edges (the robot's heading: the edge it arrived by), turns included: the
  // exact time to the goal with nobody in the way, so a robot alone is searched along its path.
  // Every edge gets its value, open or not (a robot may have arrived by an edge closed since, or
  // stand on a closed node: it may still drive off); only usable moves are searched on from. The
  // search runs only as far as the values read need (settle()). Summed in double, each value kept
  // rounded down to a float (never above the forward search's sums; rounding at every step instead
  // compounds — 0.2 s at 300 s from the goal — and made every state nearer the start look better,
  // so the search went breadth first).
  constexpr float kInf = std::numeric_limits<float>::infinity();
  Heuristic h{std::vector<float>(graph_.size(), kInf),
              std::vector<float>(edgeTail_.size(), kInf),
              {},
              goal,
              useClock_};
  h.node[static_cast<std::size_t>(goal)] = 0.0F;
  for (const std::uint32_t e : reverse_[static_cast<std::size_t>(goal)]) {
    h.edge[e] = 0.0F;
    if (usable(e))
      h.heap.emplace_back(0.0, e);
  }
  std::make_heap(h.heap.begin(), h.heap.end(), std::greater<>());
  return heuristics_.emplace(goal, std::move(h)).first->second;
}

void Sipp::settle(Heuristic& h, const float& value) {
  // A value below every key left is final: a later candidate is at least that key, and rounds
  // down to no less than the value.
  while (!h.heap.empty() && h.heap.front().first <= static_cast<double>(value)) {
    std::pop_heap(h.heap.begin(), h.heap.end(), std::greater<>());
    const auto [hf, f] = h.heap.back();
    h.heap.pop_back();
    if (down(hf) > h.edge[f])
      continue;  // a lower value came since
    // f = v → w: from arriving at v, leaving by f costs its turn, its duration and h(f).
    const NodeId v = edgeTail_[f];
    const std::size_t k = f - edgeStart_[static_cast<std::size_t>(v)];
    const double viaF = graph_.edges(v)[k].duration + hf;
    if (v == h.goal)
      continue;  // arriving at the goal ends the way
    h.node[static_cast<std::size_t>(v)] = std::min(h.node[static_cast<std::size_t>(v)], down(viaF));
    for (const std::uint32_t e : reverse_[static_cast<std::size_t>(v)]) {
      const double cand = turnAt(edgeTail_[e], static_cast<std::int32_t>(e), v, k) + viaF;
      // A lower sum that rounds to the same float is not searched on from: a value may stand up to
      // a float step per edge of its way above the least sum (~1e-5 s at 100 s from the goal; the
      // search's arrival is that much from the earliest at most, far below its 1 ms steps).
      if (down(cand) < h.edge[e]) {
        h.edge[e] = down(cand);
        if (usable(e)) {
          h.heap.emplace_back(cand, e);
          std::push_heap(h.heap.begin(), h.heap.end(), std::greater<>());
        }
      }
    }
  }
  if (h.heap.empty())
    h.heap.shrink_to_fit();
}

double Sipp::toGoal(Heuristic& h, NodeId v, std::int64_t in) {
  const float& x = in >= 0 ? h.edge[static_cast<std::size_t>(in)] : h.node[static_cast<std::size_t>(v)];
  if (!h.heap.empty() && h.heap.front().first <= static_cast<double>(x))
    settle(h, x);
  return x == std::numeric_limits<float>::infinity() ? kForever : static_cast<double>(x);
}

bool Sipp::setNodeCost(std::vector<float> cost) {
  if (!cost.empty() && cost.size() != graph_.size()) {
    throw std::invalid_argument("sipp: " + std::to_string(cost.size()) + " node costs for " +
                                std::to_string(graph_.size()) + " nodes");
  }
  if (std::any_of(cost.begin(), cost.end(), [](float c) { return !(c >= 0.0F) || !std::isfinite(c); }))
    throw std::invalid_argument("sipp: a node cost that is negative or not a finite number");
  if (std::all_of(cost.begin(), cost.end(), [](float c) { return c == 0.0F; }))
    cost.clear();
  if (cost == cost_)
    return false;
  cost_ = std::move(cost);  // the goals' tables stay: costs are not in them (sipp.hpp)
  return true;
}

double Sipp::drivingTime(NodeId v, NodeId goal) {
  if (!graph_.valid(v) || !graph_.valid(goal))
    return kForever;
  return toGoal(heuristic(goal), v, -1);
}

const std::vector<Interval>& Sipp::intervals(const ReservationTable& table, NodeId v, double from) {
  const auto i = static_cast<std::size_t>(v);
  if (intervalStamp_[i] != stamp_) {
    intervalStamp_[i] = stamp_;
    table.safe(v, from, intervals_[i]);
  }
  return intervals_[i];
}

std::pair<Sipp::Best*, bool> Sipp::bestOf(std::size_t slot, std::int32_t interval, double arrive) {
  if (bestStamp_[slot] != stamp_) {
    bestStamp_[slot] = stamp_;
    bestHead_[slot] = -1;
  }
  for (std::int32_t b = bestHead_[slot]; b >= 0; b = bestPool_[static_cast<std::size_t>(b)].next) {
    if (bestPool_[static_cast<std::size_t>(b)].interval == interval)
      return {&bestPool_[static_cast<std::size_t>(b)], false};
  }
  bestPool_.push_back({interval, bestHead_[slot], arrive});
  bestHead_[slot] = static_cast<std::int32_t>(bestPool_.size() - 1);
  return {&bestPool_.back(), true};
}

std::optional<TimedPath> Sipp::plan(const ReservationTable& table, const SippQuery& q) {
  ++stats_.searches;
  const bool refuge = q.goal == kNoNode;
  if (!graph_.valid(q.start) || (!refuge && !graph_.valid(q.goal))) {
    ++stats_.failures;
    return std::nullopt;
  }
  index();
  if (intervalStamp_.size() != graph_.size()) {
    intervalStamp_.assign(graph_.size(), 0);
    intervals_.assign(graph_.size(), {});
    stamp_ = 0;
  }
  if (++stamp_ == 0) {  // wrapped: every stamp might look current again
    std::fill(intervalStamp_.begin(), intervalStamp_.end(), 0);
    std::fill(bestStamp_.begin(), bestStamp_.end(), 0);
    stamp_ = 1;
  }
  // A refuge has no heuristic (Dijkstra in time).
  Heuristic* h = refuge ? nullptr : &heuristic(q.goal);
  // From a node arrived at by edge `in` (-1: no heading).
  auto hOf = [&](NodeId v, std::int64_t in) {
    if (h == nullptr)
      return 0.0;
    return toGoal(*h, v, in);
  };
  auto isGoal = [&](NodeId v) {
    return refuge ? (q.avoid == nullptr || (*q.avoid)[static_cast<std::size_t>(v)] == 0) : v == q.goal;
  };
  states_.clear();
  bestPool_.clear();
  open_.clear();
  // The start's interval: the one holding the start time.
  const auto& startIv = intervals(table, q.start, q.startTime);
  const std::int64_t startIn = edgeIndex(q.cameFrom, q.start);
  if (startIv.empty() || startIv.front().from > q.startTime || hOf(q.start, startIn) == kForever) {
    ++stats_.failures;
    return std::nullopt;
  }
  // A goal it cannot stay on long enough at any time is not searched for (a robot standing there
  // until its turn): the search would otherwise try every state before it gave up.
  if (!refuge && (intervals(table, q.goal, q.startTime).empty() ||
                  intervals(table, q.goal, q.startTime).back().to < q.holdUntil)) {
    ++stats_.failures;
    return std::nullopt;
  }
  const auto startEdge = static_cast<std::int32_t>(startIn);
  states_.push_back({q.start, q.cameFrom, startEdge, 0, -1, q.startTime, q.startTime, startIv.front().to});
  const double f0 = q.startTime + hOf(q.start, startIn);
  open_.push_back({0, q.startTime, 0});
  bestOf(slotOf(q.start, startEdge), 0, q.startTime);
  std::size_t expanded = 0;
  std::int32_t found = -1;
  while (!open_.empty()) {
    std::pop_heap(open_.begin(), open_.end(), kLaterFirst);
    const Open top = open_.back();
    open_.pop_back();
    const State s = states_[static_cast<std::size_t>(top.state)];
    if (top.g > bestOf(slotOf(s.node, s.inEdge), s.interval, top.g).first->arrive)
      continue;  // reached earlier since
    if (isGoal(s.node) && s.intervalEnd >= q.holdUntil) {
      found = top.state;
      break;
    }
    if (++expanded > maxExpansions_)
      break;
    const auto sv = static_cast<std::size_t>(s.node);
    const NodeId onlyTo =
        (q.line >= 0 && q.lineOf != nullptr && (*q.lineOf)[sv] == q.line) ? (*q.forward)[sv] : kNoNode;
    const auto out = graph_.edges(s.node);
    for (std::size_t k = 0; k < out.size(); ++k) {
      const Edge& e = out[k];
      if (!e.open || !graph_.isOpen(e.to) || (onlyTo != kNoNode && e.to != onlyTo))
        continue;  // a robot on a closed node may still drive off it
      const NodeId w = e.to;
      const auto viaE = static_cast<std::int32_t>(edgeStart_[sv] + k);
      const double hw = hOf(w, viaE);
      if (hw == kForever)
        continue;
      const double turn = turnAt(s.from, s.inEdge, s.node, k);
      const double earliest = s.arrive + turn;
      // It stands on its node until it has arrived at the next.
      const double took = duration(e);
      const double latest = s.intervalEnd - took;
      if (earliest > latest)
        continue;
      const auto& ivs = intervals(table, w, q.startTime);
      for (std::size_t j = 0; j < ivs.size(); ++j) {
        const Interval& iw = ivs[j];
        if (iw.from > latest)
          break;
        const double depart = std::max(earliest, iw.from);
        const double arrive = depart + took;
        if (depart > latest || arrive > iw.to)
          continue;
        const auto [best, fresh] =
            bestOf(static_cast<std::size_t>(viaE), static_cast<std::int32_t>(j), arrive);
        if (!fresh) {
          if (arrive >= best->arrive)
            continue;
          best->arrive = arrive;
        }
        states_.push_back({w, s.node, viaE, static_cast<std::int32_t>(j), top.state, arrive, depart, iw.to});
        open_.push_back({fKey(arrive + hw, f0), arrive, static_cast<std::int32_t>(states_.size() - 1)});
        std::push_heap(open_.begin(), open_.end(), kLaterFirst);
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
