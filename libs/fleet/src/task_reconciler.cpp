#include "fleet/fleet/task_reconciler.hpp"

namespace fleet {
namespace {

// Nothing left to watch: the robot carries what the manager has it carry (or neither has a task).
bool settled(const std::string& expected, const std::string& reported, std::int64_t missingSinceNs) {
  return missingSinceNs < 0 && (reported.empty() || reported == expected);
}

}  // namespace

void TaskReconciler::observe(const std::string& robot, const std::string& reported,
                             const std::string& expected, std::int64_t nowNs) {
  auto it = robots_.find(robot);
  if (it == robots_.end()) {
    if (reported == expected) {
      return;  // the common case: nothing to track, no entry made
    }
    it = robots_.try_emplace(robot).first;
    it->second.expected = expected;
  }
  Track& t = it->second;
  if (t.expected != expected) {
    // The manager's record changed since the last report: the grace starts again now.
    t.expected = expected;
    t.missingSinceNs = -1;
    t.reportedSinceNs = -1;
    t.unexpectedSaid = false;
  }
  if (expected.empty() || reported == expected) {
    t.missingSinceNs = -1;
  } else if (t.missingSinceNs < 0) {
    t.missingSinceNs = nowNs;
  }
  if (reported != t.reported || t.reportedSinceNs < 0) {
    if (reported != t.reported) {
      t.unexpectedSaid = false;
    }
    t.reported = reported;
    t.reportedSinceNs = nowNs;
  }
  if (settled(t.expected, t.reported, t.missingSinceNs)) {
    robots_.erase(it);
  }
}

void TaskReconciler::forget(std::string_view robot) {
  if (auto it = robots_.find(robot); it != robots_.end()) {
    robots_.erase(it);
  }
}

std::vector<TaskMismatch> TaskReconciler::due(
    std::int64_t nowNs, const std::function<std::string(const std::string&)>& expectedOf) {
  std::vector<TaskMismatch> out;
  for (auto it = robots_.begin(); it != robots_.end();) {
    const std::string& robot = it->first;
    Track& t = it->second;
    if (std::string cur = expectedOf(robot); cur != t.expected) {
      // A new order, or the task ended or was requeued: the old reports do not count against
      // the new record; the robot's next report starts the grace again.
      t.expected = std::move(cur);
      t.missingSinceNs = -1;
      t.reportedSinceNs = -1;
      t.unexpectedSaid = false;
    }
    if (!t.expected.empty() && t.missingSinceNs >= 0 && nowNs - t.missingSinceNs >= graceNs_) {
      out.push_back({TaskMismatch::Kind::Missing, robot, t.expected, t.reported, t.missingSinceNs});
      t.missingSinceNs = nowNs;  // asked again after another grace if the caller could not act
    }
    if (!t.reported.empty() && t.reported != t.expected && !t.unexpectedSaid && t.reportedSinceNs >= 0 &&
        nowNs - t.reportedSinceNs >= graceNs_) {
      out.push_back({TaskMismatch::Kind::Unexpected, robot, t.expected, t.reported, t.reportedSinceNs});
      t.unexpectedSaid = true;
    }
    if (settled(t.expected, t.reported, t.missingSinceNs)) {
      it = robots_.erase(it);
    } else {
      ++it;
    }
  }
  return out;
}

}  // namespace fleet
