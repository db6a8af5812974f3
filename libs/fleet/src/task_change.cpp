#include "fleet/fleet/task_store.hpp"

namespace fleet {

std::vector<FieldError> validateChange(const ChangeRequest& q, const Task& t) {
  std::vector<FieldError> errs;
  if (!q.priority && !q.deadlineNs) {
    errs.push_back({"priority", "give priority, deadline or both"});
  }
  if (q.priority && (*q.priority < kMinPriority || *q.priority > kMaxPriority)) {
    errs.push_back({"priority", "must be in [" + std::to_string(kMinPriority) + ", " +
                                    std::to_string(kMaxPriority) + "]"});
  }
  if (q.deadlineNs && *q.deadlineNs < 0) {
    errs.push_back({"deadline_ns", "must be >= 0 (0 = no deadline)"});
  } else if (q.deadlineNs && *q.deadlineNs > 0 && *q.deadlineNs < t.createdNs) {
    errs.push_back({"deadline_ns", "is before the task's created_ns (" + std::to_string(t.createdNs) + ")"});
  }
  return errs;
}

}  // namespace fleet
