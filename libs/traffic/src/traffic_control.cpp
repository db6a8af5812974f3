#include "fleet/traffic/traffic_control.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {

namespace {
/// s of plan time the options counted in lattice edges (maxLag) stand for: a 0.5 m
/// lattice edge at 0.8 m/s with a little turning.
constexpr double kStepSeconds = 0.7;

// The planner knows the robots' headings when the plan times their turns (PibtOptions::turnTime).
PibtOptions plannerOptions(const TrafficOptions& options) {
  PibtOptions p = options.pibt;
  if (!p.turnTime) {
    p.turnTime = options.turnTime;
  }
  p.headingWorkPerStep = options.headingWorkPerUpdate /
                         static_cast<std::size_t>(std::max<std::int64_t>(1, options.maxStepsPerUpdate));
  return p;
}
}  // namespace

TrafficControl::TrafficControl(const Graph& graph, std::span<const NodeId> starts, TrafficOptions options)
    : graph_(graph),
      options_(options),
      planner_(std::make_unique<Pibt>(graph, starts, plannerOptions(options))),
      execution_(graph, starts, options.release),
      goal_(starts.size(), kNoNode),
      held_(starts.size(), 0),
      priority_(starts.size(), 0),
      stationOfDock_(graph.size(), -1),
      inLine_(starts.size(), -1),
      target_(starts.size(), kNoNode),
      stall_(starts.size(), 0),
      lastEnd_(starts.begin(), starts.end()),
      evadeUntil_(starts.size(), -1),
      baseEnds_(starts.size()),
      ready_(starts.size(), 0.0),
      busy_(starts.size(), 0),
      stepTime_(1, 0.0),
      came_(starts.size(), kNoNode),
      timed_(graph, options.turnTime, options.prioritized),
      lastGoalAt_(starts.size(), 0.0) {}

void TrafficControl::setStations(std::vector<StationLine> stations) {
  for (std::size_t r = 0; r < robots(); ++r)
    leaveLine(r);
  stations_ = std::move(stations);
  lines_.assign(stations_.size(), {});
  // The lines as the planner walks them: each queue place leads to the one before it, the head to
  // the approach (or the dock), the approach to the dock.
  std::vector<std::int32_t> lineOf(graph_.size(), -1);
  std::vector<NodeId> forward(graph_.size(), kNoNode);
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    const auto& st = stations_[i];
    if (!graph_.valid(st.dock))
      continue;
    const NodeId entry = graph_.valid(st.approach) ? st.approach : st.dock;
    if (entry != st.dock) {
      lineOf[static_cast<std::size_t>(entry)] = static_cast<std::int32_t>(i);
      forward[static_cast<std::size_t>(entry)] = st.dock;
    }
    NodeId next = entry;
    for (const NodeId q : st.queue) {
      if (graph_.valid(q)) {
        lineOf[static_cast<std::size_t>(q)] = static_cast<std::int32_t>(i);
        forward[static_cast<std::size_t>(q)] = next;
        next = q;
      }
    }
  }
  timed_.setLines(lineOf, forward);
  planner_->setLines(std::move(lineOf), std::move(forward));
  leaving_.assign(stations_.size(), -1);
  // Robots wait only where they leave the dock's ways in and out free: a queue node next to a dock
  // approached along a row excludes the nodes a robot leaving the dock must drive through.
  firstClear_.assign(stations_.size(), 0);
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    const auto& st = stations_[i];
    if (!graph_.valid(st.dock))
      continue;
    // The ways in and out: the dock's neighbours, and the approach's (a robot leaving the dock
    // drives on from the approach sideways, through nodes the queue's head may exclude).
    std::vector<NodeId> ways{st.dock};
    auto addNeighbours = [&](NodeId u) {
      for (const Edge& e : graph_.edges(u))
        ways.push_back(e.to);
      for (NodeId v = 0; static_cast<std::size_t>(v) < graph_.size(); ++v) {
        if (graph_.edge(v, u) != nullptr)
          ways.push_back(v);
      }
    };
    addNeighbours(st.dock);
    if (graph_.valid(st.approach))
      addNeighbours(st.approach);
    std::erase_if(ways,
                  [&](NodeId w) { return std::find(st.queue.begin(), st.queue.end(), w) != st.queue.end(); });
    std::size_t k = 0;
    while (k < st.queue.size() && std::any_of(ways.begin(), ways.end(),
                                              [&](NodeId w) { return graph_.conflicting(w, st.queue[k]); })) {
      ++k;
    }
    firstClear_[i] = std::min(k, st.queue.empty() ? 0 : st.queue.size() - 1);
  }
  std::fill(stationOfDock_.begin(), stationOfDock_.end(), -1);
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    if (graph_.valid(stations_[i].dock)) {
      stationOfDock_[static_cast<std::size_t>(stations_[i].dock)] = static_cast<std::int32_t>(i);
    }
  }
  for (std::size_t r = 0; r < robots(); ++r) {
    const NodeId g = goal_[r];
    goal_[r] = kNoNode;
    setGoal(r, g, priority_[r]);
  }
}

std::vector<std::size_t> TrafficControl::line(NodeId dock) const {
  if (!graph_.valid(dock) || stationOfDock_[static_cast<std::size_t>(dock)] < 0)
    return {};
  return lines_[static_cast<std::size_t>(stationOfDock_[static_cast<std::size_t>(dock)])];
}

void TrafficControl::plannerGoal(std::size_t robot, NodeId goal) {
  target_[robot] = goal;
  if (evadeUntil_[robot] >= 0)
    return;  // takes effect when the evasion ends
  planner_->setGoal(robot, goal);
  plannerPriority(robot);
}

void TrafficControl::plannerPriority(std::size_t robot) {
  // A robot driving off a dock goes first: the robots in line for the dock would otherwise (they
  // have waited longer, so PIBT ranks them higher) push it back onto the dock whenever its way out
  // passes them, and it would never leave.
  planner_->setTaskPriority(robot, priority_[robot] + (leavingDock(robot) ? kLeavingBoost : 0));
}

bool TrafficControl::leavingDock(std::size_t robot) const {
  return std::find(leaving_.begin(), leaving_.end(), static_cast<std::int64_t>(robot)) != leaving_.end();
}

NodeId TrafficControl::standing(std::size_t robot) const {
  return options_.core == PlannerCore::Sipp ? execution_.at(robot) : planner_->positions()[robot];
}

void TrafficControl::leaveLine(std::size_t robot) {
  const auto s = inLine_[robot];
  if (s < 0)
    return;
  auto& l = lines_[static_cast<std::size_t>(s)];
  // The robot whose turn it was keeps the dock until it has driven off it: the next in line
  // waits at the head of the queue instead of pushing into the only way out.
  const NodeId dock = stations_[static_cast<std::size_t>(s)].dock;
  if (!l.empty() && l.front() == robot && graph_.conflicting(standing(robot), dock)) {
    leaving_[static_cast<std::size_t>(s)] = static_cast<std::int64_t>(robot);
    plannerPriority(robot);
  }
  l.erase(std::remove(l.begin(), l.end(), robot), l.end());
  inLine_[robot] = -1;
  planner_->setLine(robot, -1);
  updateLine(static_cast<std::size_t>(s));
}

void TrafficControl::orderLine(std::size_t station) {
  auto& l = lines_[station];
  if (l.size() < 2)
    return;
  const auto& st = stations_[station];
  // Place along the line where the robot stands: dock, approach, then the queue from its head.
  auto place = [&](std::size_t r) -> std::size_t {
    const NodeId v = standing(r);
    if (v == st.dock)
      return 0;
    if (v == st.approach)
      return 1;
    const auto it = std::find(st.queue.begin(), st.queue.end(), v);
    return it == st.queue.end() ? std::numeric_limits<std::size_t>::max()
                                : 2 + static_cast<std::size_t>(it - st.queue.begin());
  };
  auto sorted = l;
  std::stable_sort(sorted.begin(), sorted.end(),
                   [&](std::size_t a, std::size_t b) { return place(a) < place(b); });
  if (sorted != l) {
    l = std::move(sorted);
    updateLine(station);
  }
}

void TrafficControl::updateLine(std::size_t station) {
  const auto& st = stations_[station];
  const auto& l = lines_[station];
  const std::size_t shift = leaving_[station] >= 0 ? 1 : 0;
  for (std::size_t k = 0; k < l.size(); ++k) {
    const std::size_t place = k + shift;
    NodeId g = st.dock;
    if (place > 0 && !st.queue.empty()) {
      g = st.queue[std::min(firstClear_[station] + place - 1, st.queue.size() - 1)];
    }
    plannerGoal(l[k], g);
  }
}

std::size_t TrafficControl::addRobot(NodeId start) {
  execution_.truncateToReleased();
  std::size_t r = 0;
  try {
    r = execution_.addRobot(start);
  } catch (...) {
    replan();  // the planner starts again from the released ends either way
    throw;
  }
  goal_.push_back(kNoNode);
  held_.push_back(0);
  priority_.push_back(0);
  inLine_.push_back(-1);
  target_.push_back(kNoNode);
  stall_.push_back(0);
  lastEnd_.push_back(start);
  evadeUntil_.push_back(-1);
  baseEnds_.emplace_back();
  ready_.push_back(clock_);
  busy_.push_back(0);
  came_.push_back(kNoNode);
  lastGoalAt_.push_back(now_);
  replan();
  return r;
}

bool TrafficControl::setGoal(std::size_t robot, NodeId goal, int priority) {
  if (robot >= robots())
    return false;
  if (goal != kNoNode && (!graph_.valid(goal) || !graph_.isOpen(goal)))
    return false;
  if (goal == goal_[robot] && priority == priority_[robot]) {
    return true;
  }
  leaveLine(robot);
  goal_[robot] = goal;
  priority_[robot] = priority;
  const auto s = goal == kNoNode ? -1 : stationOfDock_[static_cast<std::size_t>(goal)];
  if (s >= 0) {
    lines_[static_cast<std::size_t>(s)].push_back(robot);
    inLine_[robot] = s;
    planner_->setLine(robot, s);
    updateLine(static_cast<std::size_t>(s));
  } else {
    plannerGoal(robot, goal);
  }
  return true;
}

void TrafficControl::setHeld(std::size_t robot, bool held) {
  if (robot >= robots() || (held_[robot] != 0) == held)
    return;
  held_[robot] = held ? 1 : 0;
  if (held) {
    // Plan around where it really is, not where the plan would have taken it.
    if (execution_.at(robot) != execution_.plannedEnd(robot)) {
      execution_.retract(robot);
      replan();
    }
  }
  planner_->setControlled(robot, !held);
}

void TrafficControl::retractStanding(std::size_t robot) {
  if (robot >= robots())
    return;
  execution_.retract(robot, true);
  replan();
}

Report TrafficControl::reached(std::size_t robot, NodeId node) {
  const Report r = execution_.reached(robot, node);
  if (r == Report::Accepted && node == target_[robot])
    lastGoalAt_[robot] = now_;
  if (r == Report::NotReleased || r == Report::UnknownRobot)
    ++stats_.refusedReports;
  // At the end of its base short of where it is being taken: say why the base ended there.
  if (r == Report::Accepted && node == execution_.releasedEnd(robot) && node != target_[robot] &&
      node != goal_[robot]) {
    auto& b = baseEnds_[robot];
    switch (execution_.baseCut(robot)) {
      case BaseCut::Held:
        ++b.held;
        break;
      case BaseCut::PlanEnd:
        ++b.planEnd;
        break;
      case BaseCut::Limit:
        ++b.limit;
        break;
    }
  }
  return r;
}

bool TrafficControl::arrived(std::size_t robot) const {
  return goal_.at(robot) != kNoNode && execution_.at(robot) == goal_[robot];
}

TrafficControl::Need TrafficControl::needsPlanning() const {
  // Plan while a robot on its way has fewer than two nodes planned ahead of where it is. A robot the
  // plan has kept standing for a while (behind one waiting in line, at a closed way) needs the
  // others to move first: more steps now would only plan everyone else far ahead of their robots
  // and force a re-plan, so it asks for a step now and then, not at once.
  Need need = Need::None;
  for (std::size_t r = 0; r < robots(); ++r) {
    if (held_[r] != 0)
      continue;
    // An evasion lasts a number of planned steps: keep planning until it is over. (Planning it at
    // the fleet's pace instead ended the re-planning churn this causes in crowds, but left a robot
    // and a vendor's vehicle standing for good in the mixed-fleet test: docs/algorithms.md.)
    if (evadeUntil_[r] >= 0)
      return Need::Now;
    const NodeId t = target_[r];
    // (A plan that brings the robot back to the node it stands on counts as nothing ahead: after
    // a change of goal the plan starts again from the released end, and a robot released one node
    // on, then planned back, stood for good on a base [A, B, A] that ends where it is.)
    const bool back = execution_.plannedEnd(r) == execution_.at(r);
    if (t != kNoNode && execution_.plannedEnd(r) != t && (execution_.pendingNodes(r) < 2 || back)) {
      if (stall_[r] < options_.standingSteps)
        return Need::Now;
      need = Need::Later;
    }
  }
  return need;
}

int TrafficControl::update() {
  if (options_.core == PlannerCore::Sipp)
    return updateTimed();
  int steps = 0;
  ++sinceStep_;
  freeDocks();  // robots report between planner steps too
  while (steps < options_.maxStepsPerUpdate) {
    const Need need = needsPlanning();
    if (need == Need::None || (need == Need::Later && (steps > 0 || sinceStep_ < options_.standingEvery)))
      break;
    // Do not plan far past a robot that is behind: what it has not been released yet is planned
    // again from where its release ends, and the others around where it really is.
    std::int64_t oldest = -1;
    for (std::size_t r = 0; r < robots(); ++r) {
      const auto s = execution_.nextUnreleasedStep(r);
      if (s >= 0 && (oldest < 0 || s < oldest))
        oldest = s;
    }
    if (oldest >= 0 && lagging(oldest))
      replan();
    // Plan times are needed from the oldest unreleased step on (lagging()): drop those before it.
    forgetStepTimes(oldest >= 0 ? oldest : execution_.plannedSteps());
    before_ = planner_->positions();
    beforeTimedStep();
    execution_.append(planner_->step());
    afterTimedStep();
    afterStep();
    ++steps;
    sinceStep_ = 0;
  }
  stats_.steps += static_cast<std::uint64_t>(steps);
  letLatePass();
  return steps;
}

void TrafficControl::letLatePass() {
  if (options_.letPassBehind > 0) {
    for (std::size_t r = 0; r < robots(); ++r) {
      if (held_[r] == 0 && !execution_.waitingOn(r).empty() && execution_.letPass(r, options_.letPassBehind))
        ++stats_.passes;
    }
  }
}

void TrafficControl::freeDocks() {
  // A dock is free for the next in line once the robot leaving it has *reported* a node clear of
  // it, not once the plan has it there: a re-plan drops what was not released and puts the robot
  // back on the dock in the planner, and a next in line already sent onto the approach (the dock's
  // only way out) then waits for the dock while the robot on it waits for the approach, for ever.
  for (std::size_t i = 0; i < stations_.size(); ++i) {
    const auto q = leaving_[i];
    if (q >= 0 && !graph_.conflicting(execution_.at(static_cast<std::size_t>(q)), stations_[i].dock)) {
      leaving_[i] = -1;
      plannerPriority(static_cast<std::size_t>(q));
      updateLine(i);
    }
  }
}

void TrafficControl::afterStep() {
  const auto now = evadeClock();
  for (std::size_t i = 0; i < stations_.size(); ++i)
    orderLine(i);
  freeDocks();
  for (std::size_t r = 0; r < robots(); ++r) {
    if (evadeUntil_[r] >= 0 && now >= evadeUntil_[r]) {
      evadeUntil_[r] = -1;
      planner_->setGoal(r, target_[r]);
    }
  }
  for (std::size_t r = 0; r < robots(); ++r) {
    const NodeId t = evadeUntil_[r] >= 0 ? planner_->goal(r) : target_[r];
    const auto& pos = planner_->positions();
    if (held_[r] != 0 || t == kNoNode || pos[r] == t) {
      stall_[r] = 0;
      lastEnd_[r] = execution_.plannedEnd(r);
      continue;
    }
    if (busy_[r] != 0)
      continue;  // still driving in the plan: neither moved nor standing this step
    // Planned to stand still this step?
    const bool moved = execution_.plannedEnd(r) != kNoNode && lastEnd_[r] != execution_.plannedEnd(r);
    lastEnd_[r] = execution_.plannedEnd(r);
    stall_[r] = moved ? 0 : stall_[r] + 1;
    if (stall_[r] >= options_.evadeAfter) {
      stall_[r] = 0;
      clearWayFor(r);
    }
  }
}

void TrafficControl::clearWayFor(std::size_t robot) {
  const NodeId goal = evadeUntil_[robot] >= 0 ? planner_->goal(robot) : target_[robot];
  if (goal == kNoNode)
    return;
  // Read as far as the search needs (a whole table per stalled robot's goal was a sixth of the
  // update at 1,000 robots).
  auto& table = planner_->distances();
  const auto dist = [&](NodeId x) { return static_cast<double>(table.distance(x, goal)); };
  const auto& pos = planner_->positions();
  // Its next few nodes on a shortest way to its goal.
  std::vector<NodeId> path;
  NodeId v = pos[robot];
  for (int k = 0; k < options_.evadeLookahead && v != goal; ++k) {
    NodeId best = kNoNode;
    double bestCost = dist(v);
    for (const Edge& e : graph_.edges(v)) {
      if (!graph_.passable(v, e))
        continue;
      const double c = e.cost() + dist(e.to);
      // The tables hold floats: a way's next node can come out a few ulps dearer than the node's
      // own distance (1e-5 relative covers a float's rounding on both sides).
      if (c < bestCost + 1e-5 * (1.0 + std::abs(bestCost)) && (best == kNoNode || c < bestCost)) {
        best = e.to;
        bestCost = c;
      }
    }
    if (best == kNoNode)
      break;
    path.push_back(best);
    v = best;
  }
  auto blocks = [&](NodeId w) {
    return std::any_of(path.begin(), path.end(), [&](NodeId p) { return graph_.conflicting(p, w); });
  };
  // How many robots stand on or exclude each node: a robot is sent only where it can drive now, not
  // through or into what another robot excludes (a refuge behind a robot parked in its dock is no
  // refuge: the robot sent there stood still, and the one it was to make room for with it).
  std::vector<int> cover(graph_.size(), 0);
  const auto footprint = [&](NodeId at, int delta) {
    cover[static_cast<std::size_t>(at)] += delta;
    for (const NodeId w : graph_.conflicts(at))
      cover[static_cast<std::size_t>(w)] += delta;
  };
  for (std::size_t q = 0; q < robots(); ++q)
    footprint(pos[q], 1);
  for (std::size_t q = 0; q < robots(); ++q) {
    if (q == robot || held_[q] != 0 || evadeUntil_[q] >= 0 || !blocks(pos[q]))
      continue;
    footprint(pos[q], -1);  // its own footprint is no obstacle to it
    // The nearest node (in edges) clear of that path, away from the stalled robot.
    std::vector<NodeId> frontier{pos[q]};
    std::vector<std::uint8_t> seen(graph_.size(), 0);
    seen[static_cast<std::size_t>(pos[q])] = 1;
    NodeId refuge = kNoNode;
    for (int depth = 0; depth < 12 && refuge == kNoNode && !frontier.empty(); ++depth) {
      std::vector<NodeId> next;
      for (NodeId u : frontier) {
        for (const Edge& e : graph_.edges(u)) {
          const auto w = static_cast<std::size_t>(e.to);
          if (!graph_.passable(u, e) || seen[w] != 0)
            continue;
          seen[w] = 1;
          if (cover[w] > 0)
            continue;  // not through the stalled robot or any other
          if (!blocks(e.to) && e.to != goal && refuge == kNoNode)
            refuge = e.to;
          next.push_back(e.to);
        }
      }
      frontier = std::move(next);
    }
    footprint(pos[q], 1);
    if (refuge == kNoNode)
      continue;
    planner_->setGoal(q, refuge);
    evadeUntil_[q] = evadeClock() + std::llround(1000.0 * options_.evadeSeconds);
    ++stats_.evasions;
  }
}

void TrafficControl::replan() {
  const auto ends = execution_.truncateToReleased();
  for (std::size_t r = 0; r < robots(); ++r) {
    came_[r] = execution_.releasedFrom(r);
  }
  planner_->reset(ends, came_);
  ++stats_.replans;
  lastTimedPlan_ = -1e18;  // the timed core plans again at the next update
  // Everyone decides again from where its release ends, facing the way it came.
  std::fill(ready_.begin(), ready_.end(), clock_);
}

std::int64_t TrafficControl::evadeClock() const {
  return std::llround(1000.0 * clock_);  // ms of plan time
}

bool TrafficControl::lagging(std::int64_t oldest) const {
  const std::int64_t k = oldest - stepTimeFirst_;
  const double at = k >= 0 && k < static_cast<std::int64_t>(stepTime_.size())
                        ? stepTime_[static_cast<std::size_t>(k)]
                        : clock_;
  return clock_ - at >= kStepSeconds * static_cast<double>(options_.maxLag);
}

void TrafficControl::forgetStepTimes(std::int64_t before) {
  // In batches, so the record is not shifted every step; it stays bounded however long the run.
  const std::int64_t drop =
      std::min<std::int64_t>(before - stepTimeFirst_, static_cast<std::int64_t>(stepTime_.size()));
  if (drop >= 1024) {
    stepTime_.erase(stepTime_.begin(), stepTime_.begin() + drop);
    stepTimeFirst_ += drop;
  }
}

void TrafficControl::beforeTimedStep() {
  double earliest = std::numeric_limits<double>::infinity();
  for (std::size_t r = 0; r < robots(); ++r) {
    if (held_[r] == 0)
      earliest = std::min(earliest, ready_[r]);
  }
  if (earliest != std::numeric_limits<double>::infinity())
    clock_ = std::max(clock_, earliest);
  for (std::size_t r = 0; r < robots(); ++r)
    busy_[r] = held_[r] == 0 && ready_[r] > clock_ + options_.timedQuantum ? 1 : 0;
  planner_->setBusy(busy_);
}

void TrafficControl::afterTimedStep() {
  const std::vector<NodeId>& before = before_;
  const auto step = static_cast<std::size_t>(execution_.plannedSteps() - stepTimeFirst_);
  if (stepTime_.size() <= step)
    stepTime_.resize(step + 1, clock_);
  stepTime_[step] = clock_;
  const auto& pos = planner_->positions();
  for (std::size_t r = 0; r < robots(); ++r) {
    if (held_[r] != 0) {
      ready_[r] = clock_;
    } else if (busy_[r] == 0) {
      if (pos[r] == before[r]) {
        ready_[r] = clock_ + options_.timedWait;
        continue;
      }
      const Edge* e = graph_.edge(before[r], pos[r]);
      double d = e != nullptr ? e->duration : 1.0;
      if (options_.turnTime && came_[r] != kNoNode)
        d += options_.turnTime(came_[r], before[r], pos[r]);
      ready_[r] = clock_ + d;
      came_[r] = before[r];
    }
  }
}

void TrafficControl::graphChanged() {
  planner_->graphChanged();  // its cached distances still route through what was closed
  timed_.graphChanged();
  replan();
}

void TrafficControl::setNodeCost(std::vector<float> cost) {
  if (options_.core == PlannerCore::Sipp)
    timed_.setNodeCost(std::move(cost));
  else
    planner_->setNodeCost(std::move(cost));
}

std::span<const float> TrafficControl::nodeCost() const {
  if (options_.core == PlannerCore::Sipp)
    return timed_.nodeCost();
  return planner_->distances().nodeCost();
}

std::string TrafficControl::explain(std::size_t robot) const {
  const NodeId at = execution_.at(robot);
  std::ostringstream os;
  os << "at node " << at;
  if (graph_.valid(at))
    os << " (" << graph_.position(at).x << ", " << graph_.position(at).y << ")";
  os << ", goal " << goal_.at(robot) << ", target " << target_.at(robot) << (held(robot) ? ", held" : "")
     << ", planned " << execution_.pendingNodes(robot) << " nodes ahead, released to "
     << execution_.releasedEnd(robot) << " [" << execution_.describe(robot) << "], waiting on";
  const auto waits = waitingOn(robot);
  if (waits.empty())
    os << " nobody";
  for (auto q : waits)
    os << " " << q << "@" << execution_.at(q);
  os << "; ways out:";
  if (graph_.valid(at)) {
    for (const Edge& e : graph_.edges(at)) {
      if (!graph_.passable(at, e))
        continue;
      os << " " << e.to;
      for (std::size_t q = 0; q < robots(); ++q) {
        // A held robot (docking, faulted, held by a person) is planned round, not pushed.
        if (q != robot && graph_.conflicting(e.to, execution_.at(q)))
          os << " [" << q << (held(q) ? " held" : "") << "]";
      }
    }
  }
  return os.str();
}

}  // namespace fleet::traffic
