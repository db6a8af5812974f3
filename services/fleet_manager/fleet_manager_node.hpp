#pragma once

// The fleet manager without its DDS wiring: turns Task requests, TaskStatus reports and RobotState
// samples into dispatcher calls, and dispatcher results into the messages to publish.

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "closed_stations.hpp"
#include "fleet/core/admission_governor.hpp"
#include "fleet/core/config.hpp"
#include "fleet/fleet/dispatcher.hpp"
#include "fleet/fleet/task_reconciler.hpp"
#include "fleet/fleet/task_store.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/metrics/histogram.hpp"
#include "fleet/planning/distance_field_cache.hpp"
#include "fleet/site/site.hpp"
#include "fleet/traffic/roadmap.hpp"
#include "fleet/traffic/roadmap_travel.hpp"

namespace fleet::manager {

/// Where the tasks live: `"store": "sqlite:PATH"` (the default, `db`'s file) or
/// `"store": "postgresql://..."` (a libpq URL; several hosts with target_session_attrs=read-write
/// find the primary). PostgreSQL also holds the managers' lease: one of several managers is active.
struct StoreSettings {
  enum class Backend { Sqlite, Postgres } backend = Backend::Sqlite;
  std::string url;  ///< PostgreSQL's URL (SQLite's file is Settings::db)
  /// PostgreSQL: the lease's time to live, renewal period and standby poll (seconds).
  double leaseTtlS = 3.0;
  double leaseRenewS = 1.0;
  /// The lease's row in fleet_lease: managers of one fleet share it.
  std::string leaseName = "fleet_manager";
};

struct Settings {
  std::string db = "fleet.db";  ///< the SQLite file (`store: "sqlite:PATH"` sets it too)
  StoreSettings store;
  std::string stationsFile;  // JSON: {"stations": [...]} (a scenario file works too)
  bool syncFull = true;      // SQLite synchronous=FULL (survives power loss) or NORMAL (process crash)
  double tickS = 0.2;        // periodic assignment
  double leaseS = 1.0;       // a robot silent this long is lost
  /// A robot whose RobotState shows no task (or another) this long while the store has it carry
  /// a task in an active state gets that task requeued (0: never). See TaskReconciler.
  double reconcileS = 5.0;
  int maxAttempts = 3;
  /// Active tasks per station at most (0: no limit); see DispatcherConfig::stationCapacity.
  int stationCapacity = 2;
  /// `"station_capacity": "queue"`: each station takes as many active tasks as its line on the
  /// roadmap holds (dock and queue nodes); stations without one keep stationCapacity.
  bool stationCapacityFromLines = false;
  /// "task": a task loads its pickup and its drop-off for the whole task; "phase": its pickup until
  /// it has loaded, then its drop-off; "arrival": each from its robot's predicted arrival there
  /// (needs the site). See DispatcherConfig::stationLoad.
  StationLoad stationLoad = StationLoad::Task;
  int robotFailLimit = 3;    ///< failures in a row before a robot is held back (0: never)
  double robotHoldS = 60.0;  ///< ... for this long
  double batteryThreshold = 0.2;
  /// A charge task ends (done, by the manager) when the robot at the charger reports this battery;
  /// must exceed batteryThreshold.
  double chargeUntil = 0.9;
  /// The robot dwells at the charger at most this long (the charge goal's duration) and then
  /// reports the task done itself: a charger that does not charge cannot hold a robot for ever.
  double chargeMaxS = 1800.0;
  double nominalSpeed = 1.0;  // m/s, turns distance into travel time for allocation
  std::string clock = "wall";
  std::string metricsFile;  // written every second when set (JSON)
  /// "path": travel costs along grid distance fields on the site's map (or `mapFile`);
  /// "straight": straight lines, as before sites (kept to measure one against the other);
  /// "roadmap": free-flow times on the traffic layer's roadmap (what robots drive in reserved
  /// traffic: one-way aisles, turns, docks), from the site.
  std::string travelCost = "path";
  /// The roadmap of "roadmap" costs and "queue" capacities: the traffic manager's "roadmap" object.
  traffic::RoadmapOptions roadmap;
  // Optional map: travel costs from grid distance fields instead of straight lines.
  std::string mapFile;  // MovingAI .map
  double mapResolution = 1.0;
  double mapOriginX = 0.0;
  double mapOriginY = 0.0;
};

/// Seconds a robot needs for a task: to its first stop and on through the task's stops, along grid
/// distance fields when `cache` is given, else in straight lines.
TravelModel makeTravelModel(const StationMap& stations, std::shared_ptr<planning::DistanceFieldCache> cache,
                            double speed);

/// Seconds a robot needs for a task along the roadmap (free flow): to its first stop's dock and on
/// through the task's stops; infeasible where a stop has no dock or no route.
TravelModel makeRoadmapTravelModel(const StationMap& stations,
                                   std::shared_ptr<const traffic::RoadmapTravel> roads);

Settings readSettings(Config& cfg);

/// Opens the store the settings name (errors as the backends' open).
Expected<std::unique_ptr<TaskStore>> openTaskStore(const Settings& s);

/// A disagreement between a robot's reports and the store that outlasted `reconcile_s`, and what
/// the manager did about it; the service logs it as a warning.
struct Reconciled {
  std::string action;  ///< "requeued" (the robot dropped its task) or "stale_report" (logged only)
  std::string robot;
  std::string task;          ///< requeued: the task requeued; stale_report: the task the robot reports
  std::string reported;      ///< what the robot reports ("" no task)
  std::int64_t sinceNs = 0;  ///< since when (manager's clock)
  std::string message;
};

/// Everything a call produced that must go on the wire, in order (and `reconciled`, for the log).
struct Outbox {
  std::vector<msg::TaskAck> acks;
  std::vector<msg::TaskEvent> events;
  std::vector<msg::TaskAssignment> assignments;
  std::vector<Reconciled> reconciled;
};

struct Metrics {
  std::int64_t requests = 0;
  std::int64_t stored = 0;
  std::int64_t duplicates = 0;
  std::int64_t rejected = 0;
  std::int64_t assignments = 0;
  std::int64_t badOrders = 0;  ///< orders that could not be built (a station not on the site): task failed
  std::int64_t reconciledRequeued = 0;  ///< tasks requeued: their robot reported no task, or another
  std::int64_t reconciledStale = 0;     ///< robots that reported a task finished or not theirs
};

class FleetManagerNode {
 public:
  /// `site`: for travel costs along paths on its drivable map (a "map" file in the settings wins;
  /// neither: straight lines) or on its roadmap, and for station lines.
  /// `store`: the opened task store (openTaskStore); null: the node opens the settings' store.
  static Expected<std::unique_ptr<FleetManagerNode>> create(const Settings& s, StationMap stations,
                                                            std::int64_t nowNs,
                                                            std::shared_ptr<const site::Site> site = nullptr,
                                                            std::unique_ptr<TaskStore> store = nullptr);

  /// A batch of requests taken from the Task topic: stores new tasks in one group commit, answers
  /// each with a TaskAck, publishes the resulting events. Cancels are applied in order.
  void onRequests(const std::vector<msg::Task>& requests, std::int64_t nowNs, Outbox& out);
  void onStatus(const msg::TaskStatus& s, std::int64_t nowNs, Outbox& out);
  /// A robot's state, received at `nowNs` on the manager's clock: the lease runs on the receiver's
  /// clock, so a robot whose clock is off (or stamps INT64_MAX) is neither lost nor kept for ever.
  /// Its task_id is compared with the task the store has it carry (reconciled in tick).
  void onRobotState(const msg::RobotState& s, std::int64_t nowNs);
  void onRobotLost(const std::string& robotId, std::int64_t nowNs, Outbox& out);
  /// Reconciles the robots' reported tasks with the store (reconcile_s), then the dispatcher's tick.
  void tick(std::int64_t nowNs, Outbox& out);
  /// Assignments to re-publish after a restart (from the store), and each open task's state as a
  /// TaskEvent, so an adapter that starts later learns every stored open task from the history.
  [[nodiscard]] const Outbox& recovered() const { return recovered_; }
  /// The epoch of the lease this manager holds (0: none, the default): stamped on every
  /// TaskAssignment and TaskEvent from now on, and on recovered(), so that readers drop what a
  /// manager of an older epoch still sends (EpochFence).
  void setEpoch(std::int64_t epoch);
  /// Roadmap closures (TrafficClosure, as the traffic manager gets them): the stations they close
  /// hold back their waiting tasks with a stated reason (Dispatcher::setClosedStations). Read on
  /// the manager's own roadmap of the site (built at the first closure); without a site they are
  /// ignored. Returns what was wrong with each closure refused (for the log); nothing changes then.
  std::vector<std::string> onClosures(const std::vector<msg::TrafficClosure>& closures, std::int64_t nowNs,
                                      Outbox& out);

  [[nodiscard]] const Dispatcher& dispatcher() const { return *dispatcher_; }
  [[nodiscard]] const Metrics& metrics() const { return metrics_; }
  /// Bucket bounds of the queued → assigned latency (seconds): 10 ms to ~5.5 min, doubling.
  [[nodiscard]] static std::vector<double> assignLatencyBuckets();
  /// Records the queued → assigned latency into `h` (the service's metrics registry) from now on
  /// instead of the node's own histogram; call before the first tick. `h` must outlive the node.
  void recordAssignLatencyInto(metrics::Histogram& h) { assignLatency_ = &h; }
  [[nodiscard]] nlohmann::json metricsJson() const;

 private:
  FleetManagerNode() = default;
  void publish(DispatchResult r, std::int64_t nowNs, Outbox& out);
  /// A request on one task or robot (cancel, TC_PAUSE / TC_RESUME, TC_QUERY, TC_HOLD_ROBOT /
  /// TC_RELEASE_ROBOT, TC_CHANGE): its ack and what it changed (fleet_manager_control.cpp).
  void control(const msg::Task& req, std::int64_t nowNs, Outbox& out);
  /// The answer to a TC_QUERY request: the stored state, robot, reason and body (JSON in detail).
  msg::TaskAck query(const msg::Task& req, std::int64_t nowNs);
  /// TC_CHANGE: a waiting task's priority and/or deadline (Dispatcher::change).
  msg::TaskAck change(const msg::Task& req, std::int64_t nowNs, Outbox& out);
  /// The robot's order; error "internal" when a station of the task is not on the site.
  Expected<msg::TaskAssignment> toAssignment(const AssignmentOrder& o, std::int64_t nowNs);
  std::uint32_t nextRevision(const std::string& robot, std::int64_t nowNs);
  /// Acts on the disagreements between robots' reports and the store that outlasted the grace
  /// (fleet_manager_reconcile.cpp).
  void reconcile(std::int64_t nowNs, Outbox& out);
  /// Files the robots' time since the last tick with the admission governor and applies its factor
  /// to the dispatcher's line capacities.
  void govern(std::int64_t nowNs);
  /// A multi-stop task's robot reported stop `s.step`: remembered; true when it is a new stop
  /// (task_progress.cpp).
  bool noteStep(const msg::TaskStatus& s);
  /// Follows the stops of task `taskId` from now on, if it is a multi-stop task.
  void trackSteps(const std::string& taskId);
  /// Puts the task's current stop on event `e` (and keeps `e` as its last event).
  void stampStep(msg::TaskEvent& e);
  /// An event telling the task's new stop, its state unchanged.
  void stepEvent(const std::string& taskId, std::int64_t nowNs, Outbox& out);

  /// A multi-stop task's progress: its stop (from 1; 0 before the first report), its number of
  /// steps and the last event published about it.
  struct StepProgress {
    std::uint32_t step = 0;
    std::uint32_t steps = 0;
    msg::TaskEvent last;
  };

  Settings settings_;
  std::unique_ptr<TaskStore> store_;
  std::unique_ptr<Dispatcher> dispatcher_;
  std::map<std::string, std::uint32_t> eventSeq_;
  std::map<std::string, std::uint32_t> revisions_;
  std::map<std::string, std::int64_t> queuedAt_;
  std::map<std::string, StepProgress> progress_;
  TaskReconciler reconciler_{0};
  Outbox recovered_;
  std::int64_t epoch_ = 0;
  std::shared_ptr<const site::Site> site_;
  std::unique_ptr<ClosedStations> closures_;
  Metrics metrics_;
  /// The lines' places scaled by what the fleet's robot time did (admission by the lines' slots
  /// only): each robot's latest activity, filed for the time between ticks.
  bool governed_ = false;
  AdmissionGovernor governor_;
  std::map<std::string, RobotActivity> activity_;
  std::int64_t governedAtNs_ = -1;
  metrics::Histogram ownAssignLatency_{assignLatencyBuckets()};
  metrics::Histogram* assignLatency_ = &ownAssignLatency_;
};

}  // namespace fleet::manager
