#include "fleet/fleet/postgres_task_store.hpp"

#include <limits>

#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/pg_connection.hpp"
#include "fleet/validation/utf8.hpp"
#include "task_store_rules.hpp"

namespace fleet {
namespace {

using pg::Param;

/// Ids order byte-wise (COLLATE "C"), as in SQLite, whatever the database's locale: list() pages
/// by id. Text must be UTF-8 in a UTF8 database: reasons are repaired before they are written.
constexpr const char* kSchemaV3 = R"sql(
CREATE TABLE IF NOT EXISTS tasks(
  id TEXT COLLATE "C" PRIMARY KEY,
  kind TEXT NOT NULL,
  body TEXT NOT NULL,
  state TEXT NOT NULL,
  robot TEXT NOT NULL DEFAULT '',
  attempts INTEGER NOT NULL DEFAULT 0,
  reason TEXT NOT NULL DEFAULT '',
  created_ns BIGINT NOT NULL,
  updated_ns BIGINT NOT NULL,
  revision BIGINT NOT NULL,
  paused BOOLEAN NOT NULL DEFAULT false,
  station TEXT NOT NULL DEFAULT ''
);
CREATE INDEX IF NOT EXISTS tasks_by_state ON tasks(state, id);
CREATE INDEX IF NOT EXISTS tasks_open ON tasks(created_ns, id)
  WHERE state NOT IN ('done', 'failed', 'cancelled');
CREATE TABLE IF NOT EXISTS transitions(
  seq BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY,
  task_id TEXT COLLATE "C" NOT NULL,
  from_state TEXT,
  to_state TEXT NOT NULL,
  robot TEXT NOT NULL DEFAULT '',
  reason TEXT NOT NULL DEFAULT '',
  stamp_ns BIGINT NOT NULL
);
CREATE INDEX IF NOT EXISTS transitions_by_task ON transitions(task_id, seq);
CREATE TABLE IF NOT EXISTS fleet_lease(
  name TEXT PRIMARY KEY,
  holder TEXT NOT NULL DEFAULT '',
  epoch BIGINT NOT NULL DEFAULT 0,
  expires_at TIMESTAMPTZ NOT NULL DEFAULT '-infinity'
);
)sql";

/// Version 4: the priority and deadline in force after a change (NULL until one; the body stays
/// as submitted, so a retry of the submission is still the same request).
constexpr const char* kSchemaV4 = R"sql(
ALTER TABLE tasks ADD COLUMN IF NOT EXISTS priority INTEGER;
ALTER TABLE tasks ADD COLUMN IF NOT EXISTS deadline_ns BIGINT;
)sql";

/// fleet_lease holds the fleet manager's lease (services/fleet_manager/manager_lease.hpp), whose
/// epoch fences the store's writes (fenceWith).
/// The steps from an older schema: each brings the database to its version. The first PostgreSQL
/// schema is version 3 (the SQLite store's versions 1 and 2 never existed here).
struct Migration {
  int version;
  const char* sql;
};
constexpr Migration kMigrations[] = {{3, kSchemaV3}, {4, kSchemaV4}};

/// Key of the advisory lock two managers starting at once take around creating or migrating the
/// schema ("fleetsch" in ASCII).
constexpr const char* kSchemaLock = "SELECT pg_advisory_xact_lock(7379531807330298728)";

constexpr const char* kRecordColumns =
    "id, body, state, robot, attempts, reason, created_ns, updated_ns, revision, paused, station, priority, "
    "deadline_ns";

Param num(std::int64_t v) {
  return std::to_string(v);
}
Param str(std::string_view v) {
  return std::string(v);
}

}  // namespace

struct PostgresTaskStore::Impl {
  explicit Impl(std::string url) : conn(std::move(url)) {}
  pg::Connection conn;
  std::string fenceName;
  std::int64_t fenceEpoch = 0;

  Expected<TaskRecord> readRecord(const pg::Result& s, int row) {
    TaskRecord r;
    const std::string id = s.text(row, 0);
    auto body = nlohmann::json::parse(s.text(row, 1), nullptr, false);
    auto task = parseTask(body);
    if (!task) {
      return unexpected(errc::kStorage, "stored task '" + id + "' is unreadable: " + task.error().message);
    }
    r.task = std::move(task).value();
    auto state = parseTaskState(s.text(row, 2));
    if (!state) {
      return unexpected(errc::kStorage,
                        "stored task '" + id + "' has unknown state '" + s.text(row, 2) + "'");
    }
    r.state = *state;
    r.robotId = s.text(row, 3);
    r.attempts = static_cast<std::int32_t>(s.integer(row, 4));
    r.reason = validation::repairUtf8(s.text(row, 5));
    r.task.createdNs = s.integer(row, 6);
    r.updatedNs = s.integer(row, 7);
    r.revision = s.integer(row, 8);
    r.paused = s.text(row, 9) == "t";
    if (std::string chosen = s.text(row, 10); !chosen.empty()) {
      r.task.station = std::move(chosen);
      r.stationChosen = true;
    }
    if (!s.isNull(row, 11)) {
      store_rules::setInForce(r, {static_cast<std::int32_t>(s.integer(row, 11)), s.integer(row, 12)});
    }
    return r;
  }

  Expected<std::vector<TaskRecord>> readAll(const Expected<pg::Result>& res) {
    if (!res) {
      return unexpected(res.error());
    }
    std::vector<TaskRecord> out;
    out.reserve(static_cast<std::size_t>(res->rows()));
    for (int i = 0; i < res->rows(); ++i) {
      auto r = readRecord(*res, i);
      if (!r) {
        return unexpected(r.error());
      }
      out.push_back(std::move(r).value());
    }
    return out;
  }

  /// The stored record (locked until the transaction ends when `forUpdate`), or not_found.
  Expected<TaskRecord> load(std::string_view id, bool forUpdate) {
    auto res = conn.run("read task", forUpdate ? "load_for_update" : "load", {str(id)});
    if (!res) {
      return unexpected(res.error());
    }
    if (res->rows() == 0) {
      return unexpected(errc::kNotFound, "no task '" + std::string(id) + "'");
    }
    return readRecord(*res, 0);
  }

  /// Inside a transaction.
  Expected<TaskRecord> transitionOne(const TransitionRequest& q) {
    auto cur = load(q.taskId, true);
    if (!cur) {
      return cur;
    }
    auto applied = store_rules::applyTransition(std::move(cur).value(), q);
    if (!applied) {
      return unexpected(applied.error());
    }
    const TaskRecord& r = applied->record;
    auto up =
        conn.run("update task", "update",
                 {str(toString(r.state)), str(r.robotId), num(r.attempts),
                  str(validation::repairUtf8(r.reason)), num(r.updatedNs), num(r.revision), str(q.taskId),
                  str(r.stationChosen ? std::string_view(r.task.station) : std::string_view()),
                  str(toString(applied->from)), str(applied->logRobot)});
    if (!up) {
      return unexpected(up.error());
    }
    return std::move(applied->record);
  }

  /// Opens a write transaction, checking the fence when one is set.
  Expected<void> beginWrite() {
    if (auto ok = conn.begin(); !ok) {
      return ok;
    }
    if (fenceName.empty()) {
      return {};
    }
    // FOR SHARE: a takeover's UPDATE of the lease row waits until this transaction ended, so no
    // write of an older epoch commits after the new holder took the lease.
    auto f = conn.run("check the lease", "fence", {str(fenceName)});
    if (!f) {
      conn.rollback();
      return unexpected(f.error());
    }
    if (f->rows() == 0 || f->integer(0, 0) != fenceEpoch) {
      conn.rollback();
      return unexpected(errc::kFenced, "lease '" + fenceName + "' is no longer at epoch " +
                                           std::to_string(fenceEpoch) + ": another manager took over");
    }
    return {};
  }

  /// Runs `body` in one write transaction; every item fails with the error when it cannot commit.
  template <class R, class F>
  std::vector<Expected<R>> batch(std::size_t n, F&& body) {
    std::vector<Expected<R>> out;
    out.reserve(n);
    auto ok = beginWrite();
    if (ok) {
      for (std::size_t i = 0; i < n; ++i) {
        out.push_back(body(i));
      }
      ok = conn.commit();
    }
    if (!ok) {
      out.clear();
      for (std::size_t i = 0; i < n; ++i) {
        out.emplace_back(unexpected(ok.error()));
      }
    }
    return out;
  }

  /// Creates the tables or brings them to store_rules::kSchemaVersion; refuses a newer schema.
  Expected<void> migrate() {
    if (auto ok = conn.begin(); !ok) {
      return ok;
    }
    auto fail = [&](const Error& e) -> Expected<void> {
      conn.rollback();
      return unexpected(e);
    };
    if (auto r = conn.exec("lock the schema", kSchemaLock); !r) {
      return fail(r.error());
    }
    if (auto r = conn.exec("create fleet_schema",
                           "CREATE TABLE IF NOT EXISTS fleet_schema(version INTEGER NOT NULL)");
        !r) {
      return fail(r.error());
    }
    auto v = conn.exec("read the schema version", "SELECT version FROM fleet_schema");
    if (!v) {
      return fail(v.error());
    }
    const std::int64_t version = v->rows() > 0 ? v->integer(0, 0) : 0;
    if (version > store_rules::kSchemaVersion) {
      return fail(store_rules::newerSchema("the PostgreSQL task database", version));
    }
    for (const auto& m : kMigrations) {
      if (m.version > version) {
        if (auto r = conn.exec("migrate to schema version " + std::to_string(m.version), m.sql); !r) {
          return fail(r.error());
        }
      }
    }
    if (version < store_rules::kSchemaVersion) {
      if (auto r = conn.exec("record the schema version", "DELETE FROM fleet_schema"); !r) {
        return fail(r.error());
      }
      if (auto r = conn.exec("record the schema version", "INSERT INTO fleet_schema(version) VALUES ($1)",
                             {num(store_rules::kSchemaVersion)});
          !r) {
        return fail(r.error());
      }
    }
    return conn.commit();
  }
};

PostgresTaskStore::PostgresTaskStore(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
PostgresTaskStore::~PostgresTaskStore() = default;

Expected<std::unique_ptr<PostgresTaskStore>> PostgresTaskStore::open(
    const PostgresTaskStoreOptions& options) {
  if (auto ok = pg::checkUrl(options.url); !ok) {
    return unexpected(ok.error());
  }
  auto impl = std::make_unique<Impl>(options.url);
  if (auto ok = impl->conn.ensure(); !ok) {
    return unexpected(ok.error());
  }
  if (auto ok = impl->migrate(); !ok) {
    return unexpected(ok.error());
  }
  // Prepared once the tables exist, and again on every new connection.
  const std::string sel = std::string("SELECT ") + kRecordColumns + " FROM tasks";
  auto& c = impl->conn;
  c.addStatement("load", sel + " WHERE id = $1");
  c.addStatement("load_for_update", sel + " WHERE id = $1 FOR UPDATE");
  c.addStatement(
      "insert",
      "WITH ins AS (INSERT INTO tasks(id, kind, body, state, reason, created_ns, updated_ns, revision) "
      "VALUES ($1, $2, $3, $4, $5, $6, $7, 1) ON CONFLICT (id) DO NOTHING RETURNING id) "
      "INSERT INTO transitions(task_id, from_state, to_state, robot, reason, stamp_ns) "
      "SELECT id, NULL, $4, '', $5, $7 FROM ins");
  c.addStatement(
      "update",
      "WITH up AS (UPDATE tasks SET state = $1, robot = $2, attempts = $3, reason = $4, updated_ns = $5, "
      "revision = $6, station = $8 WHERE id = $7 RETURNING id) "
      "INSERT INTO transitions(task_id, from_state, to_state, robot, reason, stamp_ns) "
      "SELECT id, $9, $1, $10, $4, $5 FROM up");
  c.addStatement("fence", "SELECT epoch FROM fleet_lease WHERE name = $1 FOR SHARE");
  c.addStatement("pause",
                 "UPDATE tasks SET paused = $1, updated_ns = $2, revision = revision + 1 WHERE id = $3");
  c.addStatement("wait_reason",
                 "UPDATE tasks SET reason = $1, updated_ns = $2, revision = revision + 1 WHERE id = $3");
  c.addStatement(
      "change",
      "UPDATE tasks SET priority = $1, deadline_ns = $2, updated_ns = $3, revision = $4 WHERE id = $5");
  c.addStatement("history",
                 "SELECT seq, task_id, from_state, to_state, robot, reason, stamp_ns FROM transitions "
                 "WHERE task_id = $1 ORDER BY seq");
  c.addStatement("counts", "SELECT state, COUNT(*) FROM tasks GROUP BY state");
  c.addStatement("open", sel + " WHERE state NOT IN ('done', 'failed', 'cancelled') ORDER BY created_ns, id");
  c.addStatement("list", sel + " WHERE id > $1 ORDER BY id LIMIT $2");
  c.addStatement("list_state", sel + " WHERE id > $1 AND state = $3 ORDER BY id LIMIT $2");
  c.close();  // opened again with the statements prepared
  if (auto ok = c.ensure(); !ok) {
    return unexpected(ok.error());
  }
  return std::unique_ptr<PostgresTaskStore>(new PostgresTaskStore(std::move(impl)));
}

void PostgresTaskStore::fenceWith(std::string leaseName, std::int64_t epoch) {
  std::lock_guard lock(mu_);
  impl_->fenceName = std::move(leaseName);
  impl_->fenceEpoch = epoch;
}

Expected<SubmitResult> PostgresTaskStore::submit(const Task& t, std::int64_t stampNs) {
  auto rs = submitBatch({t}, stampNs);
  return std::move(rs.front());
}

std::vector<Expected<SubmitResult>> PostgresTaskStore::submitBatch(const std::vector<Task>& tasks,
                                                                   std::int64_t stampNs) {
  std::lock_guard lock(mu_);
  // Every insert sent at once (one round trip); then, for the ids already taken, the stored record
  // read back to tell a retry from a conflict.
  std::vector<Expected<void>> valid;
  std::vector<std::string> bodies(tasks.size());
  std::vector<std::vector<Param>> inserts;
  valid.reserve(tasks.size());
  for (std::size_t i = 0; i < tasks.size(); ++i) {
    valid.push_back(store_rules::checkSubmission(tasks[i]));
    if (valid.back()) {
      bodies[i] = canonicalBody(tasks[i]);
      const TaskRecord r = store_rules::newRecord(tasks[i], stampNs);
      inserts.push_back({str(tasks[i].id), str(toString(tasks[i].kind)), str(bodies[i]),
                         str(toString(r.state)), str(r.reason), num(r.task.createdNs), num(stampNs)});
    }
  }
  std::optional<std::vector<pg::Result>> inserted;
  std::size_t next = 0;
  return impl_->batch<SubmitResult>(tasks.size(), [&](std::size_t i) -> Expected<SubmitResult> {
    if (!valid[i]) {
      return unexpected(valid[i].error());
    }
    if (!inserted) {
      auto all = impl_->conn.runAll("insert tasks", "insert", inserts);
      if (!all) {
        inserted.emplace();  // the transaction fails: commit rolls back and fails every item
        return unexpected(all.error());
      }
      inserted = std::move(*all);
    }
    if (next >= inserted->size()) {
      return unexpected(errc::kStorage, "postgresql: insert tasks failed");
    }
    if ((*inserted)[next++].affected() == 1) {
      return SubmitResult{store_rules::newRecord(tasks[i], stampNs), true};
    }
    auto existing = impl_->load(tasks[i].id, false);
    if (!existing) {
      return unexpected(existing.error());
    }
    if (auto ok = store_rules::checkResubmission(*existing, bodies[i]); !ok) {
      return unexpected(ok.error());
    }
    return SubmitResult{std::move(existing).value(), false};
  });
}

Expected<TaskRecord> PostgresTaskStore::transition(const TransitionRequest& r) {
  auto rs = transitionBatch({r});
  return std::move(rs.front());
}

std::vector<Expected<TaskRecord>> PostgresTaskStore::transitionBatch(
    const std::vector<TransitionRequest>& rs) {
  std::lock_guard lock(mu_);
  return impl_->batch<TaskRecord>(rs.size(), [&](std::size_t i) { return impl_->transitionOne(rs[i]); });
}

Expected<TaskRecord> PostgresTaskStore::setPaused(std::string_view id, bool paused, std::int64_t stampNs) {
  std::lock_guard lock(mu_);
  auto out = impl_->batch<TaskRecord>(1, [&](std::size_t) -> Expected<TaskRecord> {
    auto cur = impl_->load(id, true);
    if (!cur) {
      return cur;
    }
    if (auto ok = store_rules::checkPause(*cur); !ok) {
      return unexpected(ok.error());
    }
    if (cur->paused == paused) {
      return cur;  // idempotent: nothing to write
    }
    if (auto ok =
            impl_->conn.run("pause task", "pause", {str(paused ? "true" : "false"), num(stampNs), str(id)});
        !ok) {
      return unexpected(ok.error());
    }
    cur->paused = paused;
    cur->updatedNs = stampNs;
    ++cur->revision;  // an event of the task's: the revision counts it (task_store.hpp)
    return cur;
  });
  return std::move(out.front());
}

Expected<TaskRecord> PostgresTaskStore::setWaitReason(std::string_view id, std::string_view reason,
                                                      std::int64_t stampNs) {
  std::lock_guard lock(mu_);
  auto out = impl_->batch<TaskRecord>(1, [&](std::size_t) -> Expected<TaskRecord> {
    auto cur = impl_->load(id, true);
    if (!cur) {
      return cur;
    }
    if (auto ok = store_rules::checkWaitReason(*cur); !ok) {
      return unexpected(ok.error());
    }
    const std::string repaired = validation::repairUtf8(reason);
    if (cur->reason == repaired) {
      return cur;  // idempotent: nothing to write
    }
    if (auto ok = impl_->conn.run("set the reason of a waiting task", "wait_reason",
                                  {str(repaired), num(stampNs), str(id)});
        !ok) {
      return unexpected(ok.error());
    }
    cur->reason = repaired;
    cur->updatedNs = stampNs;
    ++cur->revision;  // an event of the task's: the revision counts it (task_store.hpp)
    return cur;
  });
  return std::move(out.front());
}

Expected<ChangeResult> PostgresTaskStore::change(const ChangeRequest& q) {
  std::lock_guard lock(mu_);
  auto out = impl_->batch<ChangeResult>(1, [&](std::size_t) -> Expected<ChangeResult> {
    auto cur = impl_->load(q.taskId, true);
    if (!cur) {
      return unexpected(cur.error());
    }
    auto applied = store_rules::applyChange(std::move(cur).value(), q);
    if (!applied || !applied->changed) {
      return applied;
    }
    const TaskRecord& r = applied->record;
    if (auto ok = impl_->conn.run(
            "change task", "change",
            {num(r.task.priority), num(r.task.deadlineNs), num(r.updatedNs), num(r.revision), str(q.taskId)});
        !ok) {
      return unexpected(ok.error());
    }
    return applied;
  });
  return std::move(out.front());
}

Expected<TaskRecord> PostgresTaskStore::get(std::string_view id) {
  std::lock_guard lock(mu_);
  return impl_->load(id, false);
}

Expected<std::vector<TaskRecord>> PostgresTaskStore::list(std::optional<TaskState> state, std::size_t limit,
                                                          std::string_view afterId) {
  std::lock_guard lock(mu_);
  const auto n = static_cast<std::int64_t>(
      std::min<std::size_t>(limit, static_cast<std::size_t>(std::numeric_limits<std::int64_t>::max())));
  if (state) {
    return impl_->readAll(
        impl_->conn.run("list tasks", "list_state", {str(afterId), num(n), str(toString(*state))}));
  }
  return impl_->readAll(impl_->conn.run("list tasks", "list", {str(afterId), num(n)}));
}

Expected<std::vector<TaskRecord>> PostgresTaskStore::openTasks() {
  std::lock_guard lock(mu_);
  return impl_->readAll(impl_->conn.run("list open tasks", "open", {}));
}

Expected<std::vector<TransitionRecord>> PostgresTaskStore::history(std::string_view id) {
  std::lock_guard lock(mu_);
  auto res = impl_->conn.run("read history", "history", {str(id)});
  if (!res) {
    return unexpected(res.error());
  }
  std::vector<TransitionRecord> out;
  for (int i = 0; i < res->rows(); ++i) {
    TransitionRecord t;
    t.seq = res->integer(i, 0);
    t.taskId = res->text(i, 1);
    if (!res->isNull(i, 2)) {
      t.from = parseTaskState(res->text(i, 2));
    }
    t.to = parseTaskState(res->text(i, 3)).value_or(TaskState::Queued);
    t.robotId = res->text(i, 4);
    t.reason = validation::repairUtf8(res->text(i, 5));
    t.stampNs = res->integer(i, 6);
    out.push_back(std::move(t));
  }
  return out;
}

Expected<std::map<TaskState, std::int64_t>> PostgresTaskStore::countByState() {
  std::lock_guard lock(mu_);
  auto res = impl_->conn.run("count tasks", "counts", {});
  if (!res) {
    return unexpected(res.error());
  }
  std::map<TaskState, std::int64_t> out;
  for (int i = 0; i < res->rows(); ++i) {
    if (auto st = parseTaskState(res->text(i, 0))) {
      out[*st] = res->integer(i, 1);
    }
  }
  return out;
}

}  // namespace fleet
