#pragma once

#include <cstdint>
#include <vector>

#include "fleet/metrics/histogram.hpp"
#include "fleet/metrics/registry.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet_manager_node.hpp"

namespace fleet::manager {

/// The manager's Prometheus metrics, mirrored from the node once a second (the node counts in plain
/// integers on the loop's thread; the registry's counters advance by the difference).
class ManagerMetrics {
 public:
  explicit ManagerMetrics(service::ServiceOps& ops) : r_(ops.registry()) {
    for (const char* outcome : {"done", "failed", "cancelled", "requeued"}) {
      outcomes_.push_back({&r_.counter("fleet_manager_tasks_total",
                                       "Tasks that reached an outcome (requeued: given back to the queue)",
                                       {{"outcome", outcome}})});
    }
    for (const char* result : {"stored", "duplicate", "rejected"}) {
      requests_.push_back({&r_.counter("fleet_manager_task_requests_total",
                                       "Task requests received over DDS, by result", {{"result", result}})});
    }
    for (const char* action : {"requeued", "stale_report"}) {
      reconciled_.push_back({&r_.counter(
          "fleet_manager_reconciled_total",
          "Robots whose reported task disagreed with the store for reconcile_s: their task requeued, or "
          "a stale report logged",
          {{"action", action}})});
    }
    for (const char* state : {"queued", "active"}) {
      tasks_.push_back(
          &r_.gauge("fleet_manager_tasks", "Open tasks: queued (waiting) or active", {{"state", state}}));
    }
    for (const char* state : {"idle", "busy", "lost", "fault"}) {
      robots_.push_back(
          &r_.gauge("fleet_manager_robots", "Robots known to the manager, by state", {{"state", state}}));
    }
  }
  metrics::Histogram& assignLatency() {
    return r_.histogram("fleet_manager_assign_latency_seconds",
                        "Time from queued to assigned, per assignment",
                        manager::FleetManagerNode::assignLatencyBuckets());
  }
  metrics::Histogram& loopSeconds() {
    return r_.histogram("fleet_manager_loop_seconds",
                        "Wall time of one turn of the manager's loop (work only)",
                        metrics::exponentialBuckets(1e-5, 2.0, 18));
  }
  /// A manager that stands by again reports no tasks and no robots (sums over managers count the
  /// active one only).
  void clear() {
    for (auto* g : tasks_) {
      g->set(0);
    }
    for (auto* g : robots_) {
      g->set(0);
    }
  }
  void update(const manager::FleetManagerNode& node) {
    const auto& c = node.dispatcher().counters();
    const auto& m = node.metrics();
    outcomes_[0].to(c.done);
    outcomes_[1].to(c.failed);
    outcomes_[2].to(c.cancelled);
    outcomes_[3].to(c.requeued);
    requests_[0].to(m.stored);
    requests_[1].to(m.duplicates);
    requests_[2].to(m.rejected);
    reconciled_[0].to(m.reconciledRequeued);
    reconciled_[1].to(m.reconciledStale);
    tasks_[0]->set(static_cast<double>(node.dispatcher().waitingCount()));
    tasks_[1]->set(static_cast<double>(node.dispatcher().activeCount()));
    double idle = 0;
    double busy = 0;
    double lost = 0;
    double fault = 0;
    for (const auto& r : node.dispatcher().robots().all()) {
      (r.lost ? lost : (r.fault ? fault : (r.taskId.empty() ? idle : busy))) += 1.0;
    }
    robots_[0]->set(idle);
    robots_[1]->set(busy);
    robots_[2]->set(lost);
    robots_[3]->set(fault);
  }

 private:
  /// A counter following a cumulative count kept elsewhere.
  struct Mirrored {
    metrics::Counter* counter;
    std::int64_t last = 0;
    void to(std::int64_t now) {
      if (now > last) {
        counter->inc(static_cast<std::uint64_t>(now - last));
        last = now;
      }
    }
  };
  metrics::Registry& r_;
  std::vector<Mirrored> outcomes_;
  std::vector<Mirrored> requests_;
  std::vector<Mirrored> reconciled_;
  std::vector<metrics::Gauge*> tasks_;
  std::vector<metrics::Gauge*> robots_;
};

}  // namespace fleet::manager
