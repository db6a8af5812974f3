#pragma once

// The load test's third stage: the tasks it feeds the fleet over the WMS adapter's HTTP API. Tasks
// fall due on the simulated clock, from the scenario's task list (each at its at_s) or generated
// at a rate (random pickup and drop-off); a poster sends what is due in batches of 100. Acknowledged
// ids go to the ledger, refused ones (4xx but 429) are counted and dropped, and unanswered or
// unavailable ones stay pending and are sent again (ids are idempotency keys).

#include <atomic>
#include <cstdint>
#include <functional>
#include <mutex>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <vector>

#include "scenario_tasks.hpp"
#include "task_ledger.hpp"

namespace httplib {
class Client;
}

namespace fleet::ctl {

class TaskFeeder {
 public:
  struct Source {
    std::vector<ScenarioTask> list;  // by at_s; posted when fromList
    bool fromList = false;
    std::vector<std::string> pickups, dropoffs;  // generated tasks
    double ratePerMin = 0;                       // generated tasks per simulated minute
    int maxTasks = 0;                            // generated: 0 no cap
    double endS = 0;                             // list tasks at or after it are never posted
    std::uint64_t seed = 7;
  };
  using Say = std::function<void(const std::string&)>;

  TaskFeeder(Source source, Say say);

  /// Hands the tasks due at simulated time `simS` to the poster.
  void due(double simS);
  /// One pass of the poster: everything pending, in batches of 100.
  void submit(httplib::Client& http);
  /// Posts every 200 ms until `stop` (on a thread of its own: a POST waits up to the adapter's
  /// acknowledgement timeout while the manager is down, and nothing else must wait for it).
  void run(httplib::Client& http, const std::atomic<bool>& stop);

  [[nodiscard]] int generated() const;
  [[nodiscard]] int refused() const { return refused_; }
  [[nodiscard]] int postErrors() const { return postErrors_; }
  [[nodiscard]] std::size_t pending() const;
  [[nodiscard]] std::size_t acknowledged() const;
  /// The acknowledged tasks against the store's rows.
  [[nodiscard]] Accounting reconcile(const std::vector<TaskRow>& tasks,
                                     const std::vector<TransitionRow>& transitions) const;

 private:
  Source src_;
  Say say_;
  std::mt19937_64 rng_;
  mutable std::mutex mu_;  // pending_, ledger_, generated_, listNext_
  std::vector<nlohmann::json> pending_;
  TaskLedger ledger_;
  int generated_ = 0;
  std::size_t listNext_ = 0;
  std::atomic<int> refused_{0};
  std::atomic<int> postErrors_{0};
};

}  // namespace fleet::ctl
