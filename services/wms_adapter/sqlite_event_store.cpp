#include "sqlite_event_store.hpp"

#include <stdexcept>

namespace fleet::wms {
namespace {

constexpr const char* kColumns =
    "SELECT id, task_id, seq, state, robot, reason, stamp_ns, station, priority, deadline_ns, eta_ns "
    "FROM task_events WHERE id > ?1 ORDER BY id LIMIT ?2";

LoggedEvent rowOf(const SqliteStmt& q) {
  LoggedEvent l;
  l.id = q.integer(0);
  l.event.task_id = q.text(1);
  l.event.seq = static_cast<std::uint32_t>(q.integer(2));
  msg::TaskState state{};
  l.event.state = msg::parse(q.text(3), state) ? state : msg::TaskState::Queued;
  l.event.robot_id = q.text(4);
  l.event.reason = q.text(5);
  l.event.stamp_ns = q.integer(6);
  l.event.station = q.text(7);
  if (!q.isNull(8)) {
    l.event.changed = true;
    l.event.priority = static_cast<std::int32_t>(q.integer(8));
    l.event.deadline_ns = q.integer(9);
  }
  l.event.eta_ns = q.isNull(10) ? 0 : q.integer(10);
  return l;
}

}  // namespace

SqliteEventStore::SqliteEventStore(std::shared_ptr<SqliteDb> db) : db_(std::move(db)) {
  std::lock_guard dbLock(db_->mutex());
  {
    // Never written into another program's database (the manager's task store, say).
    SqliteStmt q(*db_,
                 "SELECT name FROM sqlite_master WHERE type = 'table' AND name NOT IN "
                 "('task_events', 'webhooks', 'sqlite_sequence') LIMIT 1");
    if (q.step()) {
      throw std::runtime_error("\"" + db_->path() + "\" is not the adapter's event log (it has a table \"" +
                               q.text(0) + "\"): name a file of its own");
    }
  }
  db_->exec(
      "CREATE TABLE IF NOT EXISTS task_events("
      " id INTEGER PRIMARY KEY AUTOINCREMENT, task_id TEXT NOT NULL, seq INTEGER NOT NULL,"
      " state TEXT NOT NULL, robot TEXT NOT NULL, reason TEXT NOT NULL, stamp_ns INTEGER NOT NULL,"
      " station TEXT NOT NULL, logged_ns INTEGER NOT NULL, priority INTEGER, deadline_ns INTEGER,"
      " eta_ns INTEGER);"
      "CREATE INDEX IF NOT EXISTS task_events_by_task ON task_events(task_id, seq);"
      "CREATE INDEX IF NOT EXISTS task_events_by_time ON task_events(logged_ns);");
  {
    // A log written before changes of priority and deadline were logged gets their columns (NULL:
    // not a change).
    SqliteStmt q(*db_, "SELECT COUNT(*) FROM pragma_table_info('task_events') WHERE name = 'priority'");
    if (q.step() && q.integer(0) == 0) {
      db_->exec(
          "ALTER TABLE task_events ADD COLUMN priority INTEGER;"
          "ALTER TABLE task_events ADD COLUMN deadline_ns INTEGER;");
    }
  }
  {
    // A log written before events carried an ETA gets its column (NULL: no estimate).
    SqliteStmt q(*db_, "SELECT COUNT(*) FROM pragma_table_info('task_events') WHERE name = 'eta_ns'");
    if (q.step() && q.integer(0) == 0) {
      db_->exec("ALTER TABLE task_events ADD COLUMN eta_ns INTEGER;");
    }
  }
  seen_ = std::make_unique<SqliteStmt>(*db_, "SELECT 1 FROM task_events WHERE task_id = ?1 AND seq = ?2");
  insert_ = std::make_unique<SqliteStmt>(
      *db_,
      "INSERT INTO task_events(task_id, seq, state, robot, reason, stamp_ns, "
      "station, logged_ns, priority, deadline_ns, eta_ns) VALUES (?1, ?2, ?3, ?4, "
      "?5, ?6, ?7, ?8, ?9, ?10, ?11)");
}

std::vector<LoggedEvent> SqliteEventStore::append(const std::vector<msg::TaskEvent>& events,
                                                  std::int64_t nowNs,
                                                  std::int64_t /*known: only this adapter writes the file*/) {
  std::vector<LoggedEvent> added;
  std::lock_guard dbLock(db_->mutex());
  db_->exec("BEGIN IMMEDIATE");
  try {
    auto& seen = *seen_;
    auto& row = *insert_;
    for (const auto& e : events) {
      if (e.seq != 0) {
        seen.reset();
        seen.bind(1, e.task_id).bind(2, static_cast<std::int64_t>(e.seq));
        const bool logged = seen.step();
        seen.reset();  // no read left open (it would hold the WAL back from checkpoints)
        if (logged) {
          continue;
        }
      }
      row.reset();
      row.bind(1, e.task_id)
          .bind(2, static_cast<std::int64_t>(e.seq))
          .bind(3, std::string(msg::toString(e.state)))
          .bind(4, e.robot_id)
          .bind(5, e.reason)
          .bind(6, e.stamp_ns)
          .bind(7, e.station)
          .bind(8, nowNs);
      if (e.changed) {
        row.bind(9, std::int64_t{e.priority}).bind(10, e.deadline_ns);
      } else {
        row.bindNull(9).bindNull(10);
      }
      if (e.eta_ns > 0) {
        row.bind(11, e.eta_ns);
      } else {
        row.bindNull(11);
      }
      row.run();
      row.reset();
      added.push_back({sqlite3_last_insert_rowid(db_->handle()), e});
    }
    db_->exec("COMMIT");
  } catch (...) {
    seen_->reset();
    insert_->reset();
    db_->exec("ROLLBACK");
    throw;
  }
  return added;
}

std::vector<LoggedEvent> SqliteEventStore::after(std::int64_t after, std::size_t limit) const {
  std::vector<LoggedEvent> out;
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt q(*db_, kColumns);
  q.bind(1, after).bind(2, static_cast<std::int64_t>(limit));
  while (q.step()) {
    out.push_back(rowOf(q));
  }
  return out;
}

std::int64_t SqliteEventStore::lastId() const {
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt q(*db_, "SELECT seq FROM sqlite_sequence WHERE name = 'task_events'");
  return q.step() ? q.integer(0) : 0;
}

std::int64_t SqliteEventStore::prunedThrough() const {
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt q(*db_, "SELECT MIN(id) FROM task_events");
  return q.step() && !q.isNull(0) ? q.integer(0) - 1 : lastId();
}

std::int64_t SqliteEventStore::prune(std::int64_t keep, std::int64_t beforeNs) {
  std::lock_guard dbLock(db_->mutex());
  const std::int64_t newest = lastId();
  SqliteStmt byCount(*db_, "DELETE FROM task_events WHERE id <= ?1");
  byCount.bind(1, newest - keep).run();
  SqliteStmt byAge(*db_, "DELETE FROM task_events WHERE logged_ns < ?1");
  byAge.bind(1, beforeNs).run();
  SqliteStmt first(*db_, "SELECT MIN(id) FROM task_events");
  return first.step() && !first.isNull(0) ? first.integer(0) - 1 : newest;
}

}  // namespace fleet::wms
