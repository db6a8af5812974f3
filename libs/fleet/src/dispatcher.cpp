#include "fleet/fleet/dispatcher.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <set>
#include <tuple>
#include <unordered_map>

#include "fleet/core/ids.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet {
namespace {

/// Happy path of a task kind, from assigned to done.
std::vector<TaskState> happyPath(TaskKind kind) {
  using S = TaskState;
  if (kind == TaskKind::Transport) {
    return {S::Assigned, S::EnRoute, S::Loading, S::Delivering, S::Unloading, S::Done};
  }
  return {S::Assigned, S::EnRoute, S::Done};
}

// RobotState carries the battery as a float: 0.9f reads 0.8999999762 as a double.
constexpr double kBatteryEps = 1e-6;

std::string chargeTaskId(const std::string& robot, std::int64_t nowNs) {
  std::string id = "charge.";
  id += std::to_string(nowNs);
  id += '.';
  if (id.size() + robot.size() <= kMaxIdLength) {
    id += robot;
  } else {
    id += std::to_string(std::hash<std::string>{}(robot));
  }
  return id;
}

}  // namespace

void DispatchResult::append(DispatchResult other) {
  for (auto& a : other.assignments) {
    assignments.push_back(std::move(a));
  }
  for (auto& r : other.revoked) {
    revoked.push_back(std::move(r));
  }
  for (auto& e : other.events) {
    events.push_back(std::move(e));
  }
  for (auto& e : other.errors) {
    errors.push_back(std::move(e));
  }
}

Dispatcher::Dispatcher(TaskStore& store, StationMap stations, TravelModel travel, DispatcherConfig cfg)
    : store_(store),
      stations_(std::move(stations)),
      travel_(std::move(travel)),
      cfg_(cfg),
      registry_(cfg.leaseNs),
      hungarian_(cfg.policy),
      greedy_(cfg.policy) {}

std::size_t Dispatcher::waitingCount() const {
  return static_cast<std::size_t>(
      std::count_if(open_.begin(), open_.end(), [](const auto& kv) { return isWaiting(kv.second.state); }));
}

std::size_t Dispatcher::activeCount() const {
  return static_cast<std::size_t>(
      std::count_if(open_.begin(), open_.end(), [](const auto& kv) { return isActive(kv.second.state); }));
}

void Dispatcher::applied(const TaskRecord& r, DispatchResult& out) {
  if (const auto was = open_.find(r.task.id); was != open_.end() && isWaiting(was->second.state)) {
    countWaiting(was->second, -1);
  }
  out.events.push_back({r.task.id, r.state, r.robotId, r.reason, r.updatedNs,
                        r.stationChosen ? r.task.station : std::string(), etaOf(r)});
  if (isWaiting(r.state)) {
    countWaiting(r, +1);
  }
  switch (r.state) {
    case TaskState::Assigned:
      ++counters_.assigned;
      break;
    case TaskState::Done:
      ++counters_.done;
      break;
    case TaskState::Failed:
      ++counters_.failed;
      break;
    case TaskState::Cancelled:
      ++counters_.cancelled;
      break;
    case TaskState::Requeued:
      ++counters_.requeued;
      break;
    default:
      break;
  }
  if (isTerminal(r.state)) {
    failedBy_.erase(r.task.id);
    open_.erase(r.task.id);
  } else {
    open_.insert_or_assign(r.task.id, r);
  }
}

void Dispatcher::countWaiting(const TaskRecord& r, int delta) {
  auto& n = waitingByPriority_[r.task.priority];
  n = delta > 0 ? n + 1 : (n > 0 ? n - 1 : 0);
  if (n == 0) {
    waitingByPriority_.erase(r.task.priority);
  }
}

std::int64_t Dispatcher::etaOf(const TaskRecord& r) {
  const double dwellS = static_cast<double>(r.task.loadNs + r.task.unloadNs) / 1e9;
  const std::int64_t now = r.updatedNs;
  switch (r.state) {
    case TaskState::Assigned: {
      const RobotInfo* robot = registry_.find(r.robotId);
      return eta_.assigned(r.task.id, now, robot != nullptr ? travel_(r.task)(*robot) + dwellS : kInfeasible);
    }
    case TaskState::EnRoute:
    case TaskState::Loading:
    case TaskState::Delivering:
    case TaskState::Unloading:
      return eta_.active(r.task.id, now);
    case TaskState::Done:
      eta_.ended(r.task.id, now, true);
      return now;
    case TaskState::Failed:
    case TaskState::Cancelled:
    case TaskState::Rejected:  // never a stored task's state
      eta_.ended(r.task.id, now, false);
      return 0;
    case TaskState::Queued:
    case TaskState::Requeued:
      eta_.ended(r.task.id, now, false);
      return waitingEta(r, now);
  }
  return 0;
}

std::int64_t Dispatcher::currentEta(const TaskRecord& r, std::int64_t nowNs) const {
  if (isActive(r.state)) {
    return eta_.active(r.task.id, nowNs);
  }
  return isWaiting(r.state) && !r.paused ? waitingEta(r, nowNs) : 0;
}

std::int64_t Dispatcher::waitingEta(const TaskRecord& r, std::int64_t nowNs) const {
  // Ahead of it: every waiting task of a higher or the same priority (it joins its own last).
  std::size_t ahead = 0;
  for (const auto& [priority, n] : waitingByPriority_) {
    if (priority < r.task.priority) {
      break;
    }
    ahead += n;
  }
  const double dwellS = static_cast<double>(r.task.loadNs + r.task.unloadNs) / 1e9;
  double predicted = eta_.typical();
  if (predicted <= 0.0) {
    // Before the first assignment: the nearest robot's way.
    predicted = kInfeasible;
    const auto travel = travel_(r.task);
    for (const auto& robot : registry_.all()) {
      if (!robot.lost) {
        predicted = std::min(predicted, travel(robot) + dwellS);
      }
    }
  }
  // The robots that may take it: online and not held by the operator (a held robot is given no
  // task). None: no estimate.
  std::size_t robots = registry_.onlineCount();
  for (const auto& id : held_) {
    const RobotInfo* robot = registry_.find(id);
    if (robot != nullptr && !robot->lost && robots > 0) {
      --robots;
    }
  }
  return eta_.waiting(nowNs, ahead, robots, predicted);
}

Expected<DispatchResult> Dispatcher::recover(std::int64_t nowNs) {
  auto tasks = store_.openTasks();
  if (!tasks) {
    return unexpected(tasks.error());
  }
  DispatchResult out;
  open_.clear();
  waitingByPriority_.clear();
  for (auto& r : *tasks) {
    if (isActive(r.state)) {
      registry_.expect(r.robotId, nowNs);
      registry_.setTask(r.robotId, r.task.id);
      out.assignments.push_back({r.robotId, r.task, r.revision, r.paused});
    }
    if (isWaiting(r.state)) {
      countWaiting(r, +1);
    }
    std::string id = r.task.id;
    open_.emplace(std::move(id), std::move(r));
  }
  return out;
}

std::vector<Expected<SubmitResult>> Dispatcher::submit(const std::vector<Task>& tasks, std::int64_t nowNs,
                                                       DispatchResult* out,
                                                       std::vector<std::vector<FieldError>>* fields) {
  std::vector<Expected<SubmitResult>> results;
  results.reserve(tasks.size());
  if (fields != nullptr) {
    fields->assign(tasks.size(), {});
  }
  std::vector<Task> valid;
  std::vector<std::size_t> where;
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    auto errs = validateTask(tasks[i], &stations_);
    if (!errs.empty()) {
      const bool station = std::any_of(errs.begin(), errs.end(), [](const FieldError& e) {
        return e.reason.starts_with("unknown station");
      });
      auto e = makeValidationError(std::move(errs));
      results.emplace_back(
          unexpected(station ? errc::kUnknownStation : errc::kInvalid, std::move(e.message)));
      if (fields != nullptr) {
        (*fields)[i] = std::move(e.fields);
      }
      continue;
    }
    results.emplace_back(unexpected(errc::kStorage, "not stored"));
    valid.push_back(tasks[i]);
    where.push_back(i);
  }
  if (valid.empty()) {
    return results;
  }
  auto stored = store_.submitBatch(valid, nowNs);
  DispatchResult local;
  for (std::size_t k = 0; k < stored.size(); ++k) {
    if (stored[k] && stored[k]->created) {
      ++counters_.submitted;
      applied(stored[k]->record, local);
    } else if (stored[k] && !isTerminal(stored[k]->record.state) &&
               !open_.contains(stored[k]->record.task.id)) {
      // Stored by an earlier attempt whose answer was lost (the connection broke after the commit,
      // as in a database fail-over): this dispatcher never took it in. Adopted at its retry, or
      // nothing would assign it until the manager's next rebuild from the store.
      applied(stored[k]->record, local);
    }
    results[where[k]] = std::move(stored[k]);
  }
  if (out != nullptr) {
    out->append(std::move(local));
  }
  return results;
}

RobotRegistry::Update Dispatcher::onRobotState(const RobotObservation& o) {
  return registry_.observe(o);
}

void Dispatcher::requeueOrFail(const TaskRecord& r, bool failedByRobot, const std::string& reason,
                               std::int64_t nowNs, DispatchResult& out) {
  const bool giveUp = failedByRobot && r.attempts >= cfg_.maxAttempts;
  const TaskState to = giveUp ? TaskState::Failed : TaskState::Requeued;
  const std::string robot = r.robotId;
  auto res = store_.transition(r.task.id, to, "", reason, nowNs);
  if (!res) {
    out.errors.push_back(res.error());
    return;
  }
  registry_.clearTask(robot);
  applied(*res, out);
}

DispatchResult Dispatcher::onRobotLost(const std::string& robotId, std::int64_t nowNs) {
  DispatchResult out;
  if (!registry_.markLost(robotId)) {
    return out;
  }
  ++counters_.robotsLost;
  const RobotInfo* info = registry_.find(robotId);
  if (info != nullptr && !info->taskId.empty()) {
    auto it = open_.find(info->taskId);
    if (it != open_.end() && isActive(it->second.state) && it->second.robotId == robotId) {
      requeueOrFail(it->second, false, "robot " + robotId + " lost", nowNs, out);
    }
  }
  return out;
}

Expected<DispatchResult> Dispatcher::onTaskStatus(const std::string& robotId, const std::string& taskId,
                                                  TaskState state, const std::string& reason,
                                                  std::int64_t nowNs) {
  auto it = open_.find(taskId);
  if (it == open_.end()) {
    return unexpected(errc::kNotFound, "no open task '" + taskId + "'");
  }
  const TaskRecord cur = it->second;
  if (!isActive(cur.state) || cur.robotId != robotId) {
    return unexpected(errc::kWrongRobot, "task '" + taskId + "' is not held by robot '" + robotId + "'");
  }
  DispatchResult out;
  if (state == TaskState::Failed) {
    failedBy_[taskId] = robotId;
    auto& streak = failStreak_[robotId];
    if (cfg_.robotFailLimit > 0 && ++streak.count >= cfg_.robotFailLimit) {
      streak.count = 0;
      streak.holdUntilNs = nowNs + cfg_.robotHoldNs;
      ++counters_.robotsHeld;
    }
    requeueOrFail(cur, true, reason.empty() ? std::string("failed") : reason, nowNs, out);
    if (!out.errors.empty()) {
      return unexpected(out.errors.front());
    }
    return out;
  }
  if (state == cur.state) {
    return out;  // a repeated report
  }
  const auto path = happyPath(cur.task.kind);
  const auto from = std::find(path.begin(), path.end(), cur.state);
  const auto to = std::find(path.begin(), path.end(), state);
  if (from == path.end() || to == path.end() || to <= from) {
    return unexpected(errc::kIllegalTransition, "task '" + taskId + "': robot reported " +
                                                    std::string(toString(state)) + " while it is " +
                                                    std::string(toString(cur.state)));
  }
  std::vector<TransitionRequest> steps;
  for (auto s = from + 1; s <= to; ++s) {
    steps.push_back(
        {taskId, *s, robotId, s == to ? reason : std::string("implied by a later report"), nowNs, {}});
  }
  auto results = store_.transitionBatch(steps);
  for (auto& r : results) {
    if (!r) {
      return unexpected(r.error());
    }
    applied(*r, out);
  }
  if (isTerminal(state)) {
    registry_.clearTask(robotId);
  }
  if (state == TaskState::Done) {
    failStreak_[robotId].count = 0;
  }
  return out;
}

Expected<DispatchResult> Dispatcher::requeueDropped(const std::string& robotId, const std::string& taskId,
                                                    const std::string& reason, std::int64_t nowNs) {
  auto it = open_.find(taskId);
  if (it == open_.end()) {
    return unexpected(errc::kNotFound, "no open task '" + taskId + "'");
  }
  if (!isActive(it->second.state) || it->second.robotId != robotId) {
    return unexpected(errc::kWrongRobot, "task '" + taskId + "' is not held by robot '" + robotId + "'");
  }
  DispatchResult out;
  requeueOrFail(it->second, false, reason, nowNs, out);
  if (!out.errors.empty()) {
    return unexpected(out.errors.front());
  }
  failedBy_[taskId] = robotId;  // whatever made the robot drop it may do so again
  return out;
}

Expected<std::map<std::string, TaskRecord, std::less<>>::iterator> Dispatcher::findOpen(
    const std::string& taskId) {
  auto it = open_.find(taskId);
  if (it != open_.end()) {
    return it;
  }
  auto stored = store_.get(taskId);
  if (!stored) {
    return unexpected(stored.error());  // not_found
  }
  return unexpected(errc::kIllegalTransition,
                    "task '" + taskId + "' is already " + std::string(toString(stored->state)));
}

Expected<DispatchResult> Dispatcher::cancel(const std::string& taskId, const std::string& reason,
                                            std::int64_t nowNs) {
  return close(taskId, TaskState::Cancelled, reason, nowNs);
}

Expected<DispatchResult> Dispatcher::fail(const std::string& taskId, const std::string& reason,
                                          std::int64_t nowNs) {
  return close(taskId, TaskState::Failed, reason, nowNs);
}

Expected<DispatchResult> Dispatcher::close(const std::string& taskId, TaskState to, const std::string& reason,
                                           std::int64_t nowNs) {
  auto found = findOpen(taskId);
  if (!found) {
    return unexpected(found.error());
  }
  const auto it = *found;
  const std::string robot = it->second.robotId;
  const bool active = isActive(it->second.state);
  auto res = store_.transition(taskId, to, "", reason, nowNs);
  if (!res) {
    return unexpected(res.error());
  }
  DispatchResult out;
  if (active) {
    registry_.clearTask(robot);
    out.revoked.push_back(robot);
  }
  applied(*res, out);
  return out;
}

Expected<DispatchResult> Dispatcher::setPaused(const std::string& taskId, bool paused, std::int64_t nowNs) {
  auto found = findOpen(taskId);
  if (!found) {
    return unexpected(found.error());
  }
  const auto it = *found;
  auto res = store_.setPaused(taskId, paused, nowNs);
  if (!res) {
    return unexpected(res.error());
  }
  DispatchResult out;
  const bool changed = it->second.paused != paused;
  it->second.paused = res->paused;
  if (isActive(it->second.state)) {
    // Re-sent even when unchanged: the operator may be repeating a pause the robot never got.
    out.assignments.push_back({it->second.robotId, it->second.task, it->second.revision, paused});
  }
  if (changed) {
    out.events.push_back({taskId, it->second.state, it->second.robotId,
                          paused ? "paused by request" : "resumed by request", nowNs,
                          it->second.stationChosen ? it->second.task.station : std::string(),
                          currentEta(it->second, nowNs)});
  }
  return out;
}

Expected<DispatchResult> Dispatcher::setRobotHeld(const std::string& robotId, bool held, std::int64_t nowNs) {
  const RobotInfo* info = registry_.find(robotId);
  if (info == nullptr) {
    return unexpected(errc::kNotFound, "no robot with id \"" + robotId + "\"");
  }
  if (held) {
    held_.insert(robotId);
  } else {
    held_.erase(robotId);
  }
  const auto it = info->taskId.empty() ? open_.end() : open_.find(info->taskId);
  if (it != open_.end() && isActive(it->second.state)) {
    return setPaused(it->first, held, nowNs);
  }
  DispatchResult out;
  out.revoked.push_back(robotId);  // idle: an empty order, paused while held
  return out;
}

void Dispatcher::completeCharged(std::int64_t nowNs, DispatchResult& out) {
  std::vector<TransitionRequest> steps;
  std::map<std::string, std::string, std::less<>> robotOf;  // task id -> robot
  for (const auto& [id, r] : open_) {
    if (r.task.kind != TaskKind::Charge || !isActive(r.state) || r.paused) {
      continue;
    }
    const RobotInfo* info = registry_.find(r.robotId);
    const Station* st = stations_.find(r.task.station);
    if (info == nullptr || info->lost || info->taskId != id || st == nullptr ||
        info->battery + kBatteryEps < cfg_.chargeUntil ||
        distance(info->pose.position(), st->pose.position()) > cfg_.chargeReach) {
      continue;
    }
    // Steps the robot did not report (a lost status sample) are filled in, as in onTaskStatus.
    const auto path = happyPath(r.task.kind);
    for (auto s = std::find(path.begin(), path.end(), r.state) + 1; s < path.end(); ++s) {
      char why[64];
      std::snprintf(why, sizeof why, "charged to %.2f", info->battery);
      steps.push_back(
          {id, *s, r.robotId, *s == TaskState::Done ? std::string(why) : "implied by the charge", nowNs, {}});
    }
    robotOf.emplace(id, r.robotId);
  }
  if (steps.empty()) {
    return;
  }
  auto results = store_.transitionBatch(steps);
  for (auto& res : results) {
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    if (res->state == TaskState::Done) {
      const std::string& robot = robotOf.at(res->task.id);
      ++counters_.charged;
      registry_.clearTask(robot);
      out.revoked.push_back(robot);  // stop dwelling at the charger
    }
    applied(*res, out);
  }
}

void Dispatcher::chargeLowRobots(std::int64_t nowNs, DispatchResult& out) {
  const auto chargers = stations_.ofKind(StationKind::Charging);
  for (const auto& r : registry_.idleRobots()) {
    if (r.battery >= cfg_.policy.batteryThreshold || robotHeld(r.id)) {
      continue;
    }
    const bool pending = std::any_of(open_.begin(), open_.end(), [&](const auto& kv) {
      return kv.second.task.robot == r.id && kv.second.task.kind == TaskKind::Charge &&
             isWaiting(kv.second.state);
    });
    if (pending) {
      continue;
    }
    Task t;
    t.id = chargeTaskId(r.id, nowNs);
    t.kind = TaskKind::Charge;
    t.robot = r.id;
    // No station: the charger is chosen when the task is assigned (in this tick, the task being
    // the robot's own): the nearest free one, so that low robots do not queue at one charger while
    // another stands free, and none is sent to a charger another robot is already on its way to.
    const bool reachable = std::any_of(chargers.begin(), chargers.end(), [&](const Station* s) {
      Task cand = t;
      cand.station = s->name;
      return std::isfinite(travel_(cand)(r));
    });
    if (!reachable) {
      out.errors.push_back(
          Error{errc::kNotFound, "robot " + r.id + " is low but no charging station is reachable"});
      continue;
    }
    auto res = store_.submit(t, nowNs);
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    ++counters_.submitted;
    applied(res->record, out);
  }
}

namespace {
// The stations a task occupies while it is active.
std::vector<const std::string*> stationsOf(const Task& t) {
  std::vector<const std::string*> s;
  for (const std::string* n : {&t.pickup, &t.dropoff, &t.station}) {
    if (!n->empty()) {
      s.push_back(n);
    }
  }
  return s;
}

// The stations an active task loads now when load is counted by phase: where its robot is going.
std::vector<const std::string*> phaseStationsOf(const Task& t, TaskState state) {
  // Its pickup until it has loaded there, its drop-off for the whole task: a loaded robot must not
  // find its drop-off's line full (docs/algorithms.md, "Traffic: stations as servers").
  const bool delivering = state == TaskState::Delivering || state == TaskState::Unloading;
  std::vector<const std::string*> s;
  for (const std::string* n : {&t.pickup, &t.dropoff, &t.station}) {
    if (!n->empty() && !(delivering && n == &t.pickup)) {
      s.push_back(n);
    }
  }
  return s;
}
}  // namespace

void Dispatcher::admitByStationCapacity(std::vector<Task>& waiting) const {
  std::unordered_map<std::string, std::size_t> load;
  for (const auto& [id, r] : open_) {
    if (isActive(r.state)) {
      for (const std::string* s :
           cfg_.stationLoadByPhase ? phaseStationsOf(r.task, r.state) : stationsOf(r.task)) {
        ++load[*s];
      }
    }
  }
  // Oldest first (pinned and urgent before that), so a busy station's queue is served in order.
  std::stable_sort(waiting.begin(), waiting.end(), [](const Task& a, const Task& b) {
    return std::tuple(a.robot.empty(), -a.priority, a.createdNs) <
           std::tuple(b.robot.empty(), -b.priority, b.createdNs);
  });
  std::vector<Task> admitted;
  for (auto& t : waiting) {
    const auto stations = cfg_.stationLoadByPhase ? phaseStationsOf(t, TaskState::Assigned) : stationsOf(t);
    // A robot's own charge task is never held back: its battery does not wait for the queue.
    const bool full =
        t.robot.empty() && std::any_of(stations.begin(), stations.end(), [&](const std::string* s) {
          const auto it = cfg_.stationCapacities.find(*s);
          const std::size_t cap = it == cfg_.stationCapacities.end() ? cfg_.stationCapacity : it->second;
          return cap > 0 && load[*s] >= cap;
        });
    if (!full) {
      for (const std::string* s : stations) {
        ++load[*s];
      }
      admitted.push_back(std::move(t));
    }
  }
  waiting = std::move(admitted);
}

void Dispatcher::allocate(std::int64_t nowNs, DispatchResult& out) {
  std::vector<Task> waiting;
  bool choosing = false;
  for (const auto& [id, r] : open_) {
    if (isWaiting(r.state) && !r.paused && closedStationOf(r.task) == nullptr) {
      waiting.push_back(r.task);
      choosing = choosing || needsStation(r.task);
    }
  }
  if (!choosing) {
    assignWaiting(std::move(waiting), nullptr, nowNs, out);
    return;
  }
  std::set<std::string, std::less<>> targeted;
  for (const auto& [id, r] : open_) {
    if (isActive(r.state)) {
      for (const std::string* s : stationsOf(r.task)) {
        targeted.insert(*s);
      }
    }
  }
  const auto robots = registry_.all();
  StationChooser chooser(stations_, std::move(targeted), robots, cfg_.standReach);
  assignWaiting(std::move(waiting), &chooser, nowNs, out);
  noteStationWaits(chooser, nowNs, out);
}

void Dispatcher::assignWaiting(std::vector<Task> waiting, StationChooser* chooser, std::int64_t nowNs,
                               DispatchResult& out) {
  auto idle = registry_.idleRobots();
  std::erase_if(idle, [&](const RobotInfo& r) {
    const auto it = failStreak_.find(r.id);
    return robotHeld(r.id) || (it != failStreak_.end() && it->second.holdUntilNs > nowNs);
  });
  if (waiting.empty() || idle.empty()) {
    return;
  }
  if (cfg_.stationCapacity > 0 || !cfg_.stationCapacities.empty()) {
    admitByStationCapacity(waiting);
    if (waiting.empty()) {
      return;
    }
  }
  if (waiting.size() > cfg_.maxCandidates) {
    auto key = [](const Task& t) {
      return std::tuple(t.robot.empty(), -t.priority, t.deadlineNs > 0 ? t.deadlineNs : INT64_MAX,
                        t.createdNs);
    };
    const auto keep = static_cast<std::ptrdiff_t>(cfg_.maxCandidates);
    std::partial_sort(waiting.begin(), waiting.begin() + keep, waiting.end(),
                      [&](const Task& a, const Task& b) { return key(a) < key(b); });
    waiting.resize(cfg_.maxCandidates);
  }
  const auto small = static_cast<double>(std::min(waiting.size(), idle.size()));
  const auto big = static_cast<double>(std::max(waiting.size(), idle.size()));
  const Allocator& alloc = small * small * big > cfg_.hungarianMaxWork
                               ? static_cast<const Allocator&>(greedy_)
                               : static_cast<const Allocator&>(hungarian_);
  TravelModel travel = travel_;
  if (chooser != nullptr) {
    // A task without a station costs what the trip to the station the robot would get costs;
    // with no free station it can reach, the robot cannot take it.
    travel = [this, chooser](const Task& t) -> RobotTravel {
      if (!needsStation(t)) {
        return travel_(t);
      }
      auto options = std::make_shared<const StationChooser::Options>(chooser->options(t, travel_));
      return [options, chooser](const RobotInfo& r) { return chooser->best(*options, r).travelS; };
    };
  }
  if (!failedBy_.empty() && idle.size() > 1) {
    // A retry goes to another robot: whatever held the last one (boxed in, a bad pose estimate)
    // is likely to hold it again. With a single idle robot it may take the task back.
    travel = [this, base = std::move(travel)](const Task& t) -> RobotTravel {
      RobotTravel inner = base(t);
      const auto it = failedBy_.find(t.id);
      if (it == failedBy_.end()) {
        return inner;
      }
      return [inner, who = it->second](const RobotInfo& r) { return r.id == who ? kInfeasible : inner(r); };
    };
  }
  const auto assignments = alloc.assign(waiting, idle, travel, nowNs);
  // The stations of the assigned tasks that need one. Two such tasks may have been costed against
  // the same station: the robot nearest to its best one chooses first, and each choice is taken at
  // once. A task left without a station stays in the queue.
  std::vector<std::string> chosen(assignments.size());
  std::vector<bool> dropped(assignments.size(), false);
  if (chooser != nullptr) {
    std::vector<StationChooser::Options> options(assignments.size());
    std::vector<std::tuple<bool, double, std::size_t>> order;
    for (std::size_t k = 0; k < assignments.size(); ++k) {
      const Task& t = waiting[assignments[k].task];
      if (needsStation(t)) {
        options[k] = chooser->options(t, travel_);
        const auto pick = chooser->best(options[k], idle[assignments[k].robot]);
        order.emplace_back(pick.blocked, pick.travelS, k);
      }
    }
    std::sort(order.begin(), order.end());
    for (const auto& [blocked, travelS, k] : order) {
      const auto pick = chooser->best(options[k], idle[assignments[k].robot]);
      if (pick.station == nullptr) {
        dropped[k] = true;
        continue;
      }
      chosen[k] = pick.station->name;
      chooser->take(pick.station->name);
    }
  }
  std::vector<TransitionRequest> reqs;
  reqs.reserve(assignments.size());
  for (std::size_t k = 0; k < assignments.size(); ++k) {
    if (dropped[k]) {
      continue;
    }
    const Task& t = waiting[assignments[k].task];
    std::string why = "allocated";
    if (!chosen[k].empty()) {
      why += " to the nearest free " + std::string(toString(targetKind(t.kind))) + " station " + chosen[k];
    }
    reqs.push_back(
        {t.id, TaskState::Assigned, idle[assignments[k].robot].id, std::move(why), nowNs, chosen[k]});
  }
  auto results = store_.transitionBatch(reqs);
  for (std::size_t k = 0; k < results.size(); ++k) {
    if (!results[k]) {
      out.errors.push_back(results[k].error());
      continue;
    }
    registry_.setTask(reqs[k].robotId, reqs[k].taskId);
    out.assignments.push_back({reqs[k].robotId, results[k]->task, results[k]->revision});
    applied(*results[k], out);
  }
}

void Dispatcher::noteStationWaits(const StationChooser& chooser, std::int64_t nowNs, DispatchResult& out) {
  static constexpr std::string_view kWaiting = "waiting for a free ";
  std::map<StationKind, std::size_t> freeOf;
  for (auto& [id, r] : open_) {
    if (!isWaiting(r.state) || r.paused || !needsStation(r.task)) {
      continue;
    }
    const StationKind kind = targetKind(r.task.kind);
    auto [free, fresh] = freeOf.try_emplace(kind, 0);
    if (fresh) {
      free->second = chooser.freeOfKind(kind);
    }
    const std::string what(toString(kind));
    std::string why;
    if (free->second == 0) {
      const std::size_t n = chooser.countOfKind(kind);
      why = std::string(kWaiting) + what +
            " station: " + (n == 1 ? std::string("the only one is") : "all " + std::to_string(n) + " are") +
            " taken by other tasks";
    } else if (r.reason.starts_with(kWaiting)) {
      why = "a " + what + " station is free again; waiting for a robot";
    }
    if (why.empty() || why == r.reason) {
      continue;
    }
    auto res = store_.setWaitReason(id, why, nowNs);
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    r.reason = res->reason;
    r.updatedNs = res->updatedNs;
    out.events.push_back({id, r.state, "", r.reason, nowNs, "", currentEta(r, nowNs)});
  }
}

DispatchResult Dispatcher::tick(std::int64_t nowNs) {
  DispatchResult out;
  for (const auto& lost : registry_.expire(nowNs)) {
    ++counters_.robotsLost;
    auto it = open_.find(lost.taskId);
    if (!lost.taskId.empty() && it != open_.end() && isActive(it->second.state) &&
        it->second.robotId == lost.id) {
      requeueOrFail(it->second, false, "robot " + lost.id + " lost", nowNs, out);
    }
  }
  completeCharged(nowNs, out);
  chargeLowRobots(nowNs, out);
  allocate(nowNs, out);
  if (!closedStations_.empty()) {
    // Tasks that came in since a station closed get its reason; reopening is stated by
    // setClosedStations, so a tick without closures does not walk the open tasks.
    noteClosedStations(nowNs, out);
  }
  // A released robot that got a new task in the same tick must not have it withdrawn by the empty
  // assignment published after it: the new order replaces the charge order anyway.
  std::erase_if(out.revoked, [&](const std::string& robot) {
    return std::any_of(out.assignments.begin(), out.assignments.end(),
                       [&](const AssignmentOrder& a) { return a.robotId == robot; });
  });
  return out;
}

}  // namespace fleet
