#pragma once

// Safe interval path planning for one robot on a roadmap, in the robot's own units (Phillips and
// Likhachev, ICRA 2011): the state is the node, the safe interval the robot is in there
// (safe_intervals.hpp) and the node it came from — its heading, since turning on the spot before
// the next edge takes time (Roadmap::extraTurn). Its actions are the robot's: wait (within the safe
// interval), turn on the spot and drive an edge, each at its real duration; the result is the
// earliest arrival at the goal that keeps to every other robot's reservations and can stay there
// until `holdUntil`. A* over those states with the goal's driving time with its turns from the
// edge the robot arrived by as the heuristic (a robot alone's own time, kept as floats rounded
// down from double sums: within a float step per edge of it; with others waiting only adds), so the
// arrival is the earliest to within a millisecond (SIPP's optimality, heading included; states are
// ordered by f in 1 ms steps counted from the start's f, deepest first within one, so the many
// equally short ways of a lattice are not all searched; the tests check it against a search over
// every time step).

#include <cstdint>
#include <functional>
#include <optional>
#include <unordered_map>
#include <vector>

#include "fleet/traffic/graph.hpp"
#include "fleet/traffic/safe_intervals.hpp"

namespace fleet::traffic {

struct SippQuery {
  NodeId start = kNoNode;
  NodeId cameFrom = kNoNode;  ///< the node it arrived at `start` from (its heading); kNoNode: none
  double startTime = 0.0;     ///< s: it stands on `start` from then (must be safe there then)
  /// kNoNode: a refuge — the earliest node it can stay on until `holdUntil` that is not marked in
  /// `avoid` (a robot getting out of another's way).
  NodeId goal = kNoNode;
  /// It must be able to stay on the goal from its arrival until then (kForever: for good).
  double holdUntil = kForever;
  const std::vector<std::uint8_t>* avoid = nullptr;  ///< per node, for a refuge
  /// A robot in a station's line moves only forward along it: on a node whose `lineOf` is `line`,
  /// its one move is to `forward` of that node (kNoNode: any). Null or line < 0: no line.
  std::int32_t line = -1;
  const std::vector<std::int32_t>* lineOf = nullptr;
  const std::vector<NodeId>* forward = nullptr;
};

struct SippStats {
  std::uint64_t searches = 0;
  std::uint64_t expanded = 0;
  std::uint64_t failures = 0;    ///< no path, or the expansion budget ran out
  std::uint64_t heuristics = 0;  ///< goals' driving-time tables computed (each a backward search)
};

class Sipp {
 public:
  /// s of turning at `at` between prev→at and at→next beyond at→next's duration (>= 0).
  using TurnTime = std::function<double(NodeId prev, NodeId at, NodeId next)>;

  explicit Sipp(const Graph& graph, TurnTime turn = {}, std::size_t maxExpansions = 200000);

  /// The earliest timed path from the query's start to its goal that keeps to `table`'s safe
  /// intervals, or nullopt (none within the expansion budget, or the start is unsafe at the start
  /// time). The path's first node is the start (enter = arrive = startTime); its last node's leave
  /// is `holdUntil`.
  std::optional<TimedPath> plan(const ReservationTable& table, const SippQuery& query);

  /// s of driving from `v` to `goal` with nobody in the way, turns included, starting in the best
  /// heading (kForever when the goal cannot be reached).
  double drivingTime(NodeId v, NodeId goal);
  /// Call after opening or closing nodes or edges: drops the heuristics.
  void graphChanged() { heuristics_.clear(); }
  /// A standing cost (s) of driving into each node (empty: none), planned as time: an edge into
  /// v is searched as taking its duration + cost[v], so a robot plans round a dear node when that is
  /// sooner, and through it as if slowly (its reservations the longer). The risk map's
  /// collision-probability costs and a yield's come this way. The goals' tables leave costs out
  /// (driving time alone: still never above the time to the goal, so the search stays exact), so
  /// costs renewed every few seconds do not recompute them. Returns whether it changed anything.
  /// Throws std::invalid_argument for a vector of another size than the graph's or a cost that is
  /// negative or not finite (a negative one would make the tables overestimate).
  bool setNodeCost(std::vector<float> cost);
  [[nodiscard]] const std::vector<float>& nodeCost() const { return cost_; }
  [[nodiscard]] const SippStats& stats() const { return stats_; }

 private:
  struct State {
    NodeId node;
    NodeId from;          ///< the node before (kNoNode: none)
    std::int32_t inEdge;  ///< the edge it arrived by (-1: the start, or `from` is no edge's tail)
    std::int32_t interval;
    std::int32_t parent;
    double arrive;
    double depart;  ///< when it left the parent's node
    double intervalEnd;
  };
  /// Per goal: the time to it from each node (no heading) and from arriving by each edge, by a
  /// backward search run only as far as the values read need: a value is final once no key left
  /// in the search's heap is below it.
  struct Heuristic {
    std::vector<float> node;
    std::vector<float> edge;
    std::vector<std::pair<double, std::uint32_t>> heap;  ///< the search's frontier (a min-heap)
    NodeId goal = kNoNode;
    std::uint64_t used = 0;  ///< when last read (least recently used dropped first)
  };
  /// The earliest arrival found so far per state (the edge arrived by, the safe interval): a
  /// list per edge in one pool, reset by a stamp per query (no hashing, no allocation).
  struct Best {
    std::int32_t interval;
    std::int32_t next;
    double arrive;
  };
  /// The slot of a state's (edge arrived by | node without a heading).
  [[nodiscard]] std::size_t slotOf(NodeId v, std::int32_t inEdge) const {
    return inEdge >= 0 ? static_cast<std::size_t>(inEdge) : edgeTail_.size() + static_cast<std::size_t>(v);
  }
  /// The best arrival of the state (its slot, its interval), inserting `arrive` when it has none;
  /// returns the entry and whether it was new.
  std::pair<Best*, bool> bestOf(std::size_t slot, std::int32_t interval, double arrive);
  Heuristic& heuristic(NodeId goal);
  /// Runs the goal's backward search until `value` (one of its values, read as it changes) is final.
  void settle(Heuristic& h, const float& value);
  /// The final time to the goal from node `v` arrived at by edge `in` (-1: no heading).
  double toGoal(Heuristic& h, NodeId v, std::int64_t in);
  void index();
  /// The turn at `at` from arriving by edge `inEdge` (from `from`) into its out-edge `out`.
  double turnAt(NodeId from, std::int32_t inEdge, NodeId at, std::size_t out);
  [[nodiscard]] std::int64_t edgeIndex(NodeId from, NodeId to) const;
  /// s an edge is searched as taking: its duration and its head's cost.
  [[nodiscard]] double duration(const Edge& e) const {
    return cost_.empty() ? e.duration
                         : e.duration + static_cast<double>(cost_[static_cast<std::size_t>(e.to)]);
  }
  /// Edge `e` (an index) can be driven now: open, into an open node.
  [[nodiscard]] bool usable(std::uint32_t e) const;
  const std::vector<Interval>& intervals(const ReservationTable& table, NodeId v, double from);

  const Graph& graph_;
  TurnTime turn_;
  std::size_t maxExpansions_;
  std::vector<float> cost_;                          ///< per node (empty: none)
  std::vector<std::size_t> edgeStart_;               ///< per node: its first out-edge's index
  std::vector<NodeId> edgeTail_;                     ///< per edge
  std::vector<std::uint32_t> inPos_;                 ///< per edge: its place among its head's reverse_
  std::vector<std::vector<std::uint32_t>> reverse_;  ///< per node: the edges into it
  std::unordered_map<NodeId, Heuristic> heuristics_;
  std::vector<std::size_t> turnStart_;  ///< per node: its (way in, way out) turns in turns_
  std::vector<float> turns_;            ///< s, -1 until computed
  // Per query.
  std::vector<std::uint32_t> intervalStamp_;
  std::vector<std::vector<Interval>> intervals_;
  std::uint32_t stamp_ = 0;
  std::vector<State> states_;
  std::vector<std::uint32_t> bestStamp_;  ///< per slot
  std::vector<std::int32_t> bestHead_;    ///< per slot: its first entry in bestPool_
  std::vector<Best> bestPool_;
  struct Open {
    std::int64_t f;  ///< arrival + heuristic, in steps (sipp.cpp)
    double g;
    std::int32_t state;
  };
  std::vector<Open> open_;  ///< a heap
  std::uint64_t useClock_ = 0;
  SippStats stats_;
};

}  // namespace fleet::traffic
