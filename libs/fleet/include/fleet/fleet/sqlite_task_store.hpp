#pragma once

#include <memory>
#include <mutex>
#include <string>

#include "fleet/fleet/task_store.hpp"

struct sqlite3;

namespace fleet {

struct SqliteTaskStoreOptions {
  std::string path;  ///< database file; ":memory:" for tests that need no durability
  /// FULL: a commit survives power loss (fsync of the WAL on every commit). NORMAL: survives a
  /// crash of the process but the last commits may be lost on power loss. See docs/algorithms.md.
  enum class Sync { Normal, Full } sync = Sync::Full;
  int busyTimeoutMs = 5000;
};

/// TaskStore on SQLite in WAL mode. Thread-safe (one connection behind a mutex).
class SqliteTaskStore final : public TaskStore {
 public:
  static Expected<std::unique_ptr<SqliteTaskStore>> open(const SqliteTaskStoreOptions& options);
  ~SqliteTaskStore() override;
  SqliteTaskStore(const SqliteTaskStore&) = delete;
  SqliteTaskStore& operator=(const SqliteTaskStore&) = delete;

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
  explicit SqliteTaskStore(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
  std::mutex mu_;
};

}  // namespace fleet
