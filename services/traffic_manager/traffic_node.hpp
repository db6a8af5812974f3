#pragma once

// The traffic manager without its DDS wiring: builds the roadmap from the site, places robots on it
// from their progress reports, plans everyone together (libs/traffic TrafficControl) and says which
// releases to publish.
//
// Robots are learnt from their reports, so a restarted manager rebuilds its state from what robots
// report: it waits `settleS` first (robots drive to the end of what the previous manager released
// and stop there), then places each robot on the node it last reported if it stands on it, else on
// the nearest node within `placeTolerance`. A robot that cannot be placed yet (off the roadmap, or
// another robot holds a conflicting node) is tried again on every tick and gets no release.
// Robots that do not follow releases, that hold (docked, paused, faulted) or are blocked by
// something the plan does not know, and robots not heard from for `robotTimeoutS`, are obstacles
// the plan goes around.

#include <cstdint>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fleet/core/config.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/risk/risk_lookup.hpp"
#include "fleet/site/site.hpp"
#include "fleet/traffic/distance_table.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/traffic_control.hpp"

namespace fleet::trafficmgr {

struct Settings {
  std::string site;             ///< site.json (required)
  double rateHz = 10.0;         ///< planning and release cycle
  double settleS = 3.0;         ///< wait for reports before planning (robots stop at their base ends)
  double robotTimeoutS = 5.0;   ///< a robot not heard from this long is an obstacle where it was
  double placeTolerance = 0.5;  ///< m from a roadmap node to be placed on it
  std::string clock = "wall";   ///< or "sim"
  bool lockstep = false;
  /// Robots sent to a pickup, drop-off or charger wait in line on its queue nodes, one at the dock
  /// (false: they are planned straight to the dock and wait wherever the planner leaves them).
  bool stationLines = true;
  /// Seconds added to driving into a node where the risk map's collision probability is 1 (in
  /// proportion below): people-dense space costs more, so routes go round it where that is worth
  /// it. 0: the risk map is not used.
  double riskCostS = 1.0;
  /// At most one risk update per this many seconds: each one recomputes the planner's distance
  /// tables (one search per robot's goal).
  double riskPeriodS = 2.0;
  /// A robot that reports itself blocked (a person in front of it) this long is made to yield: the
  /// nodes just ahead of it on its release cost `yieldCostS` more for `yieldForS`, and it is planned
  /// again instead of held, so it backs off or goes round when another way is shorter. 0: never
  /// (the robot waits for the person to leave, and a person whose way lies past it waits too).
  double yieldAfterS = 0.0;
  double yieldForS = 20.0;
  double yieldCostS = 60.0;
  traffic::RoadmapOptions roadmap;
  traffic::TrafficOptions traffic;
  /// Written when the traffic manager stops: its counters and each robot's base ends (load tests).
  std::string summaryFile;
};

/// Reads the settings; every problem is recorded in `cfg` (call cfg.finish() after).
Settings readSettings(Config& cfg);

class TrafficNode {
 public:
  TrafficNode(const site::Site& site, Settings settings, std::uint32_t epoch);
  // The planner's turn times refer to the roadmap held here: the node stays where it was made.
  TrafficNode(const TrafficNode&) = delete;
  TrafficNode& operator=(const TrafficNode&) = delete;

  [[nodiscard]] std::uint32_t epoch() const { return epoch_; }
  [[nodiscard]] const traffic::Roadmap& roadmap() const { return roadmap_; }
  [[nodiscard]] msg::Roadmap roadmapMessage(std::int64_t nowNs) const;

  /// A robot's report. Returns what was wrong with it (the report is then ignored in part or in
  /// whole, and the robot stays held where it was); nothing otherwise.
  std::optional<std::string> onProgress(const msg::TrafficProgress& p, std::int64_t nowNs);

  /// The collision-probability map: each node's cost becomes riskCostS × the probability at it.
  /// Returns whether it was applied (not when risk is off or the last one is younger than
  /// riskPeriodS).
  bool onRiskMap(const risk::RiskLookup& risk, std::int64_t nowNs);
  /// What a TrafficClosure did: nothing when refused (`error` says why; nothing changed).
  struct ClosureResult {
    std::optional<std::string> error;
    bool changed = false;   ///< the roadmap changed: publish it again (roadmapMessage)
    std::size_t nodes = 0;  ///< nodes and directed edges the closure covers now
    std::size_t edges = 0;
    std::vector<std::string> cutOff;  ///< stations it disconnects from the rest
  };
  /// Closes (active) or reopens a part of the roadmap by the closure's id. A closure given again
  /// under the same id replaces the earlier one; reopening an unknown id, or one already open,
  /// changes nothing. Node ids must be on the roadmap and lanes must be its edges, else the whole
  /// closure is refused. Robots standing on closed nodes may leave them; nothing is routed through.
  ClosureResult onClosure(const msg::TrafficClosure& c);
  /// Closure ids in force.
  [[nodiscard]] std::vector<std::string> closures() const;
  /// Grows with every change to what is open (the Roadmap message's revision).
  [[nodiscard]] std::uint32_t revision() const { return revision_; }

  /// Each node's current risk cost (s), empty before the first map.
  [[nodiscard]] const std::vector<float>& riskCost() const { return riskCost_; }

  /// Places robots, plans, and returns the releases that changed since they were last returned.
  std::vector<msg::TrafficRelease> tick(std::int64_t nowNs);
  /// The latest release of every placed robot (to publish again, e.g. after a reconnect).
  [[nodiscard]] std::vector<msg::TrafficRelease> allReleases() const;

  struct Counters {
    std::uint64_t reports = 0;
    std::uint64_t refused = 0;
    std::uint64_t releases = 0;
    std::uint64_t plannedSteps = 0;
    std::uint64_t replans = 0;
    std::uint64_t riskUpdates = 0;
    std::uint64_t yields = 0;    ///< robots made to yield to a person (yieldAfterS)
    std::uint64_t gaveBack = 0;  ///< robots blocked on their node that gave back the next (kGiveBackAfterS)
    double lastTickMs = 0.0;
    double maxTickMs = 0.0;
  };
  [[nodiscard]] const Counters& counters() const { return counters_; }
  /// Per robot placed: the ends of its base it reached short of its target, by why they were
  /// there (traffic::BaseEnds).
  [[nodiscard]] std::map<std::string, traffic::BaseEnds> baseEnds() const;
  [[nodiscard]] std::size_t robotsKnown() const { return robots_.size(); }
  [[nodiscard]] std::size_t robotsPlaced() const;
  /// Robot's index in the planner, -1 when not placed.
  [[nodiscard]] int indexOf(const std::string& robot) const;
  [[nodiscard]] const traffic::TrafficControl* control() const { return control_.get(); }
  /// Robots with a goal that reached no new node for `minS` seconds, each with what holds it
  /// (TrafficControl::explain): what an operator reads when the fleet stands still.
  [[nodiscard]] std::vector<std::string> stalled(std::int64_t nowNs, double minS) const;

 private:
  struct Robot {
    msg::TrafficProgress last;
    std::int64_t heardNs = 0;
    int index = -1;
    traffic::NodeId goal = traffic::kNoNode;
    int priority = 0;
    msg::TrafficRelease sent;
    traffic::NodeId lastNode = traffic::kNoNode;
    std::int64_t movedNs = 0;  ///< when it last reported a node other than lastNode
    std::int64_t blockedSinceNs = -1;
    bool gaveBack = false;           ///< blocked on its node long enough to give back the node after it
    std::int64_t yieldUntilNs = -1;  ///< yielding: its blocked report does not hold it until then
    std::vector<traffic::NodeId> yieldNodes;    ///< the nodes ahead that cost more meanwhile
    std::vector<traffic::NodeId> blockedAhead;  ///< its way ahead when it said it was blocked
  };
  /// Gives back what a robot blocked on its node has been released beyond it (kGiveBackAfterS),
  /// starts or ends its yielding (yieldAfterS); true when the node costs changed.
  bool updateYield(Robot& r, std::int64_t nowNs, bool timedOut);
  /// The risk costs plus the yielding robots' costs, to the planner.
  void applyNodeCost();
  [[nodiscard]] traffic::NodeId goalNode(const msg::TrafficProgress& p, std::string& why) const;
  [[nodiscard]] traffic::NodeId placeNode(const msg::TrafficProgress& p) const;
  void place(std::int64_t nowNs);
  void apply(Robot& r, std::int64_t nowNs);
  [[nodiscard]] msg::TrafficRelease toMessage(const std::string& id, const traffic::Release& rel,
                                              const Robot& r) const;

  Settings settings_;
  std::uint32_t epoch_;
  traffic::Roadmap roadmap_;
  std::unique_ptr<traffic::TrafficControl> control_;
  std::map<std::string, Robot> robots_;
  std::vector<std::string> byIndex_;
  std::int64_t startNs_ = -1;
  /// Free-flow distances to goals, to refuse a goal the roadmap does not connect to the robot
  /// (dropped when closures change what is open).
  mutable traffic::DistanceTable reach_;
  /// A closure in force: what it said, and what it closed (one part per area, nodes, lanes).
  struct InForce {
    msg::TrafficClosure said;
    std::vector<traffic::Closure> parts;
  };
  std::map<std::string, InForce> closures_;
  std::uint32_t revision_ = 0;
  std::int64_t riskNs_ = -1;
  std::vector<float> riskCost_;
  Counters counters_;
};

}  // namespace fleet::trafficmgr
