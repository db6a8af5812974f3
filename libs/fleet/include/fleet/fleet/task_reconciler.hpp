#pragma once

// Compares the task each robot says it carries (RobotState.task_id) with the task the manager has
// it carry, and says which disagreements outlasted a grace period. Pure bookkeeping: the caller
// decides what to do (requeue, log, count).

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace fleet {

/// One disagreement that lasted at least the grace period.
struct TaskMismatch {
  enum class Kind {
    /// The manager has the robot carry `expected`, but the robot has not reported it since
    /// `sinceNs` (it reports `reported`: no task or another one).
    Missing,
    /// The robot has reported `reported` since `sinceNs`, a task the manager does not have it
    /// carry (`expected`: its task per the manager, possibly none).
    Unexpected,
  };
  Kind kind = Kind::Missing;
  std::string robot;
  std::string expected;
  std::string reported;
  std::int64_t sinceNs = 0;
};

class TaskReconciler {
 public:
  /// `graceNs` covers the normal delays: an order on its way to the robot (its reports still
  /// show the old task), a finished task whose report crosses the robot's next state.
  explicit TaskReconciler(std::int64_t graceNs) : graceNs_(graceNs) {}

  /// A robot's report received at `nowNs`: it carries `reported` ("" none) while the manager has
  /// it carry `expected` ("" none). Reporting `expected` ends a Missing disagreement at once.
  void observe(const std::string& robot, const std::string& reported, const std::string& expected,
               std::int64_t nowNs);
  /// The robot is gone (lost): its disagreements end; the lease deals with its task.
  void forget(std::string_view robot);

  /// The disagreements that have lasted at least the grace by `nowNs`, sorted by robot.
  /// `expectedOf(robot)` is the manager's current task for the robot: where it changed since the
  /// last report (a new order, a task finished or requeued), the robot's old reports no longer
  /// count against it and its grace starts again with its next report. A Missing disagreement is
  /// returned again after another grace if it still stands (the caller's action did not resolve
  /// it); an Unexpected one once for each task the robot reports.
  std::vector<TaskMismatch> due(std::int64_t nowNs,
                                const std::function<std::string(const std::string&)>& expectedOf);

  [[nodiscard]] std::int64_t graceNs() const { return graceNs_; }
  [[nodiscard]] std::size_t tracked() const { return robots_.size(); }

 private:
  struct Track {
    std::string expected;
    std::int64_t missingSinceNs = -1;  ///< not reporting `expected` since then; -1: it does
    std::string reported;
    std::int64_t reportedSinceNs = -1;  ///< reporting `reported` since then; -1: from the next report
    bool unexpectedSaid = false;
  };
  std::int64_t graceNs_;
  std::map<std::string, Track, std::less<>> robots_;
};

}  // namespace fleet
