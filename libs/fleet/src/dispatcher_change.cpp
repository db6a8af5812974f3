#include "fleet/fleet/dispatcher.hpp"
#include "fleet/fleet/errors.hpp"

namespace fleet {

Expected<DispatchResult> Dispatcher::change(const ChangeRequest& q, std::vector<FieldError>* fields) {
  auto found = findOpen(q.taskId);
  if (!found) {
    return unexpected(found.error());
  }
  const auto it = *found;
  if (!isWaiting(it->second.state)) {
    return unexpected(errc::kIllegalTransition,
                      "task '" + q.taskId + "' is " + std::string(toString(it->second.state)) +
                          "; only a waiting (queued or requeued) task can be changed");
  }
  if (auto errs = validateChange(q, it->second.task); !errs.empty()) {
    auto e = makeValidationError(std::move(errs));
    if (fields != nullptr) {
      *fields = std::move(e.fields);
    }
    return unexpected(errc::kInvalid, std::move(e.message));
  }
  auto res = store_.change(q);
  if (!res) {
    return unexpected(res.error());
  }
  DispatchResult out;
  if (!res->changed) {
    return out;  // the values were in force already: a repeated request
  }
  // The open record takes the stored one's values; allocation reads them from here every tick,
  // so the queue is ordered by the new priority and deadline from the next tick on.
  TaskRecord& r = it->second;
  countWaiting(r, -1);  // the waiting count per priority (TaskEta) moves with the priority
  r.task.priority = res->record.task.priority;
  r.task.deadlineNs = res->record.task.deadlineNs;
  r.submitted = res->record.submitted;
  r.revision = res->record.revision;
  r.updatedNs = res->record.updatedNs;
  countWaiting(r, +1);
  std::string why = "changed by request: priority " + std::to_string(r.task.priority) + ", deadline_ns " +
                    std::to_string(r.task.deadlineNs);
  out.events.push_back({q.taskId, r.state, "", std::move(why), q.stampNs,
                        r.stationChosen ? r.task.station : std::string(), etaOf(r), true,
                        r.task.priority, r.task.deadlineNs});
  return out;
}

}  // namespace fleet
