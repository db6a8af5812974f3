// FleetManagerNode::reconcile: what the manager does when a robot's reported task (RobotState
// task_id) and the store disagree for longer than reconcile_s (the bookkeeping: TaskReconciler).

#include <cstdio>

#include "fleet_manager_node.hpp"

namespace fleet::manager {
namespace {

std::string seconds(std::int64_t ns) {
  char s[32];
  std::snprintf(s, sizeof s, "%.1f s", static_cast<double>(ns) / 1e9);
  return s;
}

std::string whatReported(const std::string& reported) {
  return reported.empty() ? std::string("no task") : "task " + reported;
}

}  // namespace

void FleetManagerNode::reconcile(std::int64_t nowNs, Outbox& out) {
  if (settings_.reconcileS <= 0) {
    return;
  }
  const auto due = reconciler_.due(nowNs, [this](const std::string& robot) {
    const RobotInfo* info = dispatcher_->robots().find(robot);
    return info != nullptr ? info->taskId : std::string();
  });
  for (const auto& m : due) {
    const std::string since = "since " + std::to_string(m.sinceNs) + " ns, " + seconds(nowNs - m.sinceNs);
    if (m.kind == TaskMismatch::Kind::Missing) {
      // The robot dropped the task without a report (a TaskStatus done or failed would have
      // closed it before now): it goes back to the queue rather than wait for a lease that
      // never expires, the robot being alive.
      const auto it = dispatcher_->openTasks().find(m.expected);
      const std::string state =
          it != dispatcher_->openTasks().end() ? std::string(toString(it->second.state)) : "active";
      const std::string reason = "robot " + m.robot + " reported " + whatReported(m.reported) + " for " +
                                 seconds(nowNs - m.sinceNs) + " while it held the task (" + state + ")";
      auto r = dispatcher_->requeueDropped(m.robot, m.expected, reason, nowNs);
      if (!r) {
        continue;  // closed or moved meanwhile: nothing left to reconcile
      }
      ++metrics_.reconciledRequeued;
      publish(std::move(*r), nowNs, out);
      out.reconciled.push_back({"requeued", m.robot, m.expected, m.reported, m.sinceNs,
                                "reconcile: task " + m.expected + " requeued: robot " + m.robot +
                                    " has reported " + whatReported(m.reported) + " (" + since +
                                    ") while the store has it carry the task (" + state + ")"});
      continue;
    }
    // The robot reports a task the store does not give it: log and count. Its own active task
    // would be a resume (the reconciler does not report that: expected == reported).
    std::string why;
    const auto it = dispatcher_->openTasks().find(m.reported);
    if (it != dispatcher_->openTasks().end()) {
      const TaskRecord& r = it->second;
      if (isActive(r.state) && r.robotId == m.robot) {
        continue;
      }
      why = isActive(r.state) ? "held by robot " + r.robotId : std::string(toString(r.state)) + ", waiting";
    } else if (auto stored = store_->get(m.reported)) {
      why = "already " + std::string(toString(stored->state));
    } else {
      why = "unknown to the store";
    }
    ++metrics_.reconciledStale;
    out.reconciled.push_back({"stale_report", m.robot, m.reported, m.reported, m.sinceNs,
                              "reconcile: robot " + m.robot + " has reported task " + m.reported + " (" +
                                  since + "), which is " + why + "; the store has it carry " +
                                  (m.expected.empty() ? std::string("no task") : "task " + m.expected) +
                                  " (nothing done)"});
  }
}

}  // namespace fleet::manager
