#include "fleet/traffic/prioritized_planner.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace fleet::traffic {

PrioritizedPlanner::PrioritizedPlanner(const Graph& graph, Sipp::TurnTime turn, PrioritizedOptions options)
    : graph_(graph), options_(options), sipp_(graph, std::move(turn), options.maxExpansions), table_(graph) {}

std::vector<std::size_t> PrioritizedPlanner::order(std::span<const PlanRequest> robots) {
  std::vector<std::size_t> idx(robots.size());
  std::iota(idx.begin(), idx.end(), std::size_t{0});
  std::stable_sort(idx.begin(), idx.end(), [&](std::size_t a, std::size_t b) {
    const auto& ra = robots[a];
    const auto& rb = robots[b];
    if (ra.held != rb.held)
      return ra.held;
    if (ra.priority != rb.priority)
      return ra.priority > rb.priority;
    const bool ga = ra.goal != kNoNode && ra.goal != ra.at;
    const bool gb = rb.goal != kNoNode && rb.goal != rb.at;
    if (ga != gb)
      return ga;
    return ra.waiting > rb.waiting;
  });
  return idx;
}

void PrioritizedPlanner::reserveFixed(std::span<const PlanRequest> robots, bool starts) {
  table_.clear();
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const auto& r = robots[i];
    if (!r.committed.empty()) {
      // Driven as released: each node until it has arrived at the next, the last until `ready`
      // (its own reservation of `at` takes over then). The execution has the robot on `at` before
      // any new move, so `at` is taken from when the release begins.
      TimedPath c = r.committed;
      c.back().leave = r.ready;
      table_.reserve(c, kForever, ReservationTable::kNobody);
      table_.reserve(r.at, {c.front().enter, r.ready}, ReservationTable::kNobody);
    }
    if (r.held || starts)
      table_.reserve(r.at, {r.ready, kForever},
                     r.held ? ReservationTable::kNobody : static_cast<std::int32_t>(i));
  }
}

bool PrioritizedPlanner::keepsPlace(const PlanRequest& r) const {
  // A robot waiting on its line's nodes is never sent out of the way: it would lose its place.
  return r.line >= 0 && lineOf_.size() == graph_.size() && lineOf_[static_cast<std::size_t>(r.at)] == r.line;
}

void PrioritizedPlanner::setNodeCost(std::vector<float> cost) {
  const std::vector<float> before = sipp_.nodeCost();
  if (!sipp_.setNodeCost(std::move(cost)))
    return;
  const auto& now = sipp_.nodeCost();
  const auto at = [](const std::vector<float>& c, NodeId v) {
    // (costs given before the graph grew are shorter than it)
    return static_cast<std::size_t>(v) < c.size() ? c[static_cast<std::size_t>(v)] : 0.0F;
  };
  // A node on a kept plan dearer or cheaper: it may go round now, or its timing is off. A node a
  // second or more cheaper anywhere (a yield's end): a way round it may no longer be the earliest,
  // so every plan is searched again; smaller falls (the risk map's renewals, at most risk_cost_s a
  // node) leave plans that go round them, which are searched again anyway when they stop fitting.
  bool fell = false;
  for (std::size_t v = 0; v < graph_.size() && !fell; ++v)
    fell = at(now, static_cast<NodeId>(v)) <= at(before, static_cast<NodeId>(v)) - 1.0F;
  for (auto& path : previous_) {
    if (fell || std::any_of(path.begin(), path.end(),
                            [&](const TimedNode& n) { return at(now, n.node) != at(before, n.node); }))
      path.clear();
  }
}

std::optional<TimedPath> PrioritizedPlanner::reuse(std::size_t i, const PlanRequest& r) const {
  // The rest of its last plan, when it is where that plan has it about when it has it there, the
  // plan still goes to its goal and still keeps to everyone's reservations (moved later by how
  // late it is). Most robots are on time between two plans: no search for them.
  if (i >= previous_.size() || previous_[i].empty() || previous_[i].back().node != r.goal)
    return std::nullopt;
  const auto& old = previous_[i];
  const auto k = static_cast<std::size_t>(
      std::find_if(old.begin(), old.end(), [&](const TimedNode& n) { return n.node == r.at; }) - old.begin());
  if (k + 1 >= old.size() || std::abs(old[k].arrive - r.ready) > options_.reuseSlack)
    return std::nullopt;
  TimedPath rest(old.begin() + static_cast<std::ptrdiff_t>(k), old.end());
  for (std::size_t j = 0; j + 1 < rest.size(); ++j) {
    if (graph_.edge(rest[j].node, rest[j + 1].node) == nullptr || !graph_.isOpen(rest[j + 1].node))
      return std::nullopt;  // closed since
  }
  const double late = std::max(0.0, r.ready - rest.front().arrive);
  for (auto& n : rest) {
    n.enter += late;
    n.arrive += late;
    n.leave += late;
  }
  rest.front().enter = rest.front().arrive = r.ready;
  rest.back().leave = kForever;
  if (table_.firstConflict(rest) >= 0)
    return std::nullopt;
  return rest;
}

std::vector<std::size_t> PrioritizedPlanner::pass(std::span<const PlanRequest> robots,
                                                  std::span<const std::size_t> order,
                                                  const std::vector<std::vector<std::uint8_t>>& clear,
                                                  double until, std::vector<TimedPath>& paths) {
  // Everyone stands where it is until it is planned.
  reserveFixed(robots, true);
  paths.assign(robots.size(), {});
  for (std::size_t i = 0; i < robots.size(); ++i)
    paths[i] = {TimedNode{robots[i].at, robots[i].ready, robots[i].ready, kForever}};
  std::vector<std::size_t> failed;
  std::vector<std::size_t> deferred;
  // One robot's turn; `last`: its second try (or the only one it gets).
  const auto planOne = [&](std::size_t i, bool last) {
    const auto& r = robots[i];
    const auto owner = static_cast<std::int32_t>(i);
    const bool wantsGoal = r.goal != kNoNode && r.goal != r.at;
    const bool mustClear = !clear[i].empty() && clear[i][static_cast<std::size_t>(r.at)] != 0;
    if (!wantsGoal && !mustClear)
      return;  // it stays, as reserved
    table_.release(owner);
    std::optional<TimedPath> found = wantsGoal ? reuse(i, r) : std::nullopt;
    const bool lines = r.line >= 0 && lineOf_.size() == graph_.size();
    const SippQuery toGoal{r.at,    r.cameFrom,          r.ready,  r.goal,   until,
                           nullptr, lines ? r.line : -1, &lineOf_, &forward_};
    if (found)
      ++stats_.reused;
    else if (wantsGoal)
      found = sipp_.plan(table_, toGoal);
    if (!found && !last && !mustClear) {
      // Its way may be shut only by robots standing until their turn: it goes again after them.
      table_.reserve(r.at, {r.ready, kForever}, owner);
      deferred.push_back(i);
      return;
    }
    if (!found && mustClear) {
      // Out of the way of the robot it yields to: the earliest place off that robot's way.
      SippQuery q{r.at, r.cameFrom, r.ready, kNoNode, until, &clear[i]};
      found = sipp_.plan(table_, q);
      if (found)
        ++stats_.refuges;
    }
    if (found) {
      found->back().leave = kForever;
      paths[i] = std::move(*found);
    }
    if (wantsGoal && paths[i].back().node != r.goal)
      failed.push_back(i);
    table_.reserve(paths[i], until, owner);
    if (paths[i].back().arrive <= until)  // it stays where its path ends beyond the window
      table_.reserve(paths[i].back().node, {paths[i].back().arrive, kForever}, owner);
  };
  for (const std::size_t i : order) {
    if (robots[i].held)
      continue;
    planOne(i, false);
  }
  stats_.deferred += deferred.size();
  for (const std::size_t i : deferred)
    planOne(i, true);
  return failed;
}

std::vector<TimedPath> PrioritizedPlanner::plan(std::span<const PlanRequest> robots) {
  ++stats_.plans;
  double start = kForever;
  for (const auto& r : robots)
    start = std::min(start, r.ready);
  const double until = start + options_.window;
  until_ = until;
  auto ord = order(robots);
  std::vector<std::vector<std::uint8_t>> clear(robots.size());
  std::vector<TimedPath> paths;
  std::vector<std::size_t> failed;
  for (int round = 0;; ++round) {
    failed = pass(robots, ord, clear, until, paths);
    if (failed.empty() || round >= options_.yieldRounds)
      break;
    // Priority inheritance, a robot at a time: the robots standing on a failed robot's way (as it
    // would drive with nobody standing anywhere) are planned before it and get out of that way.
    bool changed = false;
    reserveFixed(robots, false);  // only what is released and the held robots (the loop keeps it)
    for (const std::size_t i : failed) {
      if (!clear[i].empty())
        continue;  // yielding itself: it does not make the one it yields to yield back
      const auto& r = robots[i];
      const auto way = sipp_.plan(table_, {r.at, r.cameFrom, r.ready, r.goal, until});
      if (!way)
        continue;
      std::vector<std::uint8_t> marks(graph_.size(), 0);
      for (const auto& n : *way) {
        marks[static_cast<std::size_t>(n.node)] = 1;
        for (const NodeId w : graph_.conflicts(n.node))
          marks[static_cast<std::size_t>(w)] = 1;
      }
      const auto posOf = [&](std::size_t k) { return std::find(ord.begin(), ord.end(), k) - ord.begin(); };
      for (std::size_t j = 0; j < robots.size(); ++j) {
        if (j == i || robots[j].held || keepsPlace(robots[j]) || !clear[j].empty() ||
            marks[static_cast<std::size_t>(robots[j].at)] == 0)
          continue;
        if (posOf(j) < posOf(i) && std::find(failed.begin(), failed.end(), j) == failed.end() &&
            marks[static_cast<std::size_t>(paths[j].back().node)] == 0)
          continue;  // planned before it and gone from its way
        clear[j] = marks;
        ord.erase(ord.begin() + posOf(j));
        ord.insert(ord.begin() + posOf(i), j);
        ++stats_.yields;
        changed = true;
      }
    }
    if (!changed)
      break;
  }
  stats_.failures += failed.size();
  previous_ = paths;
  return paths;
}

}  // namespace fleet::traffic
