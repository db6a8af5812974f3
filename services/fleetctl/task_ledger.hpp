#pragma once

// Accounting of a load test's tasks: which ids the WMS adapter acknowledged (HTTP 200/201, i.e. the
// manager stored them durably), and what the manager's task database says at the end. An
// acknowledged task must end done/failed/cancelled exactly once or still be tracked:
//   lost       = acknowledged, but the manager does not know the id at the end
//   duplicated = a task that reached a terminal state more than once
// Latencies come from the transitions (stamped with the simulated clock; the task's created_ns is
// the WMS's wall clock, so it is not used): assignment = first transition (stored) -> first
// "assigned", end to end = first transition -> "done".

#include <cstdint>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "fleet/core/percentiles.hpp"

#include <nlohmann/json.hpp>

namespace fleet::ctl {

struct TaskRow {
  std::string id;
  std::string state;
};

struct TransitionRow {
  std::string taskId;
  std::string toState;
  std::int64_t stampNs = 0;
};

using fleet::Percentiles;
using fleet::percentiles;

struct Accounting {
  std::size_t acknowledged = 0;
  std::size_t done = 0, failed = 0, cancelled = 0, active = 0;
  std::size_t unacknowledgedKnown = 0;  // in the database but never acknowledged (a 503 after storing)
  std::size_t unstamped = 0;            // stored by a manager without a clock yet: no latency samples
  std::vector<std::string> lost;
  std::vector<std::string> duplicated;
  Percentiles assignS;  // simulated seconds
  Percentiles endToEndS;
  std::vector<double> doneAtS;  // simulated time of each "done", sorted
};

bool isTerminal(const std::string& state);

class TaskLedger {
 public:
  void acknowledged(const std::string& id) { acked_.insert(id); }
  [[nodiscard]] bool isAcknowledged(const std::string& id) const { return acked_.count(id) != 0; }
  [[nodiscard]] std::size_t count() const { return acked_.size(); }

  /// Compares the acknowledged ids with the manager's rows and transitions.
  [[nodiscard]] Accounting reconcile(const std::vector<TaskRow>& tasks,
                                     const std::vector<TransitionRow>& transitions) const;

 private:
  std::set<std::string> acked_;
};

nlohmann::json toJson(const Percentiles& p);
nlohmann::json toJson(const Accounting& a);

}  // namespace fleet::ctl
