#pragma once

// What the HTTP API needs from the rest of the fleet, as an interface so the API can be tested
// without DDS: send task requests and wait for the manager's acknowledgements, and read the task
// and robot views kept from TaskEvent / RobotState.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <map>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "fleet/core/epoch_fence.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/validation/rejections.hpp"
#include "proximity_counter.hpp"
#include "robot_time.hpp"

namespace fleet::wms {

class EventLog;

/// A task as the API shows it: the latest event plus the task JSON we accepted.
struct TaskView {
  std::string id;
  msg::TaskState state = msg::TaskState::Queued;
  std::string robot;
  std::string reason;
  std::int64_t updatedNs = 0;
  std::uint32_t seq = 0;
  std::string body;  // the task JSON, when this adapter submitted it
  /// The station the manager chose for a charge / park task sent without one (TaskEvent.station).
  std::string station;
  /// When the task is expected done (TaskEvent.eta_ns of its newest event); 0: no estimate.
  std::int64_t etaNs = 0;
  /// A multi-stop task's stop its robot is at or driving to, from 1 (TaskEvent.step); 0: not known.
  std::uint32_t step = 0;
};

class TaskGateway {
 public:
  virtual ~TaskGateway() = default;
  /// Sends the requests and waits for one ack each. A missing ack (timeout, manager unreachable)
  /// is nothing in its slot.
  virtual std::vector<std::optional<msg::TaskAck>> submit(const std::vector<msg::Task>& requests,
                                                          std::chrono::milliseconds timeout) = 0;
  /// Asks the manager where task `id` stands (TC_QUERY); nothing on timeout.
  virtual std::optional<msg::TaskAck> query(const std::string& id, const std::string& requestId,
                                            std::chrono::milliseconds timeout) {
    msg::Task q;
    q.task_id = id;
    q.request_id = requestId;
    q.control = msg::TaskControl::Query;
    return submit({q}, timeout)[0];
  }
  /// Whether a fleet manager is matched on the Task topic.
  [[nodiscard]] virtual bool managerOnline() const = 0;
  /// Publishes a roadmap closure (or its reopening) to the traffic manager; what stopped it
  /// otherwise (no permission for the topic, a transport error).
  virtual std::optional<std::string> sendClosure(const msg::TrafficClosure&) {
    return std::string("this adapter cannot send closures");
  }
  /// Whether a traffic manager is matched on the TrafficClosure topic.
  [[nodiscard]] virtual bool trafficManagerOnline() const { return false; }
};

/// The clock people-seen lists are aged by (receipt and lookup): steady, in ns.
inline std::int64_t steadyNowNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

/// Task and robot views and the event stream, fed from DDS (or by tests). Thread-safe.
class FleetView {
 public:
  explicit FleetView(std::size_t maxTasks = 200'000) : maxTasks_(maxTasks) {}
  void onEvent(const msg::TaskEvent& e);
  /// Several events, logged in one transaction (the DDS gateway's batch).
  void onEvents(const std::vector<msg::TaskEvent>& events);
  /// Where task events are also logged, with their event ids (event_log.hpp); nullptr: nowhere.
  /// The HTTP API sets it for its life.
  void setEventLog(EventLog* log);
  /// Stops logging into `log` if it is the one set (another API on the same view keeps its own).
  void dropEventLog(const EventLog* log);
  /// Appends the event log refused (a disk error), and the last reason.
  [[nodiscard]] std::uint64_t eventLogFailures() const { return logFailures_.load(); }
  [[nodiscard]] std::string eventLogProblem() const;
  /// Events dropped because a fleet manager of a newer lease epoch had spoken (EpochFence): a
  /// manager that lost its lease cannot change a task's view, the event log or the stream.
  [[nodiscard]] std::uint64_t staleEpochEvents() const;
  void onAccepted(const std::string& id, const std::string& body, msg::TaskState state, std::int64_t nowNs);
  void onRobot(const msg::RobotState& s);
  /// The risk map service's latest map (for the dashboard's iso-level layer).
  void onRisk(msg::RiskMap m);
  /// The traffic manager's roadmap (the dashboard's traffic layer). One of a new epoch (a
  /// restarted traffic manager) drops the releases of earlier epochs.
  void onRoadmap(msg::Roadmap m);
  /// A closure in force (active) or reopened (forgotten): the roadmap closures operators made.
  void onClosure(const msg::TrafficClosure& c);
  /// Closures in force, by id.
  [[nodiscard]] std::map<std::string, msg::TrafficClosure> closures() const;
  /// A robot's latest release. One of an epoch before the roadmap's is stale and ignored, as is a
  /// robot beyond the first kMaxReleaseRobots.
  void onRelease(const msg::TrafficRelease& r);
  static constexpr std::size_t kMaxReleaseRobots = 10'000;
  /// The people robot `p.robot_id` sees, received at `receivedNs` (a steady clock's ns). Refused,
  /// and counted as PeopleSeen:unknown_robot, for a robot the view has no state of (false then);
  /// the caller has checked the sample itself (validation::check).
  bool onPeopleSeen(msg::PeopleSeen p, std::int64_t receivedNs);
  /// Robot `robot`'s latest people seen, unless stale at `nowNs` (same clock as receivedNs): older
  /// than kPeopleSeenMaxAgeNs by the time it came, or by the stamp of the robot's latest state.
  [[nodiscard]] std::optional<msg::PeopleSeen> peopleSeen(const std::string& robot, std::int64_t nowNs) const;
  /// Every robot's people seen that is not stale at `nowNs`, by robot.
  [[nodiscard]] std::map<std::string, msg::PeopleSeen> allPeopleSeen(std::int64_t nowNs) const;
  static constexpr std::int64_t kPeopleSeenMaxAgeNs = 2'000'000'000;
  /// Contacts and near misses: one look at the robots' latest states (those heard of within
  /// kLiveRobotNs of the newest, by stamp: a vanished robot's last pose is not an obstacle) and the
  /// people seen now. The caller decides how often (the DDS gateway: at most 20 times a second).
  void updateProximity(std::int64_t nowNs);
  static constexpr std::int64_t kLiveRobotNs = 5'000'000'000;
  struct Proximity {
    ProximityCounts robotRobot;
    ProximityCounts robotPerson;
    ProximityParams params;
    std::uint64_t version = 0;  ///< grows whenever a figure changes
  };
  [[nodiscard]] Proximity proximity() const;
  /// Events from the event log this view may not have heard (at start, and those other replicas
  /// logged): each changes the view only when its task is unknown or older in the view.
  void catchUp(const std::vector<msg::TaskEvent>& events);
  /// A task as the manager's store has it (the answer to a query), for a task the view lacked.
  void onStored(const msg::TaskAck& a, std::int64_t nowNs);
  /// Samples refused (or repaired) on their way into the view, for /v1/metrics.
  [[nodiscard]] validation::Rejections& rejections() { return rejections_; }
  [[nodiscard]] const validation::Rejections& rejections() const { return rejections_; }

  [[nodiscard]] std::optional<TaskView> task(const std::string& id) const;
  [[nodiscard]] std::vector<TaskView> tasks(std::optional<msg::TaskState> state, std::size_t limit) const;
  [[nodiscard]] std::vector<msg::RobotState> robots() const;
  /// Where the robots' time went since the view started (robot_time.hpp): per robot and the fleet's.
  [[nodiscard]] RobotTimeLedger robotTime() const;
  /// The latest risk map and a count that grows with every new one (0, nullptr: none yet).
  [[nodiscard]] std::pair<std::uint64_t, std::shared_ptr<const msg::RiskMap>> risk() const;
  /// The latest roadmap and a count that grows with every new one (0, nullptr: none yet).
  [[nodiscard]] std::pair<std::uint64_t, std::shared_ptr<const msg::Roadmap>> roadmap() const;
  /// Every robot's latest release, by robot id, and a count that grows with every change.
  using Releases = std::map<std::string, std::shared_ptr<const msg::TrafficRelease>>;
  [[nodiscard]] std::pair<std::uint64_t, Releases> releases() const;
  [[nodiscard]] std::map<std::string, std::int64_t> countByState() const;

  /// Events after `cursor` (a running count), waiting up to `timeout` for one to arrive. Returns the
  /// new cursor. Events older than the buffer are skipped.
  std::uint64_t eventsAfter(std::uint64_t cursor, std::chrono::milliseconds timeout,
                            std::vector<msg::TaskEvent>& out) const;
  [[nodiscard]] std::uint64_t eventCursor() const;

 private:
  mutable std::mutex m_;
  mutable std::condition_variable cv_;
  std::size_t maxTasks_;
  std::map<std::string, TaskView> tasks_;
  std::deque<std::string> insertion_;
  std::map<std::string, msg::RobotState> robots_;
  RobotTimeLedger robotTime_;
  struct Seen {
    msg::PeopleSeen people;
    std::int64_t receivedNs = 0;
  };
  std::map<std::string, Seen> people_;                                // by robot; only robots in robots_
  [[nodiscard]] bool fresh(const Seen& s, std::int64_t nowNs) const;  // m_ held
  mutable std::mutex proximityMutex_;                                 // the counter runs outside m_
  ProximityCounter proximity_;
  std::shared_ptr<const msg::RiskMap> risk_;
  std::uint64_t riskCount_ = 0;
  std::shared_ptr<const msg::Roadmap> roadmap_;
  std::uint64_t roadmapCount_ = 0;
  Releases releases_;
  std::map<std::string, msg::TrafficClosure> closures_;
  std::uint64_t releaseCount_ = 0;
  std::deque<msg::TaskEvent> events_;
  std::uint64_t eventCount_ = 0;
  mutable std::mutex logMutex_;  // the log pointer and its last problem; never under m_
  EventLog* log_ = nullptr;
  std::string logProblem_;
  std::atomic<std::uint64_t> logFailures_{0};
  EpochFence managerEpoch_;  // under logMutex_
  void viewEvent(const msg::TaskEvent& e);
  validation::Rejections rejections_;
};

}  // namespace fleet::wms
