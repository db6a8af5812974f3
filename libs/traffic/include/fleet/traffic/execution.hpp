#pragma once

// Executing a multi-robot plan on robots that are not on time: the action dependency graph of Hönig
// et al. ("Persistent and robust execution of MAPF schedules in warehouses", RA-L 2019), grown one
// planner step at a time for lifelong operation, and releasing each robot's route a few nodes at a
// time as VDA 5050 orders do (a base it may drive, a horizon it may expect).
//
// The plan is a sequence of configurations (one node per robot per step). Each robot's route is its
// sequence of distinct nodes; entering a route node is an action. The only dependency kept is the
// one that matters for safety: a robot may enter node v only after every robot that stood on a node
// conflicting with v earlier in the plan has reached the first node of its route that no longer
// conflicts with v. Only the last visitor of each node needs to be recorded: that visitor itself
// entered only after its predecessors had left. Dependencies point to the same or earlier plan steps,
// so they cannot form a cycle unless one step has a cycle of robots each entering what the next one
// leaves (a rotation); append() refuses such a step. Hence robots that only drive released nodes
// never stand on conflicting nodes, and the execution cannot deadlock however late any robot is —
// a late robot holds back only the robots that depend on it.

#include <cstdint>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

/// A step the plan cannot be executed with (names the robots and the nodes).
class PlanStepError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

struct ReleaseOptions {
  /// The base reaches at least this far (m along the route) past the robot's last reported node
  /// when the dependencies allow: the stopping distance plus the distance driven during the
  /// release latency, so a robot on time never brakes at the end of its base.
  double baseAhead = 1.5;
  /// At most this many nodes in the base (bounds how much is committed if the robot goes away).
  std::size_t maxBaseNodes = 12;
  /// Planned nodes after the base that are sent as the horizon (may change).
  std::size_t horizonNodes = 8;
};

/// What a robot may drive (base) and what it may expect after that (horizon). `base.front()` is
/// the robot's last reported node.
struct Release {
  std::vector<NodeId> base;
  std::vector<NodeId> horizon;
  std::int64_t baseEndStep = 0;  ///< plan step at which the base's last node is reached
};

/// Why a robot's base ended where it did when it was last released.
enum class BaseCut : std::uint8_t {
  PlanEnd,  ///< the planned route ends there (its goal or target, or the planner has not gone on)
  Held,     ///< its next node waits on robots planned before it there (a dependency)
  Limit,    ///< far enough ahead (ReleaseOptions::baseAhead, maxBaseNodes): more was free
};
const char* toString(BaseCut c);

enum class Report {
  Accepted,     ///< progress moved on
  Duplicate,    ///< the node it already reported
  NotReleased,  ///< not among its released nodes ahead: ignored, the robot stays held
  UnknownRobot,
};
const char* toString(Report r);

class Execution {
 public:
  /// Robots start on `starts` (plan step 0); they must not conflict.
  Execution(const Graph& graph, std::span<const NodeId> starts, ReleaseOptions options = {});

  [[nodiscard]] std::size_t robots() const { return routes_.size(); }
  /// Number of configurations appended after the start.
  [[nodiscard]] std::int64_t plannedSteps() const { return step_; }

  /// Appends the planner's next configuration (same node = the robot waits). Throws PlanStepError
  /// naming robots and nodes when a robot moves along no open edge, two robots end on conflicting
  /// nodes, or robots each enter what the next one leaves in a cycle; nothing is appended then.
  void append(std::span<const NodeId> next);
  /// append() of the configuration in which `robot` alone moves to `to` (or stays, on its last
  /// node), the others where their routes end: the same checks, dependencies and order, at the
  /// cost of the robot's conflicts rather than the fleet's (the timed core appends its plans one
  /// move at a time). The configuration the others stand in is taken as append() left it.
  void appendMove(std::size_t robot, NodeId to);

  /// The robot reports it has arrived at `node`. Accepted only for a released node ahead of its
  /// last report (reports may skip nodes: reaching a node implies passing the ones before it).
  Report reached(std::size_t robot, NodeId node);

  /// Extends the robot's base as far as its dependencies and the options allow and returns it
  /// with the horizon. Never shrinks what was released before.
  Release release(std::size_t robot);

  /// The robots whose progress the next unreleased node of `robot` waits for (empty: nothing, or
  /// the route ends).
  [[nodiscard]] std::vector<std::size_t> waitingOn(std::size_t robot) const;

  /// Why the robot's base ends where it does (set by release()).
  [[nodiscard]] BaseCut baseCut(std::size_t robot) const { return routes_.at(robot).cut; }

  /// Last reported node, last released node, last planned node of a robot.
  [[nodiscard]] NodeId at(std::size_t robot) const;
  [[nodiscard]] NodeId releasedEnd(std::size_t robot) const;
  /// The node the robot's released route enters releasedEnd() from (its heading there), kNoNode
  /// when that part of the route is gone or it never moved.
  [[nodiscard]] NodeId releasedFrom(std::size_t robot) const;
  [[nodiscard]] NodeId plannedEnd(std::size_t robot) const;
  /// The released route ahead of the robot, from its last reported node to its last released one
  /// (each node once).
  [[nodiscard]] std::vector<NodeId> releasedRoute(std::size_t robot) const;
  /// Plan step of the robot's last reported node (how far along the plan it is).
  [[nodiscard]] std::int64_t progressStep(std::size_t robot) const;
  /// Plan step of the robot's first planned node not released yet, -1 when everything is released.
  [[nodiscard]] std::int64_t nextUnreleasedStep(std::size_t robot) const;
  /// The route from the last reported node to the next unreleased one, for stall reports:
  /// "n1 n2 | n3 (needs q:index/progress ...)", released nodes before the bar.
  [[nodiscard]] std::string describe(std::size_t robot) const;
  /// Route nodes planned but not yet reported (including released ones).
  [[nodiscard]] std::size_t pendingNodes(std::size_t robot) const;

  /// Drops every planned node that was not released yet, so the planner can start again from
  /// the released ends (returned, one per robot; they never conflict). Dependencies of what stays
  /// released are kept.
  std::vector<NodeId> truncateToReleased();

  /// A robot joins on `start`. Refused (PlanStepError naming the robot in the way) when a robot
  /// holds or is released a node conflicting with it; call truncateToReleased() first so planned
  /// but unreleased nodes do not count. Returns the new robot's index.
  std::size_t addRobot(NodeId start);

  /// Switchable dependencies (after Berndt et al.'s switchable action dependency graphs): `robot`'s
  /// next node waits on robots that are at least `minBehind` route nodes short of what it waits
  /// for. Those robots, not yet released into the conflict, are put behind `robot` there: their
  /// remaining route from the first node that conflicts with `robot`'s unreleased route is
  /// ordered after `robot`'s nodes it conflicts with, every unreleased dependency is derived
  /// again from that order, and the change is kept only when the dependencies stay acyclic (no
  /// deadlock), every robot needed is planned far enough, and `robot`'s next node is then free to
  /// release. Returns whether it was kept; nothing changes otherwise.
  bool letPass(std::size_t robot, std::int64_t minBehind);

  /// A robot that stops following its route (faulted, held by a person, taken over): cuts what was
  /// released to it back to the node it may be driving into (its next one after the last reported),
  /// so the others' routes can be planned around where it really is. `standing`: the robot is known
  /// to stand at its last reported node (held there by a person for a while), so that next node
  /// goes too and it can be planned another way. Call truncateToReleased() after it. Robots must
  /// then be sent the shorter release.
  void retract(std::size_t robot, bool standing = false);

 private:
  struct Dependency {
    std::uint32_t robot;
    std::int64_t index;  ///< that robot must have reached route index >= this
  };
  struct Entry {
    NodeId node;
    std::int64_t step;
    double distance;  ///< m from the previous route node
    std::vector<Dependency> deps;
    /// Where the entry stands in the order robots take conflicting nodes: the plan step scaled,
    /// until letPass() puts a late robot's entries behind another's.
    std::int64_t order = 0;
  };
  struct Route {
    std::vector<Entry> entries;  ///< entries_[i] is route index first + i
    std::int64_t first = 0;      ///< route index of entries.front()
    std::int64_t progress = 0;   ///< last reported route index
    std::int64_t released = 0;   ///< last released route index
    BaseCut cut = BaseCut::PlanEnd;
    [[nodiscard]] std::int64_t last() const { return first + static_cast<std::int64_t>(entries.size()) - 1; }
    [[nodiscard]] const Entry& operator[](std::int64_t i) const {
      return entries[static_cast<std::size_t>(i - first)];
    }
  };
  struct Visit {
    std::int32_t robot = -1;
    std::int64_t index = 0;
  };

  [[nodiscard]] bool satisfied(const Entry& e) const;
  /// Sets the dependencies of `robot`'s newest entry (plan step `step`); returns the robots it
  /// waits on that enter their newest entry in this same step.
  std::vector<std::size_t> depend(std::size_t robot, std::int64_t step);
  void prune(std::size_t robot);
  void rebuildVisitors();
  /// Derives every unreleased entry's dependencies from `order` (released entries come first);
  /// false when a robot would have to go beyond its planned route or the dependencies form a
  /// cycle. `only` (per node): derive again only the entries on marked nodes, the others' orders
  /// having stayed as they were derived from (the whole acyclicity check runs either way).
  bool rederive(const std::vector<std::uint8_t>* only = nullptr);
  [[nodiscard]] bool acyclic() const;

  const Graph& graph_;
  ReleaseOptions options_;
  std::vector<Route> routes_;
  std::vector<Visit> lastVisit_;  ///< per node: the robot that entered it last in the plan
  std::int64_t step_ = 0;
  static constexpr std::int64_t kOrderPerStep = 1024;
};

}  // namespace fleet::traffic
