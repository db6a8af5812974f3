#include "fleet/traffic/pibt.hpp"

#include "pibt_index.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace fleet::traffic {

using pibt_detail::idx;

bool Pibt::before(std::int32_t a, std::int32_t b) const {
  const auto ia = idx(a);
  const auto ib = idx(b);
  const bool ea = escalatedAt_[ia] >= 0;
  const bool eb = escalatedAt_[ib] >= 0;
  if (ea != eb) {
    return ea;
  }
  if (ea) {
    if (escalatedAt_[ia] != escalatedAt_[ib]) {
      return escalatedAt_[ia] < escalatedAt_[ib];
    }
    if (escalationDraw_[ia] != escalationDraw_[ib]) {
      return escalationDraw_[ia] < escalationDraw_[ib];
    }
    return a < b;
  }
  if (task_[ia] != task_[ib]) {
    return task_[ia] > task_[ib];
  }
  // An agent with somewhere to go before one without (which would only stay where it is).
  const bool ga = goal_[ia] != kNoNode;
  const bool gb = goal_[ib] != kNoNode;
  if (ga != gb) {
    return ga;
  }
  if (elapsed_[ia] != elapsed_[ib]) {
    return elapsed_[ia] > elapsed_[ib];
  }
  if (epsilon_[ia] != epsilon_[ib]) {
    return epsilon_[ia] > epsilon_[ib];
  }
  return a < b;
}

bool Pibt::available(std::int32_t agent, NodeId u) const {
  if (grid_) {
    const std::int32_t r = reservedBy_[idx(u)];
    return r < 0 || r == agent;
  }
  const std::int32_t r = reservedBy_[idx(u)];
  if (r >= 0 && r != agent) {
    return false;
  }
  for (const NodeId w : graph_.conflicts(u)) {
    const std::int32_t o = reservedBy_[idx(w)];
    if (o >= 0 && o != agent) {
      return false;
    }
  }
  return true;
}

bool Pibt::leavesAncestorsAlone(std::int32_t agent, std::int32_t parent, NodeId u) const {
  if (grid_) {
    // The one swap possible on a grid: back into the node of the agent pushing this one.
    return parent < 0 || u != now_[idx(parent)];
  }
  // With conflict sets an agent may push several others; if a later one fails, the pusher stays
  // where it is, so nobody pushed on its behalf may have moved into what it excludes. Keeping every
  // agent still being planned out of reach also rules out swaps with any of them.
  const auto touches = [&](NodeId w) {
    const std::int32_t o = agentAt_[idx(w)];
    return o >= 0 && o != agent && onStack_[idx(o)] != 0;
  };
  if (touches(u)) {
    return false;
  }
  for (const NodeId w : graph_.conflicts(u)) {
    if (touches(w)) {
      return false;
    }
  }
  return true;
}

bool Pibt::closesCycle(std::int32_t agent, NodeId u) {
  // Moving into u follows whoever stands on what u excludes; follow the agents already decided
  // (their next node is known) and see whether the chain comes back to `agent`.
  ++stamp_;
  search_.clear();
  // From u itself, `agent` only meets its own node (a roadmap node excludes its neighbours): that
  // is not following anyone. Further along the chain, meeting it closes a cycle.
  const auto push = [&](NodeId w, bool first) {
    const std::int32_t o = agentAt_[idx(w)];
    if (o < 0 || visited_[idx(o)] == stamp_) {
      return false;
    }
    if (o == agent) {
      return !first;
    }
    visited_[idx(o)] = stamp_;
    const NodeId nx = next_[idx(o)];
    if (nx != kNoNode && nx != now_[idx(o)]) {
      search_.push_back(o);
    }
    return false;
  };
  const auto expand = [&](NodeId v, bool first) {
    if (push(v, first)) {
      return true;
    }
    if (!grid_) {
      for (const NodeId w : graph_.conflicts(v)) {
        if (push(w, first)) {
          return true;
        }
      }
    }
    return false;
  };
  if (expand(u, true)) {
    return true;
  }
  while (!search_.empty()) {
    const std::int32_t o = search_.back();
    search_.pop_back();
    if (expand(next_[idx(o)], false)) {
      return true;
    }
  }
  return false;
}

bool Pibt::plan(std::int32_t agent, std::int32_t parent, std::size_t depth) {
  const auto a = idx(agent);
  const NodeId from = now_[a];
  onStack_[a] = 1;
  Candidate* c = candidates_.data() + depth * stride_;
  std::size_t m = 0;
  const float* table = table_[a];
  const NodeId back = prev_[a];
  const bool straight = options_.preferStraight && back != kNoNode;
  const Vec2 heading = straight ? graph_.position(from) - graph_.position(back) : Vec2{};
  // With a heading table: the edge it arrived by (its heading), -1 when unknown.
  const float* surcharge = surcharge_[a];
  const std::int64_t arrived =
      surcharge != nullptr && back != kNoNode ? heading_->edgeBetween(back, from) : -1;
  // Standing: the cost-to-go the way it faces; facing no known way, that of its best way out.
  float standing = arrived >= 0 && table[idx(from)] > 0.0F ? surcharge[arrived] : 0.0F;
  // On its goal (distance 0) it has nowhere to turn to: standing costs nothing.
  if (surcharge != nullptr && arrived < 0 && table[idx(from)] != DistanceTable::kUnreachable &&
      table[idx(from)] > 0.0F) {
    standing = DistanceTable::kUnreachable;
    const auto es = graph_.edges(from);
    for (std::size_t k = 0; k < es.size(); ++k) {
      if (graph_.passable(from, es[k]) && table[idx(es[k].to)] != DistanceTable::kUnreachable) {
        standing = std::min(standing, static_cast<float>(es[k].cost()) + table[idx(es[k].to)] +
                                          surcharge[heading_->outEdge(from, k)] - table[idx(from)]);
      }
    }
    standing = standing == DistanceTable::kUnreachable ? 0.0F : std::max(0.0F, standing);
  }
  const auto add = [&](NodeId v, std::size_t out) {
    float d = table != nullptr ? table[idx(v)] : (v == from ? 0.0F : 1.0F);
    if (surcharge != nullptr && d != DistanceTable::kUnreachable) {
      if (v == from) {
        d += standing;
      } else {
        const std::size_t e = heading_->outEdge(from, out);
        d += surcharge[e] +
             (arrived >= 0 ? heading_->turn(static_cast<std::size_t>(arrived), from, out) : 0.0F);
      }
    }
    const std::int32_t o = agentAt_[idx(v)];
    const auto occupied = static_cast<std::uint32_t>(o >= 0 && o != agent);
    // Making a robot move costs it a move (PibtOptions::occupiedCost).
    if (options_.occupiedCost > 0.0F && v != from && d != DistanceTable::kUnreachable &&
        standingOn(v, agent) >= 0) {
      d += options_.occupiedCost;
    }
    // Ties go to free nodes first, then (if asked) to the smallest turn, then at random (the seed
    // makes the random part repeatable).
    std::uint32_t turn = 0;
    if (straight && v != from) {
      const Vec2 step = graph_.position(v) - graph_.position(from);
      const double cosine = heading.dot(step) / std::max(1e-9, heading.norm() * step.norm());
      turn = static_cast<std::uint32_t>(
          std::lround(std::acos(std::clamp(cosine, -1.0, 1.0)) * 4.0 / std::numbers::pi));
    }
    const auto draw = static_cast<std::uint32_t>(random() >> 33);
    c[m++] = Candidate{
        v, d,
        options_.preferStraight ? (occupied << 31) | (turn << 28) | (draw >> 3) : (occupied << 31) | draw};
  };
  add(from, 0);
  const auto out = graph_.edges(from);
  for (std::size_t k = 0; k < out.size(); ++k) {
    const Edge& e = out[k];
    if (!lineAllows(a, from, e.to)) {
      continue;  // in its line on one of the line's nodes: forward or nowhere
    }
    // Leaving a closed node is allowed (a robot stranded on it must get off); entering one is not.
    if (e.open && graph_.isOpen(e.to)) {
      add(e.to, k);
    }
  }
  if (forcedGroup_[a] >= 0) {
    // On a way out of a knot: its move this step is fixed (staying, if it cannot be made).
    c[0] = Candidate{forced_[a][forcedAt_[a] + 1], 0.0F, 0};
    m = 1;
  }
  for (std::size_t i = 1; i < m; ++i) {
    const Candidate x = c[i];
    std::size_t j = i;
    const float tol = options_.tieTolerance;
    while (j > 0 && (x.distance < c[j - 1].distance - tol ||
                     (x.distance <= c[j - 1].distance + tol && x.tieBreak < c[j - 1].tieBreak))) {
      c[j] = c[j - 1];
      --j;
    }
    c[j] = x;
  }

  for (std::size_t k = 0; k < m; ++k) {
    const NodeId u = c[k].node;
    if (!available(agent, u)) {
      continue;
    }
    if (u != from) {
      if (!leavesAncestorsAlone(agent, parent, u)) {
        continue;
      }
      if (options_.rotations == Rotations::kAvoid && closesCycle(agent, u)) {
        continue;
      }
    }
    next_[a] = u;
    reservedBy_[idx(u)] = agent;
    if (u == from) {
      onStack_[a] = 0;
      return true;
    }
    // Priority inheritance: everyone undecided on what u excludes has to make room first.
    const auto inherit = [&](NodeId w) {
      const std::int32_t o = agentAt_[idx(w)];
      if (o < 0 || o == agent || next_[idx(o)] != kNoNode) {
        return true;
      }
      if (plan(o, agent, depth + 1)) {
        return true;
      }
      if (!grid_) {
        refused_.push_back(o);
      }
      return false;
    };
    bool ok = inherit(u);
    if (!grid_) {
      for (auto w = graph_.conflicts(u).begin(); ok && w != graph_.conflicts(u).end(); ++w) {
        ok = inherit(*w);
      }
    }
    // Someone pushed further down may have had to stay on what u excludes.
    if (ok && available(agent, u)) {
      onStack_[a] = 0;
      return true;
    }
    if (reservedBy_[idx(u)] == agent) {
      reservedBy_[idx(u)] = -1;
    }
    next_[a] = kNoNode;
  }
  next_[a] = from;
  reservedBy_[idx(from)] = agent;
  onStack_[a] = 0;
  return false;
}

const std::vector<NodeId>& Pibt::step() {
  const std::size_t n = now_.size();
  distances_.reserve(n + 1);
  if (options_.detourAfter > 0) {
    planDetours();
  }
  order_.clear();
  for (std::size_t i = 0; i < n; ++i) {
    if (goal_[i] == kNoNode || controlled_[i] == 0) {
      table_[i] = nullptr;
    } else {
      // Searched as far as it is read: here and the next nodes (settleTables).
      table_[i] = detour_[i].empty() ? distances_.partialTo(goal_[i]) : detour_[i].data();
      settleTable(i, 1);
    }
    if (rebaseProgress_ && table_[i] != nullptr && detour_[i].empty()) {
      const float d = table_[i][idx(now_[i])];
      if (d != DistanceTable::kUnreachable) {
        best_[i] = d;
      }
    }
    if (controlled_[i] != 0 && !busy(i)) {
      next_[i] = kNoNode;
      order_.push_back(static_cast<std::int32_t>(i));
    } else {
      next_[i] = now_[i];
      reservedBy_[idx(now_[i])] = static_cast<std::int32_t>(i);
    }
  }
  rebaseProgress_ = false;
  // Agents on a way out of a knot first: their moves were found with everyone else standing.
  std::sort(order_.begin(), order_.end(), [this](std::int32_t a, std::int32_t b) {
    const bool fa = forcedGroup_[idx(a)] >= 0;
    const bool fb = forcedGroup_[idx(b)] >= 0;
    return fa != fb ? fa : before(a, b);
  });
  findHeadingTables();
  for (const std::int32_t i : order_) {
    if (next_[idx(i)] == kNoNode) {
      plan(i, -1, 0);
      reconsiderRefused();
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    reservedBy_[idx(next_[i])] = -1;
  }
  if (options_.rotations != Rotations::kAllow) {
    stats_.rotationStops += rotationPass_.cancel(now_, next_);
  }
  for (std::size_t i = 0; i < n; ++i) {
    agentAt_[idx(now_[i])] = -1;
  }
  for (std::size_t i = 0; i < n; ++i) {
    const bool counted = !busy(i);
    if (counted)
      still_[i] = next_[i] == now_[i] ? still_[i] + 1 : 0;
    if (next_[i] != now_[i])
      prev_[i] = now_[i];
    now_[i] = next_[i];
    agentAt_[idx(now_[i])] = static_cast<std::int32_t>(i);
    if (counted)
      updateProgress(i);
  }
  advanceForced();
  settleTables();  // the blockers' search reads around where the agents are now
  if (options_.escapeAfter > 0) {
    escapeDeadlocks();
  }
  ++stats_.steps;
  return now_;
}

void Pibt::findHeadingTables() {
  if (!heading_) {
    return;
  }
  const std::size_t n = now_.size();
  // Only a goal's own table has a heading table (a detour's way differs).
  const auto wants = [&](std::size_t i) { return table_[i] != nullptr && detour_[i].empty(); };
  // The agents deciding this step first, by priority, then those still driving.
  goals_.clear();
  for (const std::int32_t i : order_) {
    if (wants(idx(i))) {
      goals_.push_back(goal_[idx(i)]);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (wants(i) && busy(i)) {
      goals_.push_back(goal_[i]);
    }
  }
  heading_->want(goals_);
  heading_->work(options_.headingWorkPerStep);
  for (std::size_t i = 0; i < n; ++i) {
    surcharge_[i] = wants(i) ? heading_->find(goal_[i]) : nullptr;
  }
}

void Pibt::reconsiderRefused() {
  // A pushed agent that could not make room was left standing (PIBT's rule), so the pushers tried
  // their other nodes with it there. On a plain grid that agent has (almost) no move left of its
  // own: every neighbour was taken or held by one that could not move either. With conflict sets it
  // only had no move clear of what its pusher wanted, which reaches past its neighbours: every move
  // of a robot on the lane beside a dock's approach still excludes the approach, yet two of them
  // take it clear. Kept standing, it never made its own move while the robot leaving the dock, first
  // by priority, pushed it every step: both stood for good (full stack, seed 5: r20
  // beside P-5's approach with free ways on to D-4, r7 on P-5's dock and r11 in its queue, 2,200 s).
  // Now, once the pusher's search is over, such an agent is undecided again and plans in its own
  // turn. Nobody relies on its standing: every node reserved since was checked against its node,
  // and whoever takes what it excludes pushes it first, so it can still stay.
  for (const std::int32_t o : refused_) {
    const auto a = idx(o);
    if (next_[a] == now_[a] && reservedBy_[idx(now_[a])] == o) {
      reservedBy_[idx(now_[a])] = -1;
      next_[a] = kNoNode;
    }
  }
  refused_.clear();
}

void Pibt::updateProgress(std::size_t i) {
  const bool atGoal = goal_[i] != kNoNode && now_[i] == goal_[i];
  // A place in its station's line is where it waits, not where it is going: its steps go on
  // counting there, so through traffic does not take the place ahead of it every time it frees.
  elapsed_[i] = (goal_[i] == kNoNode || (atGoal && !onOwnLine(i, now_[i]))) ? 0 : elapsed_[i] + 1;
  const float d = table_[i] != nullptr ? table_[i][idx(now_[i])] : DistanceTable::kUnreachable;
  if (controlled_[i] == 0 || d == DistanceTable::kUnreachable) {
    // No goal, no route to it, or not ours to move: nothing to escape from.
    stalled_[i] = 0;
    tries_[i] = 0;
    escalatedAt_[i] = -1;
    return;
  }
  if (d < best_[i]) {
    best_[i] = d;
    stalled_[i] = 0;
    tries_[i] = 0;
  } else {
    ++stalled_[i];
  }
  if (escalatedAt_[i] < 0) {
    return;
  }
  if (atGoal || d <= escalationDistance_[i] - static_cast<float>(options_.escapeProgress)) {
    escalatedAt_[i] = -1;
  } else if (stalled_[i] == 0) {
    escalationIdle_[i] = 0;
  } else if (++escalationIdle_[i] >= options_.escapeAfter) {
    // Escalated and still stuck: someone else on its cycle has to go first (escapeDeadlocks).
    escalatedAt_[i] = -1;
    ++stats_.escalationRequeues;
  }
}

}  // namespace fleet::traffic
