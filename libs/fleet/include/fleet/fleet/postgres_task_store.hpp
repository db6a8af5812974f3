#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "fleet/fleet/task_store.hpp"

namespace fleet {

struct PostgresTaskStoreOptions {
  /// A libpq connection URI or key=value string: postgresql://user@host1:5432,host2:5432/fleet?
  /// target_session_attrs=read-write finds the primary among several hosts.
  std::string url;
};

/// TaskStore on PostgreSQL (libpq). Thread-safe (one connection behind a mutex). Every write is one
/// transaction that has committed when the call returns (durable as the server's
/// synchronous_commit makes it). A lost connection fails the call with "storage" and is opened
/// again (every host of the URL tried) by the next call.
class PostgresTaskStore final : public TaskStore {
 public:
  /// Connects, creates the tables or migrates them to store_rules' schema version (recorded in
  /// table fleet_schema), refusing a newer schema. Errors: invalid (a malformed URL), storage.
  static Expected<std::unique_ptr<PostgresTaskStore>> open(const PostgresTaskStoreOptions& options);
  ~PostgresTaskStore() override;
  PostgresTaskStore(const PostgresTaskStore&) = delete;
  PostgresTaskStore& operator=(const PostgresTaskStore&) = delete;

  /// Fencing: from now on every write transaction first checks (and holds shared until it
  /// commits) that lease `leaseName` in table fleet_lease is still at `epoch`; when it is not, the
  /// write stores nothing and fails with errc::kFenced. A manager that lost its lease can then not
  /// commit an assignment the new holder does not know about.
  void fenceWith(std::string leaseName, std::int64_t epoch);

  Expected<SubmitResult> submit(const Task& t, std::int64_t stampNs) override;
  std::vector<Expected<SubmitResult>> submitBatch(const std::vector<Task>& tasks,
                                                  std::int64_t stampNs) override;
  using TaskStore::transition;
  Expected<TaskRecord> transition(const TransitionRequest& r) override;
  std::vector<Expected<TaskRecord>> transitionBatch(const std::vector<TransitionRequest>& rs) override;
  Expected<TaskRecord> setPaused(std::string_view id, bool paused, std::int64_t stampNs) override;
  Expected<TaskRecord> setWaitReason(std::string_view id, std::string_view reason,
                                     std::int64_t stampNs) override;
  Expected<ChangeResult> change(const ChangeRequest& r) override;
  Expected<TaskRecord> get(std::string_view id) override;
  Expected<std::vector<TaskRecord>> list(std::optional<TaskState> state, std::size_t limit,
                                         std::string_view afterId = {}) override;
  Expected<std::vector<TaskRecord>> openTasks() override;
  Expected<std::vector<TransitionRecord>> history(std::string_view id) override;
  Expected<std::map<TaskState, std::int64_t>> countByState() override;

 private:
  struct Impl;
  explicit PostgresTaskStore(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  std::mutex mu_;
};

}  // namespace fleet
