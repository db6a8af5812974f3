#pragma once

// Lifelong PIBT: Priority Inheritance with Backtracking (Okumura, Machida, Défago, Tamura, AIJ 2022;
// Kei18/pibt2), one step at a time on a traffic Graph, for agents whose goals change at any step.
//
// Each step the agents are taken in priority order; an agent reserves the best node it can reach in
// one move (nearest to its goal), and every undecided agent standing on a node that reservation
// excludes inherits its priority and must move away first (recursively); if one of them cannot, the
// reservation is given up and the next node tried (backtracking), staying put last. On a roadmap a
// reservation of u excludes u and conflicts(u) for everyone else, and a swap is two agents each
// moving into what the other excludes now. Moving into a node its agent is leaving is allowed (the
// MAPF convention). On a roadmap a pushed agent that cannot make room stands only for the rest of
// its pusher's search, then plans in its own turn: it had no move clear of what the pusher wanted,
// which reaches past its neighbours, but may have moves of its own (reconsiderRefused). Agents
// outside the planner's control (faulted, paused, a vendor's vehicle) are fixed obstacles on their
// node.
//
// Priorities: task priority first, then agents with a goal before those without, then the number
// of steps since the agent last reached a goal, then a per-agent random number (seeded). Three
// additions, documented in docs/algorithms.md ("Traffic: lifelong planner"):
// - Rotations: a closed cycle of agents each following the next is legal in MAPF but deadlocks
//   robots executing by dependencies; by default the planner never closes one (Rotations::kAvoid).
// - Escape: plain PIBT can stall for ever (a dead-end spur whose occupant must come out before a
//   higher-priority agent can go in: each waits for the other's node and priority inheritance
//   only ever pushes the side with nowhere to go). When agents that have neither moved nor come
//   closer to their goals for `escapeAfter` steps wait for each other's nodes in a cycle, one of
//   them (the one escalated least since it last made progress, then the one of lowest priority)
//   is escalated above every other priority until it has gained `escapeProgress` on where it was
//   escalated or reached its goal; if it stays stuck for another `escapeAfter` steps it drops back
//   and the next member gets its turn.
// - Untangling: a knot escalation cannot untie because on a roadmap no single move of the agent in
//   the way clears what the other needs (a robot on the lane in front of a parked robot's only way
//   out) is searched for: a few steps of the cycle's agents (and of agents in their way, up to
//   untangleGroup), one move at a time, everyone else standing (untangle.hpp). The moves found are
//   planned before everyone else's; the member they bring closer to its goal is then escalated.
//   Escalation alone is the fallback when the search finds nothing. A wait-for chain that ends at
//   an agent content where it stands (at its goal or without one) is such a knot too when all its
//   agents have stood still that long (a robot parked in a dock, its way out excluded by the robot
//   on the lane that wants past it): its tail is searched until the agent waiting on the content
//   one is closer to its goal.
// - Fixed agents' nodes are taken out of the routes (DistanceTable::setBlocked), since PIBT only
//   moves greedily and would otherwise wait behind a stopped robot for ever.
// - Headings: given the robots' turn times (PibtOptions::turnTime), moves are ranked by the turn
//   into them plus the goal's cost-to-go with the turns on the way (heading_table.hpp), so a
//   robot keeps to ways it need not stop and turn on, and standing is ranked the way it faces.
//
// Deterministic for a seed: same graph, starts, goals and calls, same plan.

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <vector>

#include "fleet/traffic/distance_table.hpp"
#include "fleet/traffic/graph.hpp"
#include "fleet/traffic/heading_table.hpp"
#include "fleet/traffic/rotation_pass.hpp"

namespace fleet::traffic {

enum class Rotations : std::uint8_t {
  kAllow,   ///< the MAPF convention (pibt2's PIBT): a cycle of agents may move all at once
  kCancel,  ///< plan as kAllow, then RotationPass stops each cycle and everyone following it
  kAvoid,   ///< never close a cycle while planning; RotationPass stays behind it as a net
};

struct PibtOptions {
  std::uint64_t seed = 1;
  Rotations rotations = Rotations::kAvoid;
  /// Steps standing still without coming closer to its goal before an agent that waits in a cycle
  /// can be escalated; 0: never (plain PIBT).
  int escapeAfter = 16;
  /// Distance an escalated agent gains on where it was escalated before it drops back (cells on a
  /// unit grid, the edges' cost unit on a roadmap: seconds, times the flow guidance if any).
  double escapeProgress = 16.0;
  /// Agents a search for a way out of a knot may move together (untangle.hpp; at most 4); below 2:
  /// never search, escalate only.
  int untangleGroup = 4;
  /// Single moves a way out of a knot may take at most, and configurations it may look at.
  int untangleSteps = 12;
  std::size_t untangleConfigurations = 20000;
  /// Steps an agent stands without coming closer to its goal before it is routed round the agents
  /// that have stood still that long too (a detour table: entering what such an agent excludes
  /// costs `detourPenalty` more). PIBT ranks moves by distance alone, so an agent whose shortest way
  /// passes an agent waiting in line, or one stuck itself, otherwise waits for ever beside a free
  /// way round. 0: never (plain PIBT).
  int detourAfter = 0;
  /// Extra cost (the edges' cost unit: seconds, times the flow guidance if any) of entering what a
  /// standing agent excludes.
  float detourPenalty = 30.0F;
  /// Detour tables computed per step at most.
  int maxDetoursPerStep = 4;
  /// A detour is searched within this distance (graph units: m on a roadmap) of the agent and kept
  /// while the agent stays within `detourKeep` of where it was taken (local_detour.cpp): what it goes
  /// round is near it. The rest of the disc is room for the few moves an untangling reads ahead.
  double detourRadius = 12.0;
  double detourKeep = 5.0;
  std::size_t distanceCacheBytes = std::size_t{256} << 20;
  /// s of turning on the spot at `at` between prev→at and at→next beyond the edge's duration
  /// (Roadmap::extraTurn). Given, the planner knows each agent's heading: a move is ranked by the
  /// turn into it plus the goal's cost-to-go with the turns on the way (heading_table.hpp), and
  /// standing by the cost-to-go the way the agent faces. Empty: by the node distance alone.
  std::function<double(NodeId prev, NodeId at, NodeId next)> turnTime{};
  /// Turns the heading tables' searches may relax per step (HeadingTable::work): bounds the time
  /// a step spends on goals it has not seen (100,000: ~4 ms on the site for 100); their agents
  /// rank moves by distance until their table is done. TrafficControl sets it from
  /// TrafficOptions::headingWorkPerUpdate.
  std::size_t headingWorkPerStep = 100000;
  std::size_t headingCacheBytes = std::size_t{64} << 20;
  /// Moves whose distances to the goal (in the edges' cost unit) differ by at most this much count
  /// as equally good (0: exact; sums of edge durations along equally long ways differ in the last
  /// bits).
  float tieTolerance = 0.0F;
  /// Among equally good moves, prefer the one that turns least from the agent's last move. On a
  /// lattice with diagonals many shortest ways exist; picking among them at random zigzags, and a
  /// real robot stops to turn at every zig (the plan counts each edge as one step whatever the turn).
  bool preferStraight = false;
  /// Added to a move's rank (the edges' cost unit: seconds on a roadmap) when another agent stands
  /// on the node or on one it excludes. Plain PIBT ranks such a move by distance alone (the free
  /// node wins only a tie) and then pushes the agent standing there, which on a roadmap often
  /// steps away from its own goal and back: a move of someone else's for every push. Priced, a
  /// free way nearly as short wins. 0: plain PIBT (pibt2's ranking). docs/algorithms.md, "Traffic:
  /// lifelong planner".
  float occupiedCost = 0.0F;
};

struct PibtStats {
  std::uint64_t steps = 0;
  std::uint64_t rotationStops = 0;  ///< agents RotationPass stopped (kCancel; 0 with kAvoid)
  std::uint64_t escalations = 0;
  std::uint64_t escalationRequeues = 0;  ///< escalated agents that stayed stuck and dropped back
  std::uint64_t detours = 0;             ///< detour tables computed
  std::uint64_t untangles = 0;           ///< knots a search found a way out of
  std::uint64_t untangleFailures = 0;    ///< knots it found none for (escalated instead)
  std::uint64_t untangleAborts = 0;      ///< ways out given up half way (a move could not be made)
};

class Pibt {
 public:
  /// `starts` must be valid, distinct and free of conflicts (std::invalid_argument otherwise).
  Pibt(const Graph& graph, std::span<const NodeId> starts, PibtOptions options = {});

  [[nodiscard]] std::size_t size() const { return now_.size(); }
  [[nodiscard]] const std::vector<NodeId>& positions() const { return now_; }

  /// kNoNode: no goal (the agent stays unless someone needs its node).
  void setGoal(std::size_t agent, NodeId goal);
  [[nodiscard]] NodeId goal(std::size_t agent) const { return goal_[agent]; }
  /// Higher first; every other priority rule only breaks ties of this one.
  void setTaskPriority(std::size_t agent, int priority) { task_[agent] = priority; }
  /// An agent out of control is a fixed obstacle on its node until it is controlled again.
  void setControlled(std::size_t agent, bool controlled);
  [[nodiscard]] bool controlled(std::size_t agent) const { return controlled_[agent] != 0; }
  /// Moves an agent (a robot reported somewhere else, a vendor's vehicle moved). Refused (false) when
  /// the node is invalid or conflicts with another agent's node.
  bool setPosition(std::size_t agent, NodeId v);
  /// Moves every agent at once (planning starts again from where the robots' releases end) and
  /// appends agents when `positions` is longer than size() (robots joining; they start without a
  /// goal, controlled). Goals, task priorities, the steps since each reached its goal and the
  /// distance cache are kept, so re-planning does not reset PIBT's fairness. std::invalid_argument
  /// (nothing changed) when the positions are invalid or conflict.
  /// `cameFrom` (optional, per position): the node each agent arrived from, its heading at the new
  /// position (kNoNode: unknown); without it an agent that moved has no heading.
  void reset(std::span<const NodeId> positions, std::span<const NodeId> cameFrom = {});

  /// Plans and takes one step: every agent's node at the next step, conflict-free (and rotation-free
  /// unless Rotations::kAllow).
  const std::vector<NodeId>& step();
  /// The heading tables, nullptr without PibtOptions::turnTime.
  [[nodiscard]] const HeadingTable* headingTables() const { return heading_.get(); }
  /// Agents still driving their last move in a plan kept in time (TrafficControl): the next
  /// step leaves them where they are, pushes none of them and counts no standing for them. Empty or
  /// all 0: none. Agents on a way out of a knot are never busy.
  void setBusy(std::span<const std::uint8_t> busy) { busy_.assign(busy.begin(), busy.end()); }
  [[nodiscard]] bool busy(std::size_t agent) const {
    return agent < busy_.size() && busy_[agent] != 0 && forcedGroup_[agent] < 0;
  }

  [[nodiscard]] bool escalated(std::size_t agent) const { return escalatedAt_[agent] >= 0; }
  /// Whether the agent is on a way out of a knot (its next moves are fixed).
  [[nodiscard]] bool untangling(std::size_t agent) const { return forcedGroup_[agent] >= 0; }
  /// Steps since the agent last reached its goal (its PIBT priority).
  [[nodiscard]] int elapsed(std::size_t agent) const { return elapsed_[agent]; }
  [[nodiscard]] const PibtStats& stats() const { return stats_; }
  DistanceTable& distances() { return distances_; }
  [[nodiscard]] const DistanceTable& distances() const { return distances_; }
  /// Call after opening or closing nodes or edges (or adding any): drops the cached distances.
  void graphChanged();
  /// A standing cost (s) of driving into each node (DistanceTable::setNodeCost) from the next step
  /// on. Each agent's progress is measured afresh on the new distances, without resetting how
  /// long it has stalled: a cost that changes every few seconds must not hide a livelock.
  void setNodeCost(std::vector<float> cost);

  /// Station lines (TrafficControl::setStations): per node, the line it belongs to (-1: none) and
  /// the next node toward the dock (queue place → the one before it → approach → dock). An agent in
  /// a line (setLine) standing on one of that line's nodes moves only forward or stays: pushed by
  /// the robot behind it, a robot waiting in a one-way queue would otherwise step sideways out of
  /// it and have to drive round to the tail (docs/algorithms.md, "Traffic: stations as servers").
  void setLines(std::vector<std::int32_t> lineOf, std::vector<NodeId> forward);
  /// The line agent `agent` waits in (-1: none).
  void setLine(std::size_t agent, std::int32_t line);

 private:
  struct Candidate {
    NodeId node;
    float distance;
    std::uint32_t tieBreak;  ///< nodes nobody stands on first, then random
  };

  bool plan(std::int32_t agent, std::int32_t parent, std::size_t depth);
  [[nodiscard]] bool available(std::int32_t agent, NodeId u) const;
  [[nodiscard]] bool leavesAncestorsAlone(std::int32_t agent, std::int32_t parent, NodeId u) const;
  [[nodiscard]] bool closesCycle(std::int32_t agent, NodeId u);
  [[nodiscard]] bool before(std::int32_t a, std::int32_t b) const;
  /// Agents refused as pushed children (roadmaps only) are undecided again after the root's search.
  void reconsiderRefused();
  void updateProgress(std::size_t agent);
  [[nodiscard]] std::int32_t blocker(std::size_t agent) const;
  void escapeDeadlocks();
  /// Searches a way out for the knot's agents (and agents in their way); it ends when one of
  /// `counting` (members of the knot) is closer to its goal.
  [[nodiscard]] bool untangleKnot(std::span<const std::int32_t> knot, std::span<const std::int32_t> counting);
  void escalate(std::size_t agent);
  void advanceForced();
  void dropForced(std::int32_t group);
  void planDetours();
  /// Each agent's heading table for this step (searching those not there yet, within the budget).
  void findHeadingTables();
  /// Settles agent i's table (its goal's or its detour's, both searched only as far as read) at
  /// its node and within `hops` edges of it.
  void settleTable(std::size_t i, int hops);
  /// Every agent's table at its node and neighbours: all a step reads of it but to untangle.
  void settleTables();
  void dropDetour(std::size_t agent);
  /// Whether agent i is still within `detourKeep` of where its detour was taken.
  [[nodiscard]] bool nearDetour(std::size_t i) const;
  void resizeForGraph();
  void cover(NodeId v, int delta);
  /// An agent other than `except` standing on what v excludes, or -1.
  [[nodiscard]] std::int32_t standingOn(NodeId v, std::int32_t except) const;
  /// Whether the agent may move from `from` to `to` as far as its station's line goes: waiting on
  /// one of its line's nodes, only forward along the line (a step's moves and a way out of a knot
  /// alike); anywhere otherwise.
  [[nodiscard]] bool lineAllows(std::size_t agent, NodeId from, NodeId to) const {
    return !onOwnLine(agent, from) || to == lineForward_[static_cast<std::size_t>(from)];
  }
  /// Whether `v` is a node of the station line the agent waits in (a queue place or the approach:
  /// where it waits, not where it is going).
  [[nodiscard]] bool onOwnLine(std::size_t agent, NodeId v) const {
    return line_[agent] >= 0 && !lineOf_.empty() && lineOf_[static_cast<std::size_t>(v)] == line_[agent];
  }
  std::uint64_t random();

  const Graph& graph_;
  PibtOptions options_;
  DistanceTable distances_;
  std::unique_ptr<HeadingTable> heading_;  ///< with PibtOptions::turnTime only
  RotationPass rotationPass_;
  PibtStats stats_;
  std::uint64_t rng_;
  bool grid_ = true;  ///< no conflict sets: a node excludes only itself (fast paths)

  // Per agent.
  std::vector<NodeId> now_;
  std::vector<NodeId> next_;
  std::vector<NodeId> prev_;  ///< the node it last moved from (its heading), kNoNode: unknown
  std::vector<NodeId> goal_;
  std::vector<const float*> table_;
  std::vector<const float*> surcharge_;  ///< its goal's heading table this step, nullptr: none
  std::vector<int> task_;
  std::vector<int> elapsed_;
  std::vector<double> epsilon_;
  std::vector<std::uint8_t> controlled_;
  std::vector<std::uint8_t> busy_;  ///< setBusy()
  std::vector<std::uint8_t> onStack_;
  bool rebaseProgress_ = false;            ///< the distances changed: best_ from the new ones
  std::vector<float> best_;                ///< nearest it has been to its goal since the goal was set
  std::vector<int> stalled_;               ///< steps since best_ last improved
  std::vector<std::int64_t> escalatedAt_;  ///< step of (re-)escalation, -1 when not escalated
  std::vector<std::uint64_t> escalationDraw_;
  std::vector<float> escalationDistance_;
  std::vector<int> escalationIdle_;          ///< steps escalated without coming closer
  std::vector<int> still_;                   ///< steps since it last moved
  std::vector<int> tries_;                   ///< escalations since it last came closer to its goal
  std::vector<std::uint32_t> visited_;       ///< stamps for the cycle search
  std::vector<PartialTable> detour_;         ///< detour table to its goal, empty when none
  std::vector<float> detourFrom_;            ///< regular distance when the detour was taken
  std::vector<NodeId> detourAt_;             ///< where the detour was taken (its disc's centre)
  std::vector<float> extra_;                 ///< per node scratch: detour penalties
  std::vector<int> standCover_;              ///< per node scratch: standing agents excluding it
  std::vector<std::vector<NodeId>> forced_;  ///< way out of a knot: its node per step, from now
  std::vector<std::size_t> forcedAt_;        ///< index in forced_ of where it stands
  std::vector<std::int32_t> forcedGroup_;    ///< the knot it is untangling with, -1
  std::vector<std::int32_t> line_;           ///< the line it waits in, -1
  std::int32_t nextGroup_ = 0;
  std::uint32_t stamp_ = 0;

  // Per node.
  std::vector<std::int32_t> agentAt_;     ///< agent standing there now, -1
  std::vector<std::int32_t> reservedBy_;  ///< agent going there next step, -1
  std::vector<int> fixedCover_;           ///< fixed agents excluding the node (routes avoid it)
  std::vector<std::int32_t> lineOf_;      ///< the station line the node belongs to, -1 (empty: none)
  std::vector<NodeId> lineForward_;       ///< the line's next node toward the dock

  std::vector<std::int32_t> order_;
  std::vector<NodeId> goals_;          ///< scratch: the goals wanting a heading table this step
  std::vector<Candidate> candidates_;  ///< (max degree + 1) per recursion depth
  std::size_t stride_ = 1;
  std::vector<std::int32_t> search_;   ///< cycle search stack
  std::vector<std::int32_t> chain_;    ///< wait-for chain in escapeDeadlocks()
  std::vector<std::int32_t> refused_;  ///< pushed agents that could not make room, this search
};

}  // namespace fleet::traffic
