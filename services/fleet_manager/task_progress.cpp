// Where a multi-stop task is: the stop its robot reports (TaskStatus.step) is carried on the task's
// events (TaskEvent.step), and a new stop without a change of state is told by an event of its own.

#include "fleet_manager_node.hpp"

#include <algorithm>

namespace fleet::manager {

bool FleetManagerNode::noteStep(const msg::TaskStatus& s) {
  const auto& open = dispatcher_->openTasks();
  const auto it = open.find(s.task_id);
  if (s.step == 0 || it == open.end() || it->second.task.kind != TaskKind::Multistop ||
      it->second.robotId != s.robot_id || !isActive(it->second.state)) {
    return false;
  }
  const auto steps = static_cast<std::uint32_t>(it->second.task.steps.size());
  auto& p = progress_[s.task_id];
  p.steps = steps;
  const std::uint32_t step = std::min(s.step, steps);
  if (p.step == step) {
    return false;
  }
  p.step = step;
  return true;
}

void FleetManagerNode::stampStep(msg::TaskEvent& e) {
  const auto it = progress_.find(e.task_id);
  if (it == progress_.end()) {
    return;
  }
  if (e.state == TaskState::Done && it->second.steps > 0) {
    it->second.step = it->second.steps;
  }
  e.step = it->second.step;
  it->second.last = e;
  if (isTerminal(e.state) || isWaiting(e.state)) {
    // Done, or given up: nothing to follow. Requeued: the next robot starts at the first stop.
    if (isTerminal(e.state)) {
      progress_.erase(it);
    } else {
      it->second.step = 0;
    }
  }
}

void FleetManagerNode::trackSteps(const std::string& taskId) {
  const auto& open = dispatcher_->openTasks();
  const auto it = open.find(taskId);
  if (it != open.end() && it->second.task.kind == TaskKind::Multistop) {
    progress_[taskId].steps = static_cast<std::uint32_t>(it->second.task.steps.size());
  }
}

void FleetManagerNode::stepEvent(const std::string& taskId, std::int64_t nowNs, Outbox& out) {
  const auto it = progress_.find(taskId);
  const auto& open = dispatcher_->openTasks();
  const auto rec = open.find(taskId);
  if (it == progress_.end() || rec == open.end() || it->second.step == 0) {
    return;
  }
  const auto& step = rec->second.task.steps.at(it->second.step - 1);
  // The task's last event again with the stop: the same seq (no transition; a restarted manager
  // numbers from the stored revision, which a stop does not advance), a later stamp.
  msg::TaskEvent e = it->second.last;
  e.task_id = taskId;
  e.state = rec->second.state;
  e.robot_id = rec->second.robotId;
  e.seq = eventSeq_[taskId];
  e.stamp_ns = nowNs;
  e.changed = false;
  e.priority = 0;
  e.deadline_ns = 0;
  e.epoch = epoch_;
  e.step = it->second.step;
  std::string what = "step " + std::to_string(it->second.step) + " of " + std::to_string(it->second.steps) +
                     ": " + std::string(toString(step.action));
  if (!step.loadId.empty()) {
    what += " " + step.loadId;
  }
  if (!step.station.empty()) {
    what += " at " + step.station;
  }
  e.reason = what.substr(0, 255);
  it->second.last = e;
  out.events.push_back(std::move(e));
}

}  // namespace fleet::manager
