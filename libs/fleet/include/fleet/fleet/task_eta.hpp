#pragma once

// When a task will be done, as the fleet manager states it to the WMS with each transition
// (docs/algorithms.md, "fleet: task ETA"). Two things the dispatcher's travel model cannot see are
// learnt from the tasks the fleet finishes:
// - the pace: how much longer a task takes than its free-flow prediction (travel at cruise on the
//   roadmap plus dwell), since queues, traffic and people stretch every task alike — the mean of
//   actual ÷ predicted over the last `window` tasks done;
// - the rate: tasks done per second over the last `window` completions — how fast the queue ahead
//   of a waiting task drains.
// An active task is done at  assigned + pace × predicted.  A waiting task is assigned after the
// `ahead` tasks before it in the queue have left it (ahead + 1 completions at the fleet's rate, or,
// before any completion is seen, at `robots` tasks per pace × predicted), then takes its own
// pace × predicted. Before any task is done the pace is 1 (the prediction is stated as it is).

#include <cstdint>
#include <deque>
#include <map>
#include <string>

namespace fleet {

struct TaskEtaOptions {
  std::size_t window = 20;  ///< tasks done that the pace and the rate are taken over
  double minPace = 1.0;     ///< a task is never stated faster than its free-flow prediction
  double maxPace = 20.0;
};

class TaskEta {
 public:
  explicit TaskEta(TaskEtaOptions options = {}) : options_(options) {}

  /// A robot took the task: its free-flow prediction (s, finite and >= 0; else no estimate).
  /// Returns the ETA (ns; 0 when there is none).
  std::int64_t assigned(const std::string& taskId, std::int64_t nowNs, double predictedS);
  /// The ETA stated for an active task at assignment (0: none or not active). Never in the past:
  /// a task running late is stated as due now.
  [[nodiscard]] std::int64_t active(const std::string& taskId, std::int64_t nowNs) const;
  /// The task ended (done: its duration teaches the pace; the completion the rate) or went back to
  /// the queue; either way it is forgotten.
  void ended(const std::string& taskId, std::int64_t nowNs, bool done);
  /// A waiting task with `ahead` tasks before it in the queue, on a fleet of `robots` able to take
  /// it, predicted at `predictedS` once assigned. 0 when there is no estimate (no robot, no
  /// prediction).
  [[nodiscard]] std::int64_t waiting(std::int64_t nowNs, std::size_t ahead, std::size_t robots,
                                     double predictedS) const;

  /// Actual ÷ predicted task time over the last window of tasks done (1 before the first).
  [[nodiscard]] double pace() const;
  /// Tasks done per second over the last window (0 before two completions).
  [[nodiscard]] double rate() const;
  /// The mean free-flow prediction of the last window of assigned tasks (0 before the first): what
  /// a waiting task, whose robot is not known yet, is predicted at.
  [[nodiscard]] double typical() const;
  /// Tasks assigned and not ended.
  [[nodiscard]] std::size_t running() const { return running_.size(); }

 private:
  struct Running {
    std::int64_t startNs = 0;
    double predictedS = 0.0;
  };
  TaskEtaOptions options_;
  std::map<std::string, Running, std::less<>> running_;
  std::deque<double> paces_;
  std::deque<double> predictions_;
  std::deque<std::int64_t> completions_;
};

}  // namespace fleet
