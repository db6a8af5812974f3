#include "fleet/fleet/sqlite_task_store.hpp"

#include <sqlite3.h>

#include <array>
#include <limits>

#include "fleet/core/ids.hpp"
#include "fleet/fleet/errors.hpp"
#include "fleet/validation/utf8.hpp"
#include "task_store_rules.hpp"

namespace fleet {
namespace {

Unexpected<Error> storageError(sqlite3* db, std::string_view what) {
  return unexpected(errc::kStorage,
                    std::string(what) + ": " + (db != nullptr ? sqlite3_errmsg(db) : "no database"));
}

/// A prepared statement, reset after every use so it can be reused.
class Stmt {
 public:
  Stmt() = default;
  Stmt(const Stmt&) = delete;
  Stmt& operator=(const Stmt&) = delete;
  ~Stmt() { sqlite3_finalize(s_); }

  bool prepare(sqlite3* db, const char* sql) {
    return sqlite3_prepare_v3(db, sql, -1, SQLITE_PREPARE_PERSISTENT, &s_, nullptr) == SQLITE_OK;
  }
  sqlite3_stmt* get() const { return s_; }

  // Text is bound without copying (destructor nullptr = SQLITE_STATIC): every statement is stepped
  // and reset while the bound strings are alive.
  // A default string_view has a null data() that SQLite would bind as NULL, hence the "".
  void bind(int i, std::string_view v) {
    sqlite3_bind_text(s_, i, v.data() != nullptr ? v.data() : "", static_cast<int>(v.size()), nullptr);
  }
  void bind(int i, std::int64_t v) { sqlite3_bind_int64(s_, i, v); }
  void bindNull(int i) { sqlite3_bind_null(s_, i); }
  int step() { return sqlite3_step(s_); }
  void reset() {
    sqlite3_reset(s_);
    sqlite3_clear_bindings(s_);
  }
  std::string text(int col) const {
    const auto* p = sqlite3_column_text(s_, col);
    return p == nullptr ? std::string()
                        : std::string(reinterpret_cast<const char*>(p),
                                      static_cast<std::size_t>(sqlite3_column_bytes(s_, col)));
  }
  std::int64_t integer(int col) const { return sqlite3_column_int64(s_, col); }
  bool isNull(int col) const { return sqlite3_column_type(s_, col) == SQLITE_NULL; }

 private:
  sqlite3_stmt* s_ = nullptr;
};

struct ResetGuard {
  Stmt& s;
  ~ResetGuard() { s.reset(); }
};

constexpr const char* kSchema = R"sql(
CREATE TABLE IF NOT EXISTS tasks(
  id TEXT PRIMARY KEY,
  kind TEXT NOT NULL,
  body TEXT NOT NULL,
  state TEXT NOT NULL,
  robot TEXT NOT NULL DEFAULT '',
  attempts INTEGER NOT NULL DEFAULT 0,
  reason TEXT NOT NULL DEFAULT '',
  created_ns INTEGER NOT NULL,
  updated_ns INTEGER NOT NULL,
  revision INTEGER NOT NULL,
  paused INTEGER NOT NULL DEFAULT 0,
  station TEXT NOT NULL DEFAULT '',
  priority INTEGER,
  deadline_ns INTEGER
) WITHOUT ROWID;
CREATE INDEX IF NOT EXISTS tasks_by_state ON tasks(state, id);
CREATE TABLE IF NOT EXISTS transitions(
  seq INTEGER PRIMARY KEY AUTOINCREMENT,
  task_id TEXT NOT NULL,
  from_state TEXT,
  to_state TEXT NOT NULL,
  robot TEXT NOT NULL DEFAULT '',
  reason TEXT NOT NULL DEFAULT '',
  stamp_ns INTEGER NOT NULL
);
CREATE INDEX IF NOT EXISTS transitions_by_task ON transitions(task_id, seq);
)sql";

/// PRAGMA user_version: store_rules::kSchemaVersion (version 2 added tasks.paused, version 3
/// tasks.station, version 4 tasks.priority and tasks.deadline_ns, NULL until a change; the body
/// stays as submitted, so a retry of the request is still the same request). An older database
/// gets the columns on open; a newer one is refused.
constexpr int kSchemaVersion = store_rules::kSchemaVersion;

constexpr const char* kRecordColumns =
    "id, body, state, robot, attempts, reason, created_ns, updated_ns, revision, paused, station, priority, "
    "deadline_ns";

}  // namespace

struct SqliteTaskStore::Impl {
  sqlite3* db = nullptr;
  Stmt begin, commit, rollback, select, insert, update, log, history, counts, open, pause, waitReason, change;

  ~Impl() {
    // close_v2 defers the close until the statements (members, destroyed after this body) are
    // finalized.
    if (db != nullptr) {
      sqlite3_close_v2(db);
    }
  }

  Expected<void> exec(const char* sql) {
    char* err = nullptr;
    if (sqlite3_exec(db, sql, nullptr, nullptr, &err) != SQLITE_OK) {
      std::string msg = err != nullptr ? err : "unknown";
      sqlite3_free(err);
      return unexpected(errc::kStorage, std::string("sqlite: ") + msg);
    }
    return {};
  }

  Expected<void> stepDone(Stmt& s, std::string_view what) {
    ResetGuard g{s};
    if (s.step() != SQLITE_DONE) {
      return storageError(db, what);
    }
    return {};
  }

  Expected<TaskRecord> readRecord(const Stmt& s) {
    TaskRecord r;
    auto body = nlohmann::json::parse(s.text(1), nullptr, false);
    auto task = parseTask(body);
    if (!task) {
      return unexpected(errc::kStorage,
                        "stored task '" + s.text(0) + "' is unreadable: " + task.error().message);
    }
    r.task = std::move(task).value();
    auto state = parseTaskState(s.text(2));
    if (!state) {
      return unexpected(errc::kStorage,
                        "stored task '" + s.text(0) + "' has unknown state '" + s.text(2) + "'");
    }
    r.state = *state;
    r.robotId = s.text(3);
    r.attempts = static_cast<std::int32_t>(s.integer(4));
    // Databases written before reasons were repaired at the manager's edge may hold bytes that are
    // not UTF-8 (a robot's error); every reader of a record turns reasons into JSON.
    r.reason = validation::repairUtf8(s.text(5));
    r.task.createdNs = s.integer(6);
    r.updatedNs = s.integer(7);
    r.revision = s.integer(8);
    r.paused = s.integer(9) != 0;
    if (std::string chosen = s.text(10); !chosen.empty()) {
      r.task.station = std::move(chosen);
      r.stationChosen = true;
    }
    if (!s.isNull(11)) {
      store_rules::setInForce(r, {static_cast<std::int32_t>(s.integer(11)), s.integer(12)});
    }
    return r;
  }

  /// The stored record, or not_found.
  Expected<TaskRecord> load(std::string_view id) {
    ResetGuard g{select};
    select.bind(1, id);
    const int rc = select.step();
    if (rc == SQLITE_DONE) {
      return unexpected(errc::kNotFound, "no task '" + std::string(id) + "'");
    }
    if (rc != SQLITE_ROW) {
      return storageError(db, "read task");
    }
    return readRecord(select);
  }

  Expected<void> appendLog(std::string_view id, std::optional<TaskState> from, TaskState to,
                           std::string_view robot, std::string_view reason, std::int64_t stamp) {
    log.bind(1, id);
    if (from) {
      log.bind(2, toString(*from));
    } else {
      log.bindNull(2);
    }
    log.bind(3, toString(to));
    log.bind(4, robot);
    log.bind(5, reason);
    log.bind(6, stamp);
    return stepDone(log, "append transition");
  }

  /// Inside a transaction.
  Expected<SubmitResult> submitOne(const Task& t, std::int64_t stamp) {
    if (auto ok = store_rules::checkSubmission(t); !ok) {
      return unexpected(ok.error());
    }
    const std::string body = canonicalBody(t);
    auto existing = load(t.id);
    if (existing) {
      if (auto ok = store_rules::checkResubmission(*existing, body); !ok) {
        return unexpected(ok.error());
      }
      return SubmitResult{std::move(existing).value(), false};
    }
    if (existing.error().code != errc::kNotFound) {
      return unexpected(existing.error());
    }
    TaskRecord r = store_rules::newRecord(t, stamp);
    insert.bind(1, t.id);
    insert.bind(2, toString(t.kind));
    insert.bind(3, body);
    insert.bind(4, toString(r.state));
    insert.bind(5, r.reason);
    insert.bind(6, r.task.createdNs);
    insert.bind(7, stamp);
    if (auto ok = stepDone(insert, "insert task"); !ok) {
      return unexpected(ok.error());
    }
    if (auto ok = appendLog(t.id, std::nullopt, r.state, "", r.reason, stamp); !ok) {
      return unexpected(ok.error());
    }
    return SubmitResult{std::move(r), true};
  }

  /// Inside a transaction.
  /// Brings an older database to kSchemaVersion (a fresh one only gets its version stamped).
  Expected<void> migrate() {
    Stmt v;
    if (!v.prepare(db, "PRAGMA user_version")) {
      return storageError(db, "read the schema version");
    }
    const int version = v.step() == SQLITE_ROW ? static_cast<int>(v.integer(0)) : 0;
    v.reset();
    if (version > kSchemaVersion) {
      return unexpected(store_rules::newerSchema("the task database", version));
    }
    if (version == kSchemaVersion) {
      return {};
    }
    Stmt cols;
    if (!cols.prepare(db, "SELECT COUNT(*) FROM pragma_table_info('tasks') WHERE name = ?1")) {
      return storageError(db, "read the tasks table's columns");
    }
    for (const auto& [name, ddl] :
         {std::pair{"paused", "ALTER TABLE tasks ADD COLUMN paused INTEGER NOT NULL DEFAULT 0"},
          std::pair{"station", "ALTER TABLE tasks ADD COLUMN station TEXT NOT NULL DEFAULT ''"},
          std::pair{"priority", "ALTER TABLE tasks ADD COLUMN priority INTEGER"},
          std::pair{"deadline_ns", "ALTER TABLE tasks ADD COLUMN deadline_ns INTEGER"}}) {
      cols.bind(1, std::string_view(name));
      const bool has = cols.step() == SQLITE_ROW && cols.integer(0) > 0;
      cols.reset();
      if (!has) {
        if (auto ok = exec(ddl); !ok) {
          return ok;
        }
      }
    }
    return exec(("PRAGMA user_version = " + std::to_string(kSchemaVersion)).c_str());
  }

  Expected<TaskRecord> transitionOne(const TransitionRequest& q) {
    auto cur = load(q.taskId);
    if (!cur) {
      return cur;
    }
    auto applied = store_rules::applyTransition(std::move(cur).value(), q);
    if (!applied) {
      return unexpected(applied.error());
    }
    TaskRecord& r = applied->record;
    update.bind(1, toString(r.state));
    update.bind(2, r.robotId);
    update.bind(3, static_cast<std::int64_t>(r.attempts));
    update.bind(4, r.reason);
    update.bind(5, r.updatedNs);
    update.bind(6, r.revision);
    update.bind(7, q.taskId);
    update.bind(8, r.stationChosen ? std::string_view(r.task.station) : std::string_view());
    if (auto ok = stepDone(update, "update task"); !ok) {
      return unexpected(ok.error());
    }
    if (auto ok = appendLog(q.taskId, applied->from, q.to, applied->logRobot, q.reason, q.stampNs); !ok) {
      return unexpected(ok.error());
    }
    return r;
  }

  Expected<std::vector<TaskRecord>> readAll(Stmt& s) {
    std::vector<TaskRecord> out;
    ResetGuard g{s};
    for (;;) {
      const int rc = s.step();
      if (rc == SQLITE_DONE) {
        break;
      }
      if (rc != SQLITE_ROW) {
        return storageError(db, "list tasks");
      }
      auto r = readRecord(s);
      if (!r) {
        return unexpected(r.error());
      }
      out.push_back(std::move(r).value());
    }
    return out;
  }

  /// Runs `body` in one IMMEDIATE transaction; commits unless it returns false.
  template <class F>
  Expected<void> inTransaction(F&& body) {
    if (auto ok = stepDone(begin, "begin"); !ok) {
      return ok;
    }
    body();
    if (auto ok = stepDone(commit, "commit"); !ok) {
      (void)stepDone(rollback, "rollback");
      return ok;
    }
    return {};
  }
};

SqliteTaskStore::SqliteTaskStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
SqliteTaskStore::~SqliteTaskStore() = default;

Expected<std::unique_ptr<SqliteTaskStore>> SqliteTaskStore::open(const SqliteTaskStoreOptions& options) {
  auto impl = std::make_unique<Impl>();
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_NOMUTEX;
  if (sqlite3_open_v2(options.path.c_str(), &impl->db, flags, nullptr) != SQLITE_OK) {
    return storageError(impl->db, "open '" + options.path + "'");
  }
  sqlite3_busy_timeout(impl->db, options.busyTimeoutMs);
  const std::string pragmas = std::string("PRAGMA journal_mode=WAL; PRAGMA synchronous=") +
                              (options.sync == SqliteTaskStoreOptions::Sync::Full ? "FULL" : "NORMAL") +
                              "; PRAGMA foreign_keys=ON;";
  if (auto ok = impl->exec(pragmas.c_str()); !ok) {
    return unexpected(ok.error());
  }
  if (auto ok = impl->exec(kSchema); !ok) {
    return unexpected(ok.error());
  }
  if (auto ok = impl->migrate(); !ok) {
    return unexpected(ok.error());
  }
  const std::string sel = std::string("SELECT ") + kRecordColumns + " FROM tasks";
  const std::array<std::pair<Stmt*, std::string>, 13> stmts = {{
      {&impl->begin, "BEGIN IMMEDIATE"},
      {&impl->commit, "COMMIT"},
      {&impl->rollback, "ROLLBACK"},
      {&impl->select, sel + " WHERE id = ?1"},
      {&impl->insert,
       "INSERT INTO tasks(id, kind, body, state, robot, attempts, reason, created_ns, updated_ns, revision) "
       "VALUES (?1, ?2, ?3, ?4, '', 0, ?5, ?6, ?7, 1)"},
      {&impl->update,
       "UPDATE tasks SET state = ?1, robot = ?2, attempts = ?3, reason = ?4, updated_ns = ?5, revision = ?6, "
       "station = ?8 WHERE id = ?7"},
      {&impl->log,
       "INSERT INTO transitions(task_id, from_state, to_state, robot, reason, stamp_ns) VALUES (?1, ?2, ?3, "
       "?4, ?5, "
       "?6)"},
      {&impl->history,
       "SELECT seq, task_id, from_state, to_state, robot, reason, stamp_ns FROM transitions WHERE task_id = "
       "?1 "
       "ORDER BY seq"},
      {&impl->counts, "SELECT state, COUNT(*) FROM tasks GROUP BY state"},
      {&impl->pause, "UPDATE tasks SET paused = ?1, updated_ns = ?2, revision = revision + 1 WHERE id = ?3"},
      {&impl->waitReason,
       "UPDATE tasks SET reason = ?1, updated_ns = ?2, revision = revision + 1 WHERE id = ?3"},
      {&impl->change,
       "UPDATE tasks SET priority = ?1, deadline_ns = ?2, updated_ns = ?3, revision = ?4 WHERE id = ?5"},
      {&impl->open, sel + " WHERE state NOT IN ('done', 'failed', 'cancelled') ORDER BY created_ns, id"},
  }};
  for (const auto& [stmt, sql] : stmts) {
    if (!stmt->prepare(impl->db, sql.c_str())) {
      return storageError(impl->db, "prepare '" + sql + "'");
    }
  }
  return std::unique_ptr<SqliteTaskStore>(new SqliteTaskStore(std::move(impl)));
}

Expected<SubmitResult> SqliteTaskStore::submit(const Task& t, std::int64_t stampNs) {
  auto rs = submitBatch({t}, stampNs);
  return std::move(rs.front());
}

std::vector<Expected<SubmitResult>> SqliteTaskStore::submitBatch(const std::vector<Task>& tasks,
                                                                 std::int64_t stampNs) {
  std::lock_guard lock(mu_);
  std::vector<Expected<SubmitResult>> out;
  out.reserve(tasks.size());
  auto ok = impl_->inTransaction([&] {
    for (const auto& t : tasks) {
      out.push_back(impl_->submitOne(t, stampNs));
    }
  });
  if (!ok) {
    out.clear();
    for (std::size_t i = 0; i < tasks.size(); ++i) {
      out.emplace_back(unexpected(ok.error()));
    }
  }
  return out;
}

Expected<TaskRecord> SqliteTaskStore::transition(const TransitionRequest& r) {
  auto rs = transitionBatch({r});
  return std::move(rs.front());
}

std::vector<Expected<TaskRecord>> SqliteTaskStore::transitionBatch(const std::vector<TransitionRequest>& rs) {
  std::lock_guard lock(mu_);
  std::vector<Expected<TaskRecord>> out;
  out.reserve(rs.size());
  auto ok = impl_->inTransaction([&] {
    for (const auto& r : rs) {
      out.push_back(impl_->transitionOne(r));
    }
  });
  if (!ok) {
    out.clear();
    for (std::size_t i = 0; i < rs.size(); ++i) {
      out.emplace_back(unexpected(ok.error()));
    }
  }
  return out;
}

Expected<TaskRecord> SqliteTaskStore::setPaused(std::string_view id, bool paused, std::int64_t stampNs) {
  std::lock_guard lock(mu_);
  auto cur = impl_->load(id);
  if (!cur) {
    return cur;
  }
  if (auto ok = store_rules::checkPause(*cur); !ok) {
    return unexpected(ok.error());
  }
  if (cur->paused == paused) {
    return cur;  // idempotent: nothing to write
  }
  impl_->pause.bind(1, static_cast<std::int64_t>(paused ? 1 : 0));
  impl_->pause.bind(2, stampNs);
  impl_->pause.bind(3, id);
  if (auto ok = impl_->stepDone(impl_->pause, "pause task"); !ok) {
    return unexpected(ok.error());
  }
  cur->paused = paused;
  cur->updatedNs = stampNs;
  ++cur->revision;  // an event of the task's: the revision counts it (task_store.hpp)
  return cur;
}

Expected<TaskRecord> SqliteTaskStore::setWaitReason(std::string_view id, std::string_view reason,
                                                    std::int64_t stampNs) {
  std::lock_guard lock(mu_);
  auto cur = impl_->load(id);
  if (!cur) {
    return cur;
  }
  if (auto ok = store_rules::checkWaitReason(*cur); !ok) {
    return unexpected(ok.error());
  }
  if (cur->reason == reason) {
    return cur;  // idempotent: nothing to write
  }
  impl_->waitReason.bind(1, reason);
  impl_->waitReason.bind(2, stampNs);
  impl_->waitReason.bind(3, id);
  if (auto ok = impl_->stepDone(impl_->waitReason, "set the reason of a waiting task"); !ok) {
    return unexpected(ok.error());
  }
  cur->reason = std::string(reason);
  cur->updatedNs = stampNs;
  ++cur->revision;  // an event of the task's: the revision counts it (task_store.hpp)
  return cur;
}

Expected<ChangeResult> SqliteTaskStore::change(const ChangeRequest& q) {
  std::lock_guard lock(mu_);
  auto cur = impl_->load(q.taskId);
  if (!cur) {
    return unexpected(cur.error());
  }
  auto applied = store_rules::applyChange(std::move(cur).value(), q);
  if (!applied || !applied->changed) {
    return applied;
  }
  const TaskRecord& r = applied->record;
  auto& s = impl_->change;
  s.bind(1, static_cast<std::int64_t>(r.task.priority));
  s.bind(2, r.task.deadlineNs);
  s.bind(3, r.updatedNs);
  s.bind(4, r.revision);
  s.bind(5, q.taskId);
  if (auto ok = impl_->stepDone(s, "change task"); !ok) {
    return unexpected(ok.error());
  }
  return applied;
}

Expected<TaskRecord> SqliteTaskStore::get(std::string_view id) {
  std::lock_guard lock(mu_);
  return impl_->load(id);
}

Expected<std::vector<TaskRecord>> SqliteTaskStore::list(std::optional<TaskState> state, std::size_t limit,
                                                        std::string_view afterId) {
  std::lock_guard lock(mu_);
  std::string sql = std::string("SELECT ") + kRecordColumns + " FROM tasks WHERE id > ?1";
  if (state) {
    sql += " AND state = ?2";
  }
  sql += " ORDER BY id LIMIT ?3";
  Stmt s;
  if (!s.prepare(impl_->db, sql.c_str())) {
    return storageError(impl_->db, "prepare list");
  }
  s.bind(1, afterId);
  if (state) {
    s.bind(2, toString(*state));
  }
  s.bind(3, static_cast<std::int64_t>(std::min<std::size_t>(
                limit, static_cast<std::size_t>(std::numeric_limits<std::int64_t>::max()))));
  return impl_->readAll(s);
}

Expected<std::vector<TaskRecord>> SqliteTaskStore::openTasks() {
  std::lock_guard lock(mu_);
  return impl_->readAll(impl_->open);
}

Expected<std::vector<TransitionRecord>> SqliteTaskStore::history(std::string_view id) {
  std::lock_guard lock(mu_);
  auto& s = impl_->history;
  ResetGuard g{s};
  s.bind(1, id);
  std::vector<TransitionRecord> out;
  for (;;) {
    const int rc = s.step();
    if (rc == SQLITE_DONE) {
      break;
    }
    if (rc != SQLITE_ROW) {
      return storageError(impl_->db, "read history");
    }
    TransitionRecord t;
    t.seq = s.integer(0);
    t.taskId = s.text(1);
    if (!s.isNull(2)) {
      t.from = parseTaskState(s.text(2));
    }
    t.to = parseTaskState(s.text(3)).value_or(TaskState::Queued);
    t.robotId = s.text(4);
    t.reason = validation::repairUtf8(s.text(5));
    t.stampNs = s.integer(6);
    out.push_back(std::move(t));
  }
  return out;
}

Expected<std::map<TaskState, std::int64_t>> SqliteTaskStore::countByState() {
  std::lock_guard lock(mu_);
  auto& s = impl_->counts;
  ResetGuard g{s};
  std::map<TaskState, std::int64_t> out;
  for (;;) {
    const int rc = s.step();
    if (rc == SQLITE_DONE) {
      break;
    }
    if (rc != SQLITE_ROW) {
      return storageError(impl_->db, "count tasks");
    }
    if (auto st = parseTaskState(s.text(0))) {
      out[*st] = s.integer(1);
    }
  }
  return out;
}

}  // namespace fleet
