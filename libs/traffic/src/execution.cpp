#include "fleet/traffic/execution.hpp"

#include <algorithm>
#include <limits>
#include <sstream>

namespace fleet::traffic {

const char* toString(Report r) {
  switch (r) {
    case Report::Accepted:
      return "accepted";
    case Report::Duplicate:
      return "duplicate";
    case Report::NotReleased:
      return "not released";
    case Report::UnknownRobot:
      return "unknown robot";
  }
  return "?";
}

Execution::Execution(const Graph& graph, std::span<const NodeId> starts, ReleaseOptions options)
    : graph_(graph), options_(options), lastVisit_(graph.size()) {
  routes_.resize(starts.size());
  for (std::size_t r = 0; r < starts.size(); ++r) {
    if (!graph_.valid(starts[r])) {
      throw PlanStepError("robot " + std::to_string(r) + " starts on node " + std::to_string(starts[r]) +
                          ", which is not on the graph");
    }
    for (std::size_t q = 0; q < r; ++q) {
      if (graph_.conflicting(starts[q], starts[r])) {
        throw PlanStepError("robots " + std::to_string(q) + " and " + std::to_string(r) +
                            " start on conflicting nodes " + std::to_string(starts[q]) + " and " +
                            std::to_string(starts[r]));
      }
    }
    routes_[r].entries.push_back(Entry{starts[r], 0, 0.0, {}, 0});
    lastVisit_[static_cast<std::size_t>(starts[r])] = Visit{static_cast<std::int32_t>(r), 0};
  }
}

void Execution::append(std::span<const NodeId> next) {
  const std::size_t n = routes_.size();
  if (next.size() != n) {
    throw PlanStepError("a plan step has " + std::to_string(next.size()) + " nodes for " + std::to_string(n) +
                        " robots");
  }
  auto fail = [](const std::string& what) { throw PlanStepError("plan step refused: " + what); };
  // Moves along the graph.
  std::vector<std::size_t> movers;
  for (std::size_t r = 0; r < n; ++r) {
    const NodeId from = routes_[r].entries.back().node;
    const NodeId to = next[r];
    if (!graph_.valid(to))
      fail("robot " + std::to_string(r) + " to node " + std::to_string(to) + " off the graph");
    if (to == from)
      continue;
    const Edge* e = graph_.edge(from, to);
    if (e == nullptr || !graph_.isOpen(to)) {
      fail("robot " + std::to_string(r) + " from node " + std::to_string(from) + " to " + std::to_string(to) +
           ": no open edge");
    }
    movers.push_back(r);
  }
  // The configuration is conflict-free (pairs only meet through a node or its conflict set).
  std::vector<std::pair<NodeId, std::size_t>> at;
  at.reserve(n);
  for (std::size_t r = 0; r < n; ++r)
    at.emplace_back(next[r], r);
  std::sort(at.begin(), at.end());
  for (std::size_t i = 1; i < n; ++i) {
    if (at[i].first == at[i - 1].first) {
      fail("robots " + std::to_string(at[i - 1].second) + " and " + std::to_string(at[i].second) +
           " on node " + std::to_string(at[i].first));
    }
  }
  auto robotOn = [&](NodeId v) -> std::int64_t {
    auto it = std::lower_bound(at.begin(), at.end(), std::pair<NodeId, std::size_t>{v, 0});
    return (it != at.end() && it->first == v) ? static_cast<std::int64_t>(it->second) : -1;
  };
  if (graph_.hasConflicts()) {
    for (std::size_t r = 0; r < n; ++r) {
      for (NodeId x : graph_.conflicts(next[r])) {
        const auto q = robotOn(x);
        if (q >= 0 && static_cast<std::size_t>(q) != r) {
          fail("robots " + std::to_string(r) + " and " + std::to_string(q) + " on conflicting nodes " +
               std::to_string(next[r]) + " and " + std::to_string(x));
        }
      }
    }
  }
  // New entries first, so a dependency can point at a move of this same step.
  const std::int64_t step = step_ + 1;
  for (std::size_t r : movers) {
    auto& route = routes_[r];
    const NodeId from = route.entries.back().node;
    const std::int64_t order = std::max(step * kOrderPerStep, route.entries.back().order + 1);
    route.entries.push_back(
        Entry{next[r], step, (graph_.position(next[r]) - graph_.position(from)).norm(), {}, order});
  }
  auto undo = [&] {
    for (std::size_t r : movers)
      routes_[r].entries.pop_back();
  };
  std::vector<std::vector<std::size_t>> sameStep(n);
  for (std::size_t r : movers)
    sameStep[r] = depend(r, step);
  // A cycle of same-step dependencies (a rotation, or a swap) could never be executed.
  std::vector<std::uint8_t> mark(n, 0);  // 0 new, 1 on the stack, 2 done
  std::vector<std::size_t> cycle;
  auto dfs = [&](auto&& self, std::size_t r) -> bool {
    mark[r] = 1;
    cycle.push_back(r);
    for (std::size_t q : sameStep[r]) {
      if (mark[q] == 1) {
        cycle.push_back(q);
        return true;
      }
      if (mark[q] == 0 && self(self, q))
        return true;
    }
    mark[r] = 2;
    cycle.pop_back();
    return false;
  };
  for (std::size_t r : movers) {
    if (mark[r] == 0 && dfs(dfs, r)) {
      undo();
      std::ostringstream os;
      os << "robots";
      for (std::size_t q : cycle)
        os << ' ' << q;
      os << " each enter what the next one leaves (a cycle cannot be executed)";
      fail(os.str());
    }
  }
  // A robot entering what another leaves in this same step comes after that move in the order
  // (the same-step dependencies are acyclic, so this settles within one pass per mover).
  for (std::size_t pass = 0; pass < movers.size(); ++pass) {
    bool changed = false;
    for (std::size_t r : movers) {
      auto& order = routes_[r].entries.back().order;
      for (std::size_t q : sameStep[r]) {
        const auto after = routes_[q].entries.back().order + 1;
        if (order < after) {
          order = after;
          changed = true;
        }
      }
    }
    if (!changed)
      break;
  }
  for (std::size_t r : movers) {
    const auto& route = routes_[r];
    lastVisit_[static_cast<std::size_t>(route.entries.back().node)] =
        Visit{static_cast<std::int32_t>(r), route.last()};
  }
  step_ = step;
}

std::vector<std::size_t> Execution::depend(std::size_t r, std::int64_t step) {
  // Wait until the last visitor of every node excluding the target has moved on to the first node
  // of its route that no longer conflicts with the target.
  auto& entry = routes_[r].entries.back();
  const NodeId v = entry.node;
  std::vector<std::pair<std::size_t, std::int64_t>> need;  // robot, route index: a conflict set's few
  auto visitor = [&](NodeId x) {
    const Visit lv = lastVisit_[static_cast<std::size_t>(x)];
    if (lv.robot < 0 || static_cast<std::size_t>(lv.robot) == r)
      return;
    const auto q = static_cast<std::size_t>(lv.robot);
    const Route& qr = routes_[q];
    // After letPass() a visitor may stand later in the order than this step: stay behind it.
    if (lv.index >= qr.first)
      entry.order = std::max(entry.order, qr[lv.index].order + 1);
    std::int64_t i = std::max(lv.index + 1, qr.first);
    while (i <= qr.last() && graph_.conflicting(qr[i].node, v))
      ++i;
    // i <= last: the configuration check guarantees q's current node does not conflict.
    const auto it = std::find_if(need.begin(), need.end(), [&](const auto& n) { return n.first == q; });
    if (it == need.end())
      need.emplace_back(q, i);
    else
      it->second = std::max(it->second, i);
  };
  visitor(v);
  for (NodeId x : graph_.conflicts(v))
    visitor(x);
  std::sort(need.begin(), need.end());  // by robot, as the dependencies have always been listed
  std::vector<std::size_t> sameStep;
  for (const auto& [q, i] : need) {
    if (routes_[q].progress >= i)
      continue;
    entry.deps.push_back(Dependency{static_cast<std::uint32_t>(q), i});
    const bool movesNow = routes_[q].entries.back().step == step;
    if (movesNow && i == routes_[q].last())
      sameStep.push_back(q);
  }
  return sameStep;
}

void Execution::appendMove(std::size_t robot, NodeId to) {
  auto fail = [](const std::string& what) { throw PlanStepError("plan step refused: " + what); };
  if (robot >= routes_.size())
    fail("no robot " + std::to_string(robot));
  const NodeId from = routes_[robot].entries.back().node;
  if (!graph_.valid(to))
    fail("robot " + std::to_string(robot) + " to node " + std::to_string(to) + " off the graph");
  const std::int64_t step = step_ + 1;
  if (to != from) {
    const Edge* e = graph_.edge(from, to);
    if (e == nullptr || !graph_.isOpen(to)) {
      fail("robot " + std::to_string(robot) + " from node " + std::to_string(from) + " to " +
           std::to_string(to) + ": no open edge");
    }
    for (std::size_t q = 0; q < routes_.size(); ++q) {
      const NodeId at = routes_[q].entries.back().node;
      if (q == robot || (at != to && !graph_.conflicting(at, to)))
        continue;
      const auto [a, b] = std::minmax(robot, q);
      fail(at == to ? "robots " + std::to_string(a) + " and " + std::to_string(b) + " on node " +
                          std::to_string(to)
                    : "robots " + std::to_string(robot) + " and " + std::to_string(q) +
                          " on conflicting nodes " + std::to_string(to) + " and " + std::to_string(at));
    }
    auto& route = routes_[robot];
    const std::int64_t order = std::max(step * kOrderPerStep, route.entries.back().order + 1);
    route.entries.push_back(Entry{to, step, (graph_.position(to) - graph_.position(from)).norm(), {}, order});
    depend(robot, step);  // nobody else moves in this step: no same-step dependency
    lastVisit_[static_cast<std::size_t>(to)] = Visit{static_cast<std::int32_t>(robot), route.last()};
  }
  step_ = step;
}

bool Execution::satisfied(const Entry& e) const {
  return std::all_of(e.deps.begin(), e.deps.end(),
                     [&](const Dependency& d) { return routes_[d.robot].progress >= d.index; });
}

const char* toString(BaseCut c) {
  switch (c) {
    case BaseCut::PlanEnd:
      return "plan_end";
    case BaseCut::Held:
      return "held";
    case BaseCut::Limit:
      return "limit";
  }
  return "?";
}

Report Execution::reached(std::size_t robot, NodeId node) {
  if (robot >= routes_.size())
    return Report::UnknownRobot;
  auto& route = routes_[robot];
  if (route[route.progress].node == node)
    return Report::Duplicate;
  for (std::int64_t i = route.progress + 1; i <= route.released; ++i) {
    if (route[i].node == node) {
      route.progress = i;
      prune(robot);
      return Report::Accepted;
    }
  }
  return Report::NotReleased;
}

void Execution::prune(std::size_t robot) {
  auto& route = routes_[robot];
  const auto drop = route.progress - route.first;
  if (drop <= 0)
    return;
  route.entries.erase(route.entries.begin(), route.entries.begin() + drop);
  route.first = route.progress;
}

namespace {

/// A base never passes a node twice. The planner moves robots aside and back ([A B C A]: out of
/// another's way and back onto its route); an agent that projects itself onto such a base finds
/// its own node at both ends, takes the base as driven, and stands while the traffic manager waits
/// for B (full stack: three robots stood for good with bases [A B C A], 20 robots,
/// seed 7, 67 of 100 tasks done). Released up to C, reported there, then [C A ...].
template <class Route>
bool releasedAgain(const Route& route, NodeId node) {
  for (std::int64_t i = route.progress; i < route.released; ++i) {
    if (route[i].node == node)
      return true;
  }
  return false;
}

}  // namespace

Release Execution::release(std::size_t robot) {
  Release out;
  if (robot >= routes_.size())
    return out;
  auto& route = routes_[robot];
  double ahead = 0.0;
  for (std::int64_t i = route.progress + 1; i <= route.released; ++i)
    ahead += route[i].distance;
  route.cut = BaseCut::Limit;
  while (route.released < route.last() && ahead < options_.baseAhead &&
         static_cast<std::size_t>(route.released - route.progress) < options_.maxBaseNodes) {
    const Entry& e = route[route.released + 1];
    if (!satisfied(e) || releasedAgain(route, e.node)) {
      route.cut = BaseCut::Held;
      break;
    }
    ++route.released;
    ahead += e.distance;
  }
  if (route.released >= route.last())
    route.cut = BaseCut::PlanEnd;
  for (std::int64_t i = route.progress; i <= route.released; ++i)
    out.base.push_back(route[i].node);
  const std::int64_t end =
      std::min(route.last(), route.released + static_cast<std::int64_t>(options_.horizonNodes));
  for (std::int64_t i = route.released + 1; i <= end; ++i) {
    if (std::find(out.base.begin(), out.base.end(), route[i].node) != out.base.end() ||
        std::find(out.horizon.begin(), out.horizon.end(), route[i].node) != out.horizon.end())
      break;
    out.horizon.push_back(route[i].node);
  }
  out.baseEndStep = route[route.released].step;
  return out;
}

std::vector<std::size_t> Execution::waitingOn(std::size_t robot) const {
  std::vector<std::size_t> out;
  if (robot >= routes_.size())
    return out;
  const auto& route = routes_[robot];
  if (route.released >= route.last())
    return out;
  for (const auto& d : route[route.released + 1].deps) {
    if (routes_[d.robot].progress < d.index)
      out.push_back(d.robot);
  }
  return out;
}

NodeId Execution::at(std::size_t robot) const {
  return routes_.at(robot)[routes_[robot].progress].node;
}
NodeId Execution::releasedEnd(std::size_t robot) const {
  return routes_.at(robot)[routes_[robot].released].node;
}
NodeId Execution::releasedFrom(std::size_t robot) const {
  const Route& route = routes_.at(robot);
  const NodeId end = route[route.released].node;
  for (std::int64_t i = route.released - 1; i >= route.first; --i) {
    if (route[i].node != end) {
      return route[i].node;
    }
  }
  return kNoNode;
}
std::vector<NodeId> Execution::releasedRoute(std::size_t robot) const {
  const Route& route = routes_.at(robot);
  std::vector<NodeId> out;
  for (std::int64_t i = route.progress; i <= route.released; ++i) {
    if (out.empty() || out.back() != route[i].node)
      out.push_back(route[i].node);
  }
  return out;
}
NodeId Execution::plannedEnd(std::size_t robot) const {
  return routes_.at(robot).entries.back().node;
}
std::int64_t Execution::progressStep(std::size_t robot) const {
  return routes_.at(robot)[routes_[robot].progress].step;
}
std::int64_t Execution::nextUnreleasedStep(std::size_t robot) const {
  const auto& route = routes_.at(robot);
  return route.released < route.last() ? route[route.released + 1].step : -1;
}

std::string Execution::describe(std::size_t robot) const {
  std::ostringstream os;
  const auto& route = routes_.at(robot);
  for (std::int64_t i = route.progress; i <= route.released; ++i)
    os << (i > route.progress ? " " : "") << route[i].node;
  if (route.released < route.last()) {
    const Entry& e = route[route.released + 1];
    os << " | " << e.node << " (needs";
    for (const auto& d : e.deps)
      os << " " << d.robot << ":" << d.index << "/" << routes_[d.robot].progress;
    os << ")";
  }
  return os.str();
}

std::size_t Execution::pendingNodes(std::size_t robot) const {
  const auto& route = routes_.at(robot);
  return static_cast<std::size_t>(route.last() - route.progress);
}

std::size_t Execution::addRobot(NodeId start) {
  if (!graph_.valid(start)) {
    throw PlanStepError("a robot cannot join on node " + std::to_string(start) + ": not on the graph");
  }
  for (std::size_t q = 0; q < routes_.size(); ++q) {
    const auto& route = routes_[q];
    for (std::int64_t i = route.progress; i <= route.last(); ++i) {
      if (graph_.conflicting(route[i].node, start)) {
        throw PlanStepError("a robot cannot join on node " + std::to_string(start) + ": robot " +
                            std::to_string(q) + " holds or is planned on conflicting node " +
                            std::to_string(route[i].node));
      }
    }
  }
  Route route;
  route.entries.push_back(Entry{start, step_, 0.0, {}, step_ * kOrderPerStep});
  routes_.push_back(std::move(route));
  lastVisit_[static_cast<std::size_t>(start)] = Visit{static_cast<std::int32_t>(routes_.size() - 1), 0};
  return routes_.size() - 1;
}

namespace {
/// The order robots take conflicting nodes in: ties (after letPass() shifts) go to the lower index,
/// so two entries are never unordered.
bool before(std::int64_t order, std::size_t robot, std::int64_t otherOrder, std::size_t other) {
  return order != otherOrder ? order < otherOrder : robot < other;
}
}  // namespace

bool Execution::rederive(const std::vector<std::uint8_t>* only) {
  struct At {
    NodeId node;
    std::uint32_t robot;
    std::int64_t index;
    bool operator<(const At& o) const { return node < o.node; }
  };
  // Every entry on a node an entry whose dependencies are derived looks at: its own and the nodes
  // it conflicts with. With `only`, that is the nodes marked and those conflicting with one (the
  // conflicts are symmetric); the rest are left out of the sort, which was most of a let-pass.
  // Marked once per node (a marked node and its conflicts) rather than asked per entry: asking
  // per entry walked every entry's conflicts: the update's p50 at 1,000 robots fell by a quarter
  // without it.
  std::vector<std::uint8_t> lookedAt;
  if (only != nullptr) {
    lookedAt.assign(graph_.size(), 0);
    for (std::size_t x = 0; x < only->size(); ++x) {
      if ((*only)[x] == 0)
        continue;
      lookedAt[x] = 1;
      for (NodeId y : graph_.conflicts(static_cast<NodeId>(x)))
        lookedAt[static_cast<std::size_t>(y)] = 1;
    }
  }
  const auto looked = [&](NodeId x) { return only == nullptr || lookedAt[static_cast<std::size_t>(x)] != 0; };
  std::vector<At> at;
  for (std::size_t r = 0; r < routes_.size(); ++r) {
    const Route& route = routes_[r];
    for (std::int64_t i = route.first; i <= route.last(); ++i) {
      if (looked(route[i].node))
        at.push_back(At{route[i].node, static_cast<std::uint32_t>(r), i});
    }
  }
  std::sort(at.begin(), at.end());
  std::vector<std::int64_t> lastBefore(routes_.size(), -1);
  std::vector<std::size_t> touched;
  for (std::size_t r = 0; r < routes_.size(); ++r) {
    Route& route = routes_[r];
    for (std::int64_t i = route.released + 1; i <= route.last(); ++i) {
      Entry& e = route.entries[static_cast<std::size_t>(i - route.first)];
      // An entry's dependencies come from the orders of the entries on its node and the nodes it
      // conflicts with (and from its own order): where none of them changed, they stand.
      if (only != nullptr && (*only)[static_cast<std::size_t>(e.node)] == 0)
        continue;
      e.deps.clear();
      auto visits = [&](NodeId x) {
        const auto [lo, hi] = std::equal_range(at.begin(), at.end(), At{x, 0, 0});
        for (auto it = lo; it != hi; ++it) {
          if (it->robot == r)
            continue;
          const Route& q = routes_[it->robot];
          // A released entry was ordered when it was released: before everything unreleased.
          if (it->index > q.released && !before(q[it->index].order, it->robot, e.order, r))
            continue;
          auto& last = lastBefore[it->robot];
          if (last < 0)
            touched.push_back(it->robot);
          last = std::max(last, it->index);
        }
      };
      visits(e.node);
      for (NodeId x : graph_.conflicts(e.node))
        visits(x);
      bool ok = true;
      for (const std::size_t q : touched) {
        const Route& qr = routes_[q];
        std::int64_t need = lastBefore[q] + 1;
        while (need <= qr.last() && graph_.conflicting(qr[need].node, e.node))
          ++need;
        if (need > qr.last())
          ok = false;  // q would have to drive beyond what is planned for it
        else if (qr.progress < need)
          e.deps.push_back(Dependency{static_cast<std::uint32_t>(q), need});
        lastBefore[q] = -1;
      }
      touched.clear();
      if (!ok)
        return false;
    }
  }
  return acyclic();
}

bool Execution::acyclic() const {
  // Vertices: unreleased entries (released ones only wait on what was already reached). Entering
  // entry i needs entry i - 1 reached and every dependency's entry reached.
  std::vector<std::size_t> offset(routes_.size() + 1, 0);
  for (std::size_t r = 0; r < routes_.size(); ++r)
    offset[r + 1] = offset[r] + static_cast<std::size_t>(routes_[r].last() - routes_[r].released);
  auto id = [&](std::size_t r, std::int64_t i) {
    return offset[r] + static_cast<std::size_t>(i - routes_[r].released - 1);
  };
  std::vector<std::uint8_t> mark(offset.back(), 0);  // 0 new, 1 on the stack, 2 done
  struct Frame {
    std::size_t robot;
    std::int64_t index;
    std::size_t next;  ///< 0: the previous entry, then deps
  };
  std::vector<Frame> stack;
  for (std::size_t r = 0; r < routes_.size(); ++r) {
    for (std::int64_t i = routes_[r].released + 1; i <= routes_[r].last(); ++i) {
      if (mark[id(r, i)] != 0)
        continue;
      mark[id(r, i)] = 1;
      stack.push_back(Frame{r, i, 0});
      while (!stack.empty()) {
        Frame& f = stack.back();
        const Route& route = routes_[f.robot];
        const auto& deps = route[f.index].deps;
        std::size_t q = 0;
        std::int64_t j = 0;
        bool edge = false;
        while (!edge && f.next <= deps.size()) {
          if (f.next == 0) {
            q = f.robot;
            j = f.index - 1;
          } else {
            q = deps[f.next - 1].robot;
            j = deps[f.next - 1].index;
          }
          ++f.next;
          edge = j > routes_[q].released;
        }
        if (!edge) {
          mark[id(f.robot, f.index)] = 2;
          stack.pop_back();
          continue;
        }
        const auto v = id(q, j);
        if (mark[v] == 1)
          return false;
        if (mark[v] == 0) {
          mark[v] = 1;
          stack.push_back(Frame{q, j, 0});
        }
      }
    }
  }
  return true;
}

void Execution::retract(std::size_t robot, bool standing) {
  auto& route = routes_.at(robot);
  route.released = std::min(route.released, route.progress + (standing ? 0 : 1));
  route.cut = BaseCut::Held;  // held back (faulted, by a person), not late
}

std::vector<NodeId> Execution::truncateToReleased() {
  std::vector<NodeId> ends;
  for (auto& route : routes_) {
    route.entries.resize(static_cast<std::size_t>(route.released - route.first + 1));
    ends.push_back(route.entries.back().node);
  }
  rebuildVisitors();
  return ends;
}

void Execution::rebuildVisitors() {
  // Released entries were ordered among themselves when they were released and come before every
  // unreleased one (rederive()); unreleased ones follow their order.
  struct Item {
    bool unreleased;
    std::int64_t order;
    std::int32_t robot;
    std::int64_t index;
    NodeId node;
  };
  std::vector<Item> items;
  for (std::size_t r = 0; r < routes_.size(); ++r) {
    const auto& route = routes_[r];
    for (std::int64_t i = route.first; i <= route.last(); ++i) {
      items.push_back(
          Item{i > route.released, route[i].order, static_cast<std::int32_t>(r), i, route[i].node});
    }
  }
  std::sort(items.begin(), items.end(), [](const Item& a, const Item& b) {
    if (a.unreleased != b.unreleased)
      return b.unreleased;
    if (a.order != b.order)
      return a.order < b.order;
    return a.robot != b.robot ? a.robot < b.robot : a.index < b.index;
  });
  std::fill(lastVisit_.begin(), lastVisit_.end(), Visit{});
  for (const auto& it : items)
    lastVisit_[static_cast<std::size_t>(it.node)] = Visit{it.robot, it.index};
}

}  // namespace fleet::traffic
