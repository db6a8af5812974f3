#include "task_ledger.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>

namespace fleet::ctl {

bool isTerminal(const std::string& state) {
  return state == "done" || state == "failed" || state == "cancelled";
}

Accounting TaskLedger::reconcile(const std::vector<TaskRow>& tasks,
                                 const std::vector<TransitionRow>& transitions) const {
  Accounting a;
  a.acknowledged = acked_.size();
  std::map<std::string, const TaskRow*> known;
  for (const auto& t : tasks) {
    known[t.id] = &t;
  }
  for (const auto& id : acked_) {
    auto it = known.find(id);
    if (it == known.end()) {
      a.lost.push_back(id);
      continue;
    }
    const std::string& s = it->second->state;
    if (s == "done") {
      ++a.done;
    } else if (s == "failed") {
      ++a.failed;
    } else if (s == "cancelled") {
      ++a.cancelled;
    } else {
      ++a.active;
    }
  }
  for (const auto& t : tasks) {
    if (!acked_.count(t.id)) {
      ++a.unacknowledgedKnown;
    }
  }
  std::map<std::string, int> terminal;
  std::map<std::string, std::int64_t> created;  // first transition: stored (simulated clock)
  std::map<std::string, std::int64_t> firstAssigned;
  std::set<std::string> unstamped;
  std::int64_t latest = 0;
  constexpr std::int64_t kClockSlackNs = 1000000000;
  std::vector<double> assign;
  std::vector<double> e2e;
  for (const auto& tr : transitions) {
    auto row = known.find(tr.taskId);
    if (isTerminal(tr.toState) && ++terminal[tr.taskId] == 2) {
      a.duplicated.push_back(tr.taskId);
    }
    if (row == known.end()) {
      continue;
    }
    // A restarted manager stamps what it stores before its first simulator Clock message with 0:
    // a first stamp well behind the log's latest one means "no clock yet", and such a task gives
    // no latency samples.
    const bool first = !created.count(tr.taskId);
    const std::int64_t c0 = created.try_emplace(tr.taskId, tr.stampNs).first->second;
    if (first && tr.stampNs + kClockSlackNs < latest) {
      unstamped.insert(tr.taskId);
      ++a.unstamped;
    }
    latest = std::max(latest, tr.stampNs);
    if (unstamped.count(tr.taskId)) {
      continue;
    }
    const double sinceCreated = static_cast<double>(tr.stampNs - c0) / 1e9;
    if (tr.toState == "assigned" && !firstAssigned.count(tr.taskId)) {
      firstAssigned[tr.taskId] = tr.stampNs;
      assign.push_back(sinceCreated);
    }
    if (tr.toState == "done" && terminal[tr.taskId] == 1) {
      e2e.push_back(sinceCreated);
      a.doneAtS.push_back(static_cast<double>(tr.stampNs) / 1e9);
    }
  }
  std::sort(a.doneAtS.begin(), a.doneAtS.end());
  a.assignS = percentiles(assign);
  a.endToEndS = percentiles(e2e);
  return a;
}

nlohmann::json toJson(const Percentiles& p) {
  return {{"count", p.count}, {"p50", p.p50}, {"p90", p.p90}, {"p99", p.p99}, {"max", p.max}};
}

nlohmann::json toJson(const Accounting& a) {
  return {{"acknowledged", a.acknowledged},
          {"done", a.done},
          {"failed", a.failed},
          {"cancelled", a.cancelled},
          {"still_tracked", a.active},
          {"known_not_acknowledged", a.unacknowledgedKnown},
          {"unstamped", a.unstamped},
          {"lost", a.lost.size()},
          {"lost_ids", a.lost},
          {"duplicated", a.duplicated.size()},
          {"duplicated_ids", a.duplicated},
          {"assignment_latency_s", toJson(a.assignS)},
          {"end_to_end_latency_s", toJson(a.endToEndS)}};
}

}  // namespace fleet::ctl
