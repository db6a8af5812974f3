#include "fleet/traffic/safe_intervals.hpp"

#include <algorithm>

namespace fleet::traffic {

std::vector<Interval> occupancy(std::span<const TimedNode> path) {
  std::vector<Interval> out(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    out[i].from = path[i].enter;
    out[i].to = i + 1 < path.size() ? path[i + 1].arrive : path[i].leave;
  }
  return out;
}

ReservationTable::ReservationTable(const Graph& graph) : graph_(graph), unsafe_(graph.size()) {}

void ReservationTable::add(NodeId v, Span span) {
  auto& list = unsafe_[static_cast<std::size_t>(v)];
  if (list.empty())
    touched_.push_back(v);
  const auto it = std::upper_bound(list.begin(), list.end(), span.from,
                                   [](double t, const Span& s) { return t < s.from; });
  list.insert(it, span);
  if (span.owner >= 0) {
    const auto o = static_cast<std::size_t>(span.owner);
    if (ownerTouched_.size() <= o)
      ownerTouched_.resize(o + 1);
    ownerTouched_[o].push_back(v);
  }
}

void ReservationTable::reserve(NodeId v, Interval span, std::int32_t owner) {
  if (!graph_.valid(v) || !(span.from <= span.to))
    return;
  if (unsafe_.size() < graph_.size())
    unsafe_.resize(graph_.size());
  add(v, {span.from, span.to, owner});
  for (const NodeId w : graph_.conflicts(v))
    add(w, {span.from, span.to, owner});
}

void ReservationTable::reserve(std::span<const TimedNode> path, double until, std::int32_t owner) {
  const auto occ = occupancy(path);
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (occ[i].from > until)
      break;
    reserve(path[i].node, {occ[i].from, std::min(occ[i].to, until)}, owner);
  }
}

void ReservationTable::release(std::int32_t owner) {
  if (owner < 0 || static_cast<std::size_t>(owner) >= ownerTouched_.size())
    return;
  auto& nodes = ownerTouched_[static_cast<std::size_t>(owner)];
  for (const NodeId v : nodes)
    std::erase_if(unsafe_[static_cast<std::size_t>(v)], [&](const Span& s) { return s.owner == owner; });
  nodes.clear();
}

void ReservationTable::clear() {
  for (const NodeId v : touched_)
    unsafe_[static_cast<std::size_t>(v)].clear();
  touched_.clear();
  for (auto& nodes : ownerTouched_)
    nodes.clear();
}

std::vector<Interval> ReservationTable::unsafe(NodeId v) const {
  std::vector<Interval> out;
  for (const Span& s : unsafe_[static_cast<std::size_t>(v)]) {
    if (!out.empty() && s.from <= out.back().to)
      out.back().to = std::max(out.back().to, s.to);
    else
      out.push_back({s.from, s.to});
  }
  return out;
}

std::vector<Interval> ReservationTable::safe(NodeId v, double from) const {
  std::vector<Interval> out;
  safe(v, from, out);
  return out;
}

void ReservationTable::safe(NodeId v, double from, std::vector<Interval>& out) const {
  out.clear();
  double start = from;
  for (const Span& u : unsafe_[static_cast<std::size_t>(v)]) {
    if (u.to < start)
      continue;
    if (u.from > start)
      out.push_back({start, u.from});
    start = std::max(start, u.to);
    if (start == kForever)
      return;
  }
  out.push_back({start, kForever});
}

bool ReservationTable::safeOver(NodeId v, double a, double b) const {
  // Touching ends are allowed; a span inside [a, b], even of no length, is not.
  return std::none_of(unsafe_[static_cast<std::size_t>(v)].begin(),
                      unsafe_[static_cast<std::size_t>(v)].end(), [&](const Span& s) {
                        return s.from < b && s.to > a && !(s.from == s.to && (s.from == a || s.from == b));
                      });
}

std::int64_t ReservationTable::firstConflict(std::span<const TimedNode> path) const {
  const auto occ = occupancy(path);
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (!safeOver(path[i].node, occ[i].from, occ[i].to))
      return static_cast<std::int64_t>(i);
  }
  return -1;
}

}  // namespace fleet::traffic
