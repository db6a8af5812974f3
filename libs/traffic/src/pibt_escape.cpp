// Pibt's way out of knots PIBT cannot leave on its own: the wait-for graph (blocker), the escape
// (escalating one agent of a knot), the untangling search over a few steps of a knot's agents, and
// The forced moves it finds (pibt.hpp: "Escape" and "Untangling" of its three additions).

#include <algorithm>
#include <span>

#include "fleet/traffic/pibt.hpp"
#include "fleet/traffic/untangle.hpp"
#include "pibt_index.hpp"

namespace fleet::traffic {

using pibt_detail::idx;

std::int32_t Pibt::blocker(std::size_t i) const {
  // The agent standing where i would go if it were alone: its nearest neighbour to the goal.
  const float* table = table_[i];
  if (table == nullptr || controlled_[i] == 0) {
    return -1;
  }
  const NodeId from = now_[i];
  NodeId want = from;
  float best = table[idx(from)];
  for (const Edge& e : graph_.edges(from)) {
    if (e.open && graph_.isOpen(e.to) && table[idx(e.to)] < best) {
      best = table[idx(e.to)];
      want = e.to;
    }
  }
  if (want == from) {
    return -1;
  }
  const std::int32_t o = agentAt_[idx(want)];
  if (o >= 0 || grid_) {
    return o;
  }
  for (const NodeId w : graph_.conflicts(want)) {
    const std::int32_t c = agentAt_[idx(w)];
    if (c >= 0 && idx(c) != i) {
      return c;
    }
  }
  return -1;
}

void Pibt::escapeDeadlocks() {
  // A stall PIBT cannot leave on its own is a cycle of agents each waiting for the next one's node
  // (a dead-end spur: the agent inside wants out through the one at the entrance, which wants in).
  // Priority inheritance only ever pushes the lower-priority side, which has nowhere to go, so the
  // cycle stands for ever. Escalating one member (the one escalated least since it last made
  // progress, then the one of lowest priority) reverses who yields. Queues and jams, where agents
  // wait behind others that are themselves moving or waiting elsewhere, have no such cycle and keep
  // PIBT's own order, and so does a head-on meeting PIBT is already resolving (the lower agent backs
  // out, moving every step): only a cycle of agents that have all stood still for escapeAfter steps
  // counts. (Escalating every agent stalled that long, or every stalled cycle, cost 15-25 % of the
  // throughput at 1,000 agents on warehouse-10-20-10-2-1: it reversed resolutions under way.)
  constexpr std::size_t kMaxChain = 64;
  const std::size_t n = now_.size();
  // Knots are searched on roadmaps only (see below), at most `limit` agents at a time.
  const bool untangling = !grid_ && options_.untangleGroup >= 2;
  const std::size_t limit =
      std::min<std::size_t>(kMaxUntangleGroup, static_cast<std::size_t>(std::max(options_.untangleGroup, 0)));
  ++stamp_;
  const std::uint32_t seen = stamp_;
  for (std::size_t s = 0; s < n; ++s) {
    // Standing still, not "no closer": a robot sent out of another's way gets a new goal every few
    // steps (TrafficControl's evasion), which restarts its progress but not its standing.
    if (still_[s] < options_.escapeAfter || escalatedAt_[s] >= 0 || forcedGroup_[s] >= 0 ||
        visited_[s] == seen) {
      continue;
    }
    chain_.clear();
    std::int32_t cur = static_cast<std::int32_t>(s);
    std::size_t first = 0;
    bool cycle = false;
    while (chain_.size() < kMaxChain) {
      if (visited_[idx(cur)] == seen) {
        // Back on this walk's own path: the cycle is the part from there on. Met an earlier walk:
        // whatever cycle lies ahead was handled by that walk.
        const auto it = std::find(chain_.begin(), chain_.end(), cur);
        if (it != chain_.end()) {
          first = static_cast<std::size_t>(it - chain_.begin());
          cycle = chain_.size() - first >= 2;
        }
        break;
      }
      visited_[idx(cur)] = seen;
      chain_.push_back(cur);
      cur = blocker(idx(cur));
      if (cur < 0) {
        break;
      }
    }
    // A chain can also end at an agent content where it stands (at its goal, or without one: it
    // waits for nobody). On a plain grid priority inheritance pushes it off if it can move at all.
    // With conflict sets it may have no single move clear of the one waiting on it (a robot parked
    // in a dock whose only way out the robot on the lane in front excludes, that robot wanting
    // past the dock): the chain stands for ever, a knot like a cycle, and escalating one of its
    // agents changes nothing. Its tail (the content agent and those waiting on it) is searched;
    // The content agent does not count, it only makes room. (Full stack: r7 and r1
    // head-on in front of the parking row for 830 s, r6 parked across every way west.)
    if (!cycle) {
      const auto end = idx(chain_.back());
      const bool content =
          cur < 0 && controlled_[end] != 0 && (goal_[end] == kNoNode || now_[end] == goal_[end]);
      if (!untangling || !content || chain_.size() < 2) {
        continue;
      }
      first = chain_.size() - std::min(chain_.size(), limit);
    }
    std::int32_t pick = -1;
    bool anyEscalated = false;
    bool standing = true;
    for (std::size_t k = first; k < chain_.size(); ++k) {
      const std::int32_t m = chain_[k];
      anyEscalated = anyEscalated || escalatedAt_[idx(m)] >= 0 || forcedGroup_[idx(m)] >= 0;
      standing = standing && still_[idx(m)] >= options_.escapeAfter;
      // (The content end of a chain wants nothing: escalating it would not make it move.)
      if ((cycle || k + 1 < chain_.size()) && (pick < 0 || tries_[idx(m)] < tries_[idx(pick)] ||
                                               (tries_[idx(m)] == tries_[idx(pick)] && before(pick, m)))) {
        pick = m;
      }
    }
    if (anyEscalated || !standing) {
      continue;
    }
    const std::span<const std::int32_t> knot(chain_.data() + first, chain_.size() - first);
    // On a plain grid a node excludes only itself, so the agent in the escalated one's way can
    // always clear it in one move if it can move at all: escalation is enough there, and the
    // search's one-move-at-a-time ways out cost throughput (1,000 agents on
    // warehouse-10-20-10-2-1: 5.36 goals per step against 5.44).
    //
    // In a chain only the agent waiting on the content one counts: the search stops when that one
    // is closer to its goal. An agent further back coming closer proves nothing: counting r1 too,
    // r7 tucked into the empty dock beside the lane, r1 gained a node, still short of r6's
    // footprint, and the two swapped places back and forth.
    const std::span<const std::int32_t> counting =
        cycle ? knot : std::span<const std::int32_t>(chain_.data() + chain_.size() - 2, 1);
    if (untangling && knot.size() <= limit && untangleKnot(knot, counting)) {
      continue;
    }
    // The fallback for a chain too: the one escalated goes first and keeps trying to push, and the
    // chain counts as handled (no search every step) until it drops back.
    escalate(idx(pick));
  }
}

void Pibt::escalate(std::size_t p) {
  escalatedAt_[p] = static_cast<std::int64_t>(stats_.steps);
  escalationDraw_[p] = random();
  escalationDistance_[p] = table_[p][idx(now_[p])];
  escalationIdle_[p] = 0;
  ++tries_[p];
  ++stats_.escalations;
}

bool Pibt::untangleKnot(std::span<const std::int32_t> knot, std::span<const std::int32_t> counting) {
  // Escalating one member of the knot makes it plan first, but on a roadmap the one in its way may
  // have no single move that clears what it needs (every neighbour of a lane node in front of a
  // dock is still excluded by the dock's exit): search a few steps of the knot's agents instead,
  // and if that finds nothing, of the agents standing in their way too.
  const std::size_t limit =
      std::min<std::size_t>(kMaxUntangleGroup, static_cast<std::size_t>(options_.untangleGroup));
  std::vector<std::int32_t> group(knot.begin(), knot.end());
  const auto inGroup = [&](std::int32_t o) {
    return std::find(group.begin(), group.end(), o) != group.end();
  };
  for (int round = 0; round < 2; ++round) {
    UntangleProblem problem;
    for (const std::int32_t a : group) {
      problem.starts.push_back(now_[idx(a)]);
      settleTable(idx(a), options_.untangleSteps);  // read up to untangleSteps moves away
      problem.tables.push_back(table_[idx(a)]);
      problem.counts.push_back(std::find(counting.begin(), counting.end(), a) != counting.end() ? 1 : 0);
    }
    problem.clearOfOthers = [&](NodeId v) {
      const auto other = [&](NodeId w) {
        const std::int32_t o = agentAt_[idx(w)];
        return o >= 0 && !inGroup(o);
      };
      if (other(v))
        return false;
      for (const NodeId w : graph_.conflicts(v)) {
        if (other(w))
          return false;
      }
      return true;
    };
    // A robot waiting in its station's line moves only forward, in a way out as in a step (left
    // sideways, it lost its place: the line orders robots off its nodes last).
    problem.mayMove = [&](std::size_t j, NodeId from, NodeId to) {
      return lineAllows(idx(group[j]), from, to);
    };
    problem.maxSteps = options_.untangleSteps;
    problem.maxConfigurations = options_.untangleConfigurations;
    if (const auto way = untangle(graph_, problem)) {
      const std::int32_t id = nextGroup_++;
      for (std::size_t j = 0; j < group.size(); ++j) {
        const auto a = idx(group[j]);
        forced_[a].clear();
        for (const auto& config : way->steps)
          forced_[a].push_back(config[j]);
        forcedAt_[a] = 0;
        forcedGroup_[a] = id;
      }
      // The member the way out brings closer keeps the lead once it is out.
      escalate(idx(group[way->improved]));
      ++stats_.untangles;
      return true;
    }
    // Pull in the agents standing where the knot's members could move: they may make room.
    const std::size_t pulled = group.size();
    for (const std::int32_t m : knot) {
      for (const Edge& e : graph_.edges(now_[idx(m)])) {
        if (!e.open || !graph_.isOpen(e.to))
          continue;
        const auto pull = [&](NodeId w) {
          const std::int32_t o = agentAt_[idx(w)];
          if (o >= 0 && group.size() < limit && !inGroup(o) && controlled_[idx(o)] != 0 &&
              forcedGroup_[idx(o)] < 0)
            group.push_back(o);
        };
        pull(e.to);
        for (const NodeId w : graph_.conflicts(e.to))
          pull(w);
      }
    }
    if (group.size() == pulled)
      break;
  }
  ++stats_.untangleFailures;
  return false;
}

void Pibt::advanceForced() {
  // A move of a way out that could not be made (someone from outside the knot got in the way since
  // it was found): the way out is given up, and the knot is found again if it still holds.
  const std::size_t n = now_.size();
  for (std::size_t i = 0; i < n; ++i) {
    const std::int32_t g = forcedGroup_[i];
    if (g < 0)
      continue;
    if (now_[i] != forced_[i][forcedAt_[i] + 1]) {
      ++stats_.untangleAborts;
      dropForced(g);
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    if (forcedGroup_[i] >= 0 && ++forcedAt_[i] + 1 >= forced_[i].size()) {
      forced_[i].clear();
      forcedGroup_[i] = -1;
    }
  }
}

void Pibt::dropForced(std::int32_t group) {
  if (group < 0)
    return;
  for (std::size_t i = 0; i < now_.size(); ++i) {
    if (forcedGroup_[i] == group) {
      forced_[i].clear();
      forcedGroup_[i] = -1;
    }
  }
}

}  // namespace fleet::traffic
