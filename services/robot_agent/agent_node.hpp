#pragma once

// The robots of one robot_agent process without its DDS wiring: builds an Agent per hosted robot
// from the world and the settings, checks every sample at the edge (libs/validation), hands each
// one to the robot it is for, steps all robots in parallel and returns their outputs in robot
// order, to be written in that order (so a lockstep run's traffic does not depend on thread
// timing).
//
// One cycle: onFrames, onRobotStates, onAssignments, onReleases, onRiskMaps (each with what was
// taken from its topic since the last cycle, in this order), then step(). Samples refused at the
// edge come out of takeRefusals() for the process to count and log.

#include <cstdint>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

#include "agent.hpp"
#include "agent_settings.hpp"
#include "agent_world.hpp"
#include "fleet/core/epoch_fence.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/validation/rejections.hpp"
#include "people_report.hpp"
#include "pose_store.hpp"
#include "worker_pool.hpp"

namespace fleet::agent {

/// A sample refused at the node's edge. `key` ("SensorFrame:non_finite", "risk_map") is what to
/// count and rate-limit by, `message` says which sample and why, for the log.
struct Refusal {
  std::string key;
  std::string message;
};

/// What the node made of the world's map when it was built (for the start-up log).
struct MapFacts {
  std::optional<std::string> siteName;  ///< none: no site (a scenario with its map inline)
  std::size_t zones = 0;
  bool speedLimits = false;   ///< the site has speed-limit zones the motion gate enforces
  std::size_t wallFaces = 0;  ///< walls the localizers match their scan lines against
};

class AgentNode {
 public:
  /// An Agent for every robot of `world` (only those in `s.only` when it names any). Fails when
  /// none is left; an agent that cannot be built (an unknown planner) throws std::invalid_argument.
  /// A robot with a pose in `resume` (the pose file's fresh ones) starts its localization there.
  static Expected<std::unique_ptr<AgentNode>> create(const World& world, const Settings& s,
                                                     const SavedPoses& resume = {});

  // The inputs of a cycle; samples are checked, then handed to the robot they are for.
  /// A frame for a robot hosted elsewhere is ignored.
  void onFrames(std::vector<msg::SensorFrame> frames);
  /// Robots hosted elsewhere, for every agent here (this process's own robots learn each other's
  /// state in step()).
  void onRobotStates(std::vector<msg::RobotState> states);
  /// A refused order for a hosted robot is answered by that robot's failed TaskStatus naming why
  /// (when its task id can be named), so the manager retries it elsewhere.
  void onAssignments(std::vector<msg::TaskAssignment> assignments);
  /// Reserved traffic: each release to the robot it names (one hosted elsewhere: ignored).
  void onReleases(std::vector<msg::TrafficRelease> releases);
  /// Only the newest map counts; decoded once and shared read-only by every agent. Ignored with
  /// `useRisk` off (the samples are still checked).
  void onRiskMaps(std::vector<msg::RiskMap> maps);

  /// Steps every agent at `nowNs` (in parallel), numbers the commands by cycle, adds each robot's
  /// people seen when its report is due (AgentOutput::people, PeopleReport), and hands each
  /// robot's new state to the others of this process (exactly one cycle later for them: over DDS a
  /// state came one or two cycles late depending on timing, and lockstep replays differed).
  const std::vector<AgentOutput>& step(std::int64_t nowNs, double dt);

  /// Refused samples since the last call (oldest first).
  std::vector<Refusal> takeRefusals();

  [[nodiscard]] std::size_t size() const { return agents_.size(); }
  [[nodiscard]] const Agent& agent(std::size_t i) const { return *agents_[i]; }
  /// The hosted robot `id`, or null.
  [[nodiscard]] const Agent* find(const std::string& id) const;
  /// The last cycle's outputs, in robot order (defaults before the first cycle).
  [[nodiscard]] const std::vector<AgentOutput>& outputs() const { return outs_; }
  [[nodiscard]] std::uint64_t cycles() const { return cycles_; }
  [[nodiscard]] unsigned threads() const { return pool_.threads(); }
  [[nodiscard]] const Settings& settings() const { return settings_; }
  [[nodiscard]] const MapFacts& mapFacts() const { return facts_; }
  /// Samples refused at the edge, by topic and reason.
  [[nodiscard]] const validation::Rejections& rejections() const { return rejections_; }

  /// Summed over the hosted robots.
  [[nodiscard]] Agent::Conduct conduct() const;
  [[nodiscard]] LineStats lineStats() const;
  [[nodiscard]] ReleaseCounts releaseCounts() const;
  /// Times a hosted robot's pose was doubted by its laser lines (PoseWatch), cumulative.
  [[nodiscard]] std::uint64_t poseDoubts() const;
  /// Robots resumed with wheel totals from the pose file that did not fit their first reading (the
  /// driver restarted): they started less certain (Localizer::resumeTotalsRefused).
  [[nodiscard]] std::uint64_t resumeTotalsRefused() const;
  /// Driver restarts seen under the running agents, summed (Localizer::driverRestarts).
  [[nodiscard]] std::uint64_t driverRestarts() const;
  /// For the --metrics file: "samples" (refused at the edge), "conduct", "localization", "traffic".
  [[nodiscard]] nlohmann::json statsJson() const;

 private:
  AgentNode(Settings s, unsigned threads) : settings_(std::move(s)), pool_(threads) {}
  Agent* hosted(const std::string& id);
  /// The edge: why `sample` may not be used (a refusal is then queued), or nothing.
  template <class T>
  std::optional<validation::Rejection> refused(T& sample);
  /// `samples` without those refused.
  template <class T>
  std::vector<T> admitted(std::vector<T> samples);

  Settings settings_;
  MapFacts facts_;
  std::vector<std::unique_ptr<Agent>> agents_;
  std::map<std::string, Agent*> byId_;
  WorkerPool pool_;
  std::vector<AgentOutput> outs_;
  /// Each robot id heard of, numbered once for all hosted agents (Agent::onOtherRobot by slot).
  std::size_t slotOf(const std::string& id) { return slots_.try_emplace(id, slots_.size()).first->second; }
  std::unordered_map<std::string, std::size_t> slots_;
  std::vector<std::size_t> hostedSlot_;            // per hosted agent, its robot's slot
  std::vector<std::optional<OtherRobot>> others_;  // per hosted agent, its state this cycle as others see it
  std::vector<PeopleReport> peopleReports_;        // one per agent, phases spread over the period
  std::uint64_t cycles_ = 0;
  validation::Rejections rejections_;
  std::vector<Refusal> refusals_;
  EpochFence managerEpoch_;  ///< TaskAssignments of an older fleet manager epoch are dropped
};

}  // namespace fleet::agent
