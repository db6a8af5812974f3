#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/fleet/allocator.hpp"
#include "fleet/fleet/robot_registry.hpp"
#include "fleet/fleet/station_choice.hpp"
#include "fleet/fleet/station_map.hpp"
#include "fleet/fleet/task_eta.hpp"
#include "fleet/fleet/task_store.hpp"

namespace fleet {

enum class StationLoad { Task, Phase, Arrival };

/// What admission by predicted arrival knows of the site; the fleet manager fills it from the
/// roadmap (free-flow times, nobody in the way).
struct StationTimes {
  /// Seconds from a position to a station's dock (+infinity: no way there).
  std::function<double(Vec2, const std::string&)> toStation;
  /// Seconds from one station's dock to another's.
  std::function<double(const std::string&, const std::string&)> between;
  /// Seconds of a station's least dock cycle without the dwell: enter from the queue head, leave.
  std::function<double(const std::string&)> dockMove;

  [[nodiscard]] bool known() const { return toStation && between && dockMove; }
};

struct DispatcherConfig {
  AllocationPolicy policy;
  std::int32_t maxAttempts = 3;  ///< a task that failed this many assignments is failed for good
  std::int64_t leaseNs = 1'000'000'000;
  /// The Hungarian method costs about k²·K steps for k = min(tasks, robots), K = max; above this
  /// many a tick uses the greedy allocator (200 tasks × 1,000 robots = 4e7 takes ~15 ms).
  double hungarianMaxWork = 4e7;
  /// With a long backlog only this many waiting tasks enter one allocation: pinned tasks first
  /// (a robot's own charge task), then by priority, deadline and age. Bounds a tick's cost.
  std::size_t maxCandidates = 1000;
  /// At most this many active tasks use one station (pickup, drop-off or target) at a time; a
  /// task whose station is full waits in the queue (oldest first) instead of sending another robot
  /// to crowd the station. 0: no limit.
  std::size_t stationCapacity = 0;
  /// Per-station capacities that override stationCapacity (0: no limit at that station). With
  /// reserved traffic, each station's line on the roadmap (dock and queue nodes) gives its own.
  std::unordered_map<std::string, std::size_t> stationCapacities;
  /// How an active task loads its stations. Task: its pickup and its drop-off from assignment to
  /// the end, so with 9 stations and a capacity of 2 at most ~8 tasks are active while 20 robots
  /// wait. Phase: its pickup until it has loaded there, its drop-off for the whole task (a loaded
  /// robot must not find its drop-off's line full); admission checks both. Arrival: a robot counts
  /// in a station's line from the time it is predicted to get there until it is served
  /// (fleet/core/station_slots.hpp), so a robot minutes away holds no place now; a task is admitted
  /// when its pickup's line has a place when the nearest idle robot could get there and its
  /// drop-off's line one after it has loaded (needs `stationTimes`; docs/algorithms.md, "Admission
  /// by predicted arrival").
  StationLoad stationLoad = StationLoad::Task;
  /// The roadmap's free-flow times. When known, besides admission by predicted arrival they price
  /// the queues: a transport task costs a robot its travel plus the wait it would have in its
  /// pickup's and its drop-off's lines behind the robots booked there (docs/algorithms.md,
  /// "Assignment: expected queue wait").
  StationTimes stationTimes;
  /// A robot that fails this many tasks in a row gets no task for robotHoldNs: an agent that fails
  /// every order at once (a pose estimate inside a shelf after a restart) would otherwise burn
  /// through the queue, each task failing its attempts on it. 0: never held.
  std::int32_t robotFailLimit = 3;
  std::int64_t robotHoldNs = 60'000'000'000;
  /// A charge task is done when its robot stands within chargeReach (m) of the charging station
  /// with a battery of at least chargeUntil: the dispatcher completes it and releases the robot
  /// (the robot itself dwells at the charger until then). Must exceed policy.batteryThreshold, or a
  /// robot released below the threshold would be sent straight back.
  double chargeUntil = 0.9;
  double chargeReach = 0.5;
  /// A robot within this distance (m) of a station stands on it. A charge or park task without a
  /// station is given a free one nobody stands on when there is one (StationChooser).
  double standReach = 0.5;
};

/// A state change to publish as `TaskEvent`.
struct TaskEvent {
  std::string taskId;
  TaskState state = TaskState::Queued;
  std::string robotId;
  std::string reason;
  std::int64_t stampNs = 0;
  std::string station;  ///< the station the dispatcher chose for the task (TaskRecord::stationChosen)
  /// When the task is expected to be done (TaskEta), as estimated at this transition; 0: no
  /// estimate (no robot could take it, or it ended without being done).
  std::int64_t etaNs = 0;
  /// The event of a change (Dispatcher::change): priority and deadlineNs are the values in force.
  bool changed = false;
  std::int32_t priority = 0;
  std::int64_t deadlineNs = 0;
};

/// A task a robot must now execute (publish as `TaskAssignment`, key robot_id).
struct AssignmentOrder {
  std::string robotId;
  Task task;
  std::int64_t revision = 0;  ///< the task record's revision: newer orders supersede older ones
  bool paused = false;        ///< the robot holds where it is with the task until resumed
};

/// What a call changed; the service publishes it. Everything in it is already committed.
struct DispatchResult {
  std::vector<AssignmentOrder> assignments;
  /// Robots whose task was withdrawn (cancelled) or completed by the dispatcher (charged), or that
  /// were held or released idle: publish an empty assignment (paused while the robot is held). A
  /// robot never appears both here and in `assignments` of one result.
  std::vector<std::string> revoked;
  std::vector<TaskEvent> events;
  std::vector<Error> errors;  ///< problems that did not stop the call (a store error on one task)

  void append(DispatchResult other);
};

struct DispatcherCounters {
  std::int64_t submitted = 0;
  std::int64_t assigned = 0;
  std::int64_t done = 0;
  std::int64_t failed = 0;
  std::int64_t cancelled = 0;
  std::int64_t requeued = 0;
  std::int64_t robotsLost = 0;
  std::int64_t robotsHeld = 0;  ///< times a robot was held back after robotFailLimit failures in a row
  std::int64_t charged = 0;     ///< charge tasks the dispatcher completed (battery reached chargeUntil)
};

class StationLines;  // dispatcher_arrival.cpp, src/station_lines.hpp

/// The fleet manager's logic without DDS: owns the open tasks in memory, the robot registry and
/// the allocation, and writes every change through the TaskStore before reporting it. Not
/// thread-safe: the service calls it from one thread (or under one lock).
class Dispatcher {
 public:
  Dispatcher(TaskStore& store, StationMap stations, TravelModel travel, DispatcherConfig cfg = {});
  Dispatcher(TaskStore& store, StationMap stations, TravelCost travel, DispatcherConfig cfg = {})
      : Dispatcher(store, std::move(stations), perPair(std::move(travel)), cfg) {}

  /// Rebuilds the open tasks from the store after a restart. Active tasks stay with their robots
  /// (whose lease starts now) and are returned as assignments to re-publish.
  Expected<DispatchResult> recover(std::int64_t nowNs);

  /// Validates against the station map and stores durably (one group commit). Per task: the stored
  /// record, or an error (invalid / unknown_station → 400, conflict → 409, storage → 503). With
  /// `fields`, an invalid task's field errors are also returned there, one list per task (empty
  /// for the others): the one validation of a task on its way into the store.
  std::vector<Expected<SubmitResult>> submit(const std::vector<Task>& tasks, std::int64_t nowNs,
                                             DispatchResult* out = nullptr,
                                             std::vector<std::vector<FieldError>>* fields = nullptr);

  /// Stale: a sample older than the newest one of the robot, ignored.
  RobotRegistry::Update onRobotState(const RobotObservation& o);
  /// DDS liveliness lost: the robot's task is requeued at once.
  DispatchResult onRobotLost(const std::string& robotId, std::int64_t nowNs);
  /// A robot's report on its task. Intermediate happy-path steps it skipped are filled in; failed
  /// is turned into requeued while attempts remain. Errors: not_found (unknown or closed task),
  /// wrong_robot (the robot does not hold it; the service should revoke), illegal_transition.
  Expected<DispatchResult> onTaskStatus(const std::string& robotId, const std::string& taskId,
                                        TaskState state, const std::string& reason, std::int64_t nowNs);
  /// The robot does not carry the task it holds here (its states have shown no task, or another,
  /// for longer than the manager's reconcile grace): the task is requeued with `reason` (no
  /// attempt counted; the retry goes to another idle robot if there is one) and the robot is free
  /// for new work. Errors as onTaskStatus: not_found, wrong_robot.
  Expected<DispatchResult> requeueDropped(const std::string& robotId, const std::string& taskId,
                                          const std::string& reason, std::int64_t nowNs);
  /// Operator cancel; an active task is withdrawn from its robot.
  Expected<DispatchResult> cancel(const std::string& taskId, const std::string& reason, std::int64_t nowNs);
  /// Fails an open task for good, whatever its attempts (an internal error: the service cannot
  /// build the task's order); an active task is withdrawn from its robot. Errors as cancel.
  Expected<DispatchResult> fail(const std::string& taskId, const std::string& reason, std::int64_t nowNs);
  /// Operator pause / resume (durable): a paused waiting task is not dispatched; an active one is
  /// re-sent to its robot with `paused` set, and the robot stands still with it until resumed.
  /// Errors as cancel (not_found, illegal_transition for a finished task).
  Expected<DispatchResult> setPaused(const std::string& taskId, bool paused, std::int64_t nowNs);
  /// Operator hold of a robot (in memory): its active task is paused (setPaused) and it gets no new
  /// task until released, which resumes that task; idle, it is sent an empty paused order (it
  /// stands where it is). not_found for a robot never seen.
  Expected<DispatchResult> setRobotHeld(const std::string& robotId, bool held, std::int64_t nowNs);
  [[nodiscard]] bool robotHeld(std::string_view robotId) const { return held_.count(robotId) > 0; }
  /// Stations closed at run time (a roadmap closure closed or cut off their dock), each with why
  /// (e.g. "closure 'spill': wet floor"); replaces the set before. A waiting task with a closed
  /// station is not assigned, and its wait reason (an event) says "station D-2 closed: ..."; once
  /// reopened it says so and the task is assigned again. An active task is left to its robot (the
  /// traffic manager holds it at its last released node). dispatcher_closures.cpp.
  DispatchResult setClosedStations(std::map<std::string, std::string, std::less<>> closed,
                                   std::int64_t nowNs);
  [[nodiscard]] const std::map<std::string, std::string, std::less<>>& closedStations() const {
    return closedStations_;
  }
  /// Operator change of a waiting task's priority and/or deadline, stored (TaskStore::change) and
  /// in force from the next allocation: every tick orders the queue (admission at busy stations,
  /// the candidates of a long backlog) and costs its tasks by the values held here
  /// (dispatcher_change.cpp). One event with `changed` set when a value differs; nothing when the
  /// values were already in force. Errors: not_found; illegal_transition for a task that is active
  /// or finished (the message names its state); invalid, with the field errors in `fields` when
  /// given (a value out of range, a deadline before the task's created_ns).
  Expected<DispatchResult> change(const ChangeRequest& q, std::vector<FieldError>* fields = nullptr);

  /// Periodic work: expire leases (requeue the lost robots' tasks), complete the charge tasks whose
  /// robot is charged (releasing it), send low robots to charge, and assign waiting tasks to idle
  /// robots. A charge or park task without a station is given the nearest free station of its kind
  /// for its robot with the assignment (stored with it); while every such station is taken it waits,
  /// and its reason says so.
  DispatchResult tick(std::int64_t nowNs);
  /// Scales the per-station capacities (`stationCapacities`, the lines' places) to floor(k × places),
  /// k ≥ 1, from the next tick on: the admission governor's factor (fleet/core/admission_governor.hpp).
  void setLineScale(double k);
  [[nodiscard]] double lineScale() const { return lineScale_; }
  /// Waiting tasks the last tick's admission held back for want of a place in a line (0 when no
  /// robot was idle or no task waited).
  [[nodiscard]] std::size_t heldInLines() const { return heldInLines_; }

  [[nodiscard]] const RobotRegistry& robots() const { return registry_; }
  [[nodiscard]] const StationMap& stations() const { return stations_; }
  [[nodiscard]] const std::map<std::string, TaskRecord, std::less<>>& openTasks() const { return open_; }
  [[nodiscard]] std::size_t waitingCount() const;
  [[nodiscard]] std::size_t activeCount() const;
  [[nodiscard]] const DispatcherCounters& counters() const { return counters_; }

 private:
  void applied(const TaskRecord& r, DispatchResult& out);
  /// The ETA of the transition to `r` (TaskEta), and what it teaches the estimator.
  [[nodiscard]] std::int64_t etaOf(const TaskRecord& r);
  /// The ETA of an open task now, without teaching the estimator (a pause, a new wait reason).
  [[nodiscard]] std::int64_t currentEta(const TaskRecord& r, std::int64_t nowNs) const;
  [[nodiscard]] std::int64_t waitingEta(const TaskRecord& r, std::int64_t nowNs) const;
  /// Counts the waiting tasks per priority (`delta` +1 when one enters the queue, -1 when it leaves).
  void countWaiting(const TaskRecord& r, int delta);
  /// The open task, or not_found / illegal_transition ("already done") for an operator request.
  Expected<std::map<std::string, TaskRecord, std::less<>>::iterator> findOpen(const std::string& taskId);
  void requeueOrFail(const TaskRecord& r, bool failedByRobot, const std::string& reason, std::int64_t nowNs,
                     DispatchResult& out);
  /// Charge tasks whose robot is at the station with battery >= chargeUntil → done, robot revoked.
  void completeCharged(std::int64_t nowNs, DispatchResult& out);
  void chargeLowRobots(std::int64_t nowNs, DispatchResult& out);
  void allocate(std::int64_t nowNs, DispatchResult& out);
  /// The assignment itself; `chooser` is set when a waiting task needs a station chosen.
  void assignWaiting(std::vector<Task> waiting, StationChooser* chooser, std::int64_t nowNs,
                     DispatchResult& out);
  /// Cancel or fail (`to`) an open task; an active one's robot is revoked.
  Expected<DispatchResult> close(const std::string& taskId, TaskState to, const std::string& reason,
                                 std::int64_t nowNs);
  /// Says in their reason why charge / park tasks without a station still wait (every station of
  /// their kind taken), and takes it back once one is free again.
  void noteStationWaits(const StationChooser& chooser, std::int64_t nowNs, DispatchResult& out);
  /// The closed station of `t` (nullptr: none) and the wait reasons of the waiting tasks it holds.
  [[nodiscard]] const std::string* closedStationOf(const Task& t) const;
  void noteClosedStations(std::int64_t nowNs, DispatchResult& out);
  /// A task admission held back: the first of its stations whose line was full, and its capacity.
  struct HeldAtStation {
    std::string taskId;
    std::string station;  ///< empty: not looked at, every idle robot went to an older task
    std::size_t capacity = 0;
    bool byArrival = false;  ///< no place for when a robot could get there
  };
  /// Drops from `waiting` the tasks whose stations are at capacity (DispatcherConfig); returns them.
  std::vector<HeldAtStation> admitByStationCapacity(std::vector<Task>& waiting) const;
  /// The same by predicted arrival (StationLoad::Arrival): keeps at most as many tasks as there are
  /// `idle` robots, the oldest that get a place (dispatcher_arrival.cpp).
  std::vector<HeldAtStation> admitByArrival(std::vector<Task>& waiting,
                                            const std::vector<RobotInfo>& idle) const;
  [[nodiscard]] std::size_t capacityOf(const std::string& station) const;
  /// The robots with an active task booked in the lines of the stations they are bound for, at
  /// their predicted arrival (needs `stationTimes`; dispatcher_arrival.cpp).
  [[nodiscard]] StationLines bookLines() const;
  /// Says in their reason that (and where) the held tasks wait for a place in a station's line,
  /// and when one has waited past its deadline.
  void noteAdmissionWaits(const std::vector<HeldAtStation>& held, std::int64_t nowNs, DispatchResult& out);

  TaskStore& store_;
  StationMap stations_;
  TravelModel travel_;
  DispatcherConfig cfg_;
  RobotRegistry registry_;
  HungarianAllocator hungarian_;
  GreedyAllocator greedy_;
  std::map<std::string, TaskRecord, std::less<>> open_;
  DispatcherCounters counters_;
  struct FailStreak {
    std::int32_t count = 0;
    std::int64_t holdUntilNs = 0;
  };
  std::map<std::string, FailStreak, std::less<>> failStreak_;  // by robot id
  /// Task id -> the robot that failed it last: the retry goes to another idle robot if there is
  /// one (a robot boxed in at its parking place failed the same task three times in a row).
  std::map<std::string, std::string, std::less<>> failedBy_;
  std::set<std::string, std::less<>> held_;                         // robots held by the operator
  std::map<std::string, std::string, std::less<>> closedStations_;  // station -> why
  TaskEta eta_;
  /// Waiting tasks by priority: how many are ahead of a task entering the queue.
  std::map<std::int32_t, std::size_t, std::greater<>> waitingByPriority_;
  double lineScale_ = 1.0;
  std::size_t heldInLines_ = 0;
};

}  // namespace fleet
