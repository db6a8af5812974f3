#pragma once

// What a load test's task database holds at the end, for the ledger (task_ledger.hpp): the task
// rows and every transition in order, from the manager's SQLite file or from PostgreSQL.

#include <filesystem>
#include <string>
#include <vector>

#include "task_ledger.hpp"

namespace fleet::ctl {

struct StoreContents {
  std::vector<TaskRow> tasks;
  std::vector<TransitionRow> transitions;
  std::string error;  ///< what could not be read ("" when all was)
};

/// The tasks and transitions of the SQLite database at `path`, opened read-only.
StoreContents readSqliteStore(const std::filesystem::path& path);
/// The tasks and transitions of the PostgreSQL database at libpq URL `url`.
StoreContents readPostgresStore(const std::string& url);
/// Copies the tasks and transitions of the PostgreSQL database at `url` into a new SQLite file
/// `path` with the columns the run's figures and report read (tasks: id, kind, body, state, robot,
/// created_ns, updated_ns; transitions: seq, task_id, from_state, to_state, robot, reason,
/// stamp_ns). Empty on success, else what failed.
std::string copyPostgresToSqlite(const std::string& url, const std::filesystem::path& path);

}  // namespace fleet::ctl
