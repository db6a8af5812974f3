// The traffic layer's timed core (PlannerCore::Sipp): every robot's timed path from where its
// release ends, by windowed prioritized planning over safe intervals, appended to the execution
// one move at a time in the order of the moves' times.

#include <algorithm>
#include <tuple>

#include "fleet/traffic/traffic_control.hpp"

namespace fleet::traffic {

const char* toString(PlannerCore c) {
  return c == PlannerCore::Sipp ? "sipp" : "pibt";
}

std::optional<PlannerCore> plannerCoreFrom(std::string_view name) {
  if (name == "pibt")
    return PlannerCore::Pibt;
  if (name == "sipp")
    return PlannerCore::Sipp;
  return std::nullopt;
}

int TrafficControl::updateTimed() {
  if (!nowGiven_)
    now_ += options_.tick;
  freeDocks();
  for (std::size_t i = 0; i < stations_.size(); ++i)
    orderLine(i);
  // Plan again when a robot on its way runs short of planned nodes (soon), or every
  // `replanEvery` s while a robot is not planned to its target (a way that was shut may be open).
  bool shortOf = false;
  bool unplanned = false;
  for (std::size_t r = 0; r < robots(); ++r) {
    if (held_[r] != 0 || target_[r] == kNoNode || execution_.plannedEnd(r) == target_[r])
      continue;
    unplanned = true;
    shortOf = shortOf || execution_.pendingNodes(r) < 2;
  }
  const double since = now_ - lastTimedPlan_;
  int moves = 0;
  if ((shortOf && since >= options_.replanAtLeast) || (unplanned && since >= options_.replanEvery)) {
    moves = planTimed();
    lastTimedPlan_ = now_;
  }
  letLatePass();
  return moves;
}

int TrafficControl::planTimed() {
  const auto ends = execution_.truncateToReleased();
  ++stats_.replans;
  std::vector<PlanRequest> req(robots());
  for (std::size_t r = 0; r < robots(); ++r) {
    auto& q = req[r];
    // What is released is driven as it is, from its last report now.
    const auto route = execution_.releasedRoute(r);
    double t = now_;
    q.committed.push_back({route.front(), t, t, t});
    for (std::size_t k = 1; k < route.size(); ++k) {
      // Its duration whether the edge is open or closed since it was released.
      double duration = 1.0;
      for (const Edge& e : graph_.edges(route[k - 1])) {
        if (e.to == route[k])
          duration = e.duration;
      }
      double turn = 0.0;  // (the first edge's turn is not known: where it came from is not kept)
      if (k >= 2 && options_.turnTime)
        turn = options_.turnTime(route[k - 2], route[k - 1], route[k]);
      const double enter = t + turn;
      const double arrive = enter + duration;
      q.committed.back().leave = enter;
      q.committed.push_back({route[k], enter, arrive, arrive});
      t = arrive;
    }
    if (q.committed.size() < 2)
      q.committed.clear();
    q.at = ends[r];
    q.cameFrom = execution_.releasedFrom(r);
    q.ready = t;
    q.held = held_[r] != 0;
    q.line = inLine_[r];
    q.goal = q.held ? kNoNode : target_[r];
    q.priority = priority_[r] + (leavingDock(r) ? kLeavingBoost : 0);
    q.waiting = now_ - lastGoalAt_[r];
  }
  const auto paths = timed_.plan(req);
  // The moves within the window (conflict-free by construction), in time order.
  const double until = timed_.windowEnd();
  std::vector<std::tuple<double, std::size_t, NodeId>> moves;
  for (std::size_t r = 0; r < paths.size(); ++r) {
    for (std::size_t k = 1; k < paths[r].size(); ++k) {
      if (paths[r][k].enter < until)
        moves.emplace_back(paths[r][k].enter, r, paths[r][k].node);
    }
  }
  std::sort(moves.begin(), moves.end());

  int appended = 0;
  for (const auto& [time, r, node] : moves) {
    try {
      execution_.appendMove(r, node);
      ++appended;
    } catch (const PlanStepError&) {
      ++stats_.refusedMoves;
      break;
    }
  }
  stats_.steps += static_cast<std::uint64_t>(appended);
  return appended;
}

}  // namespace fleet::traffic
