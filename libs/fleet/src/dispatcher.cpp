#include "fleet/fleet/dispatcher.hpp"

#include <algorithm>
#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include "dispatcher_detail.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet {

using dispatcher_detail::happyPath;

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
  // A multi-stop task picks and drops more than once: it stays en_route until it is done (which
  // stop it is at travels beside its state), whatever stage the robot reports for a stop.
  const TaskState reached =
      cur.task.kind == TaskKind::Multistop && isActive(state) && state != TaskState::Assigned
          ? TaskState::EnRoute
          : state;
  if (reached == cur.state) {
    return out;  // a repeated report
  }
  const auto path = happyPath(cur.task.kind);
  const auto from = std::find(path.begin(), path.end(), cur.state);
  const auto to = std::find(path.begin(), path.end(), reached);
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
