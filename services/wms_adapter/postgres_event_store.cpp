#include "postgres_event_store.hpp"

#include <stdexcept>

#include "pg_errors.hpp"

namespace fleet::wms {
namespace {

// The advisory lock of the event log's appends and prunes (any constant other programs on the
// database do not use: "wmsevent" in ASCII).
constexpr const char* kLock = "SELECT pg_advisory_xact_lock(8606010379466966900)";

constexpr const char* kSchema =
    "CREATE TABLE IF NOT EXISTS wms_task_events("
    " id BIGINT GENERATED ALWAYS AS IDENTITY PRIMARY KEY, task_id TEXT NOT NULL, seq BIGINT,"
    " state TEXT NOT NULL, robot TEXT NOT NULL, reason TEXT NOT NULL, stamp_ns BIGINT NOT NULL,"
    " station TEXT NOT NULL, logged_ns BIGINT NOT NULL, priority INTEGER, deadline_ns BIGINT,"
    " eta_ns BIGINT);"
    // seq 0 is stored as NULL: always new (NULLs never conflict in a unique index).
    "CREATE UNIQUE INDEX IF NOT EXISTS wms_task_events_once ON wms_task_events(task_id, seq);"
    "CREATE INDEX IF NOT EXISTS wms_task_events_by_time ON wms_task_events(logged_ns);"
    "CREATE TABLE IF NOT EXISTS wms_event_log(one BOOLEAN PRIMARY KEY DEFAULT true CHECK (one),"
    " pruned_through BIGINT NOT NULL);"
    "INSERT INTO wms_event_log(pruned_through) VALUES (0) ON CONFLICT DO NOTHING";

constexpr const char* kSelect =
    "SELECT id, task_id, COALESCE(seq, 0), state, robot, reason, stamp_ns, station, priority, deadline_ns, "
    "eta_ns FROM wms_task_events";

using pg_errors::failed;
using pg_errors::orThrow;

std::vector<LoggedEvent> rowsOf(const pg::Result& r) {
  std::vector<LoggedEvent> out;
  out.reserve(static_cast<std::size_t>(r.rows()));
  for (int i = 0; i < r.rows(); ++i) {
    LoggedEvent l;
    l.id = r.integer(i, 0);
    l.event.task_id = r.text(i, 1);
    l.event.seq = static_cast<std::uint32_t>(r.integer(i, 2));
    msg::TaskState state{};
    l.event.state = msg::parse(r.text(i, 3), state) ? state : msg::TaskState::Queued;
    l.event.robot_id = r.text(i, 4);
    l.event.reason = r.text(i, 5);
    l.event.stamp_ns = r.integer(i, 6);
    l.event.station = r.text(i, 7);
    if (!r.isNull(i, 8)) {
      l.event.changed = true;
      l.event.priority = static_cast<std::int32_t>(r.integer(i, 8));
      l.event.deadline_ns = r.integer(i, 9);
    }
    l.event.eta_ns = r.isNull(i, 10) ? 0 : r.integer(i, 10);
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace

bool isPostgresUrl(const std::string& location) {
  return location.rfind("postgresql://", 0) == 0 || location.rfind("postgres://", 0) == 0;
}

PostgresEventStore::PostgresEventStore(const std::string& url) : url_(url), conn_(url) {
  // Checked before inserting, under the appends' lock: an id is never spent on a row not added.
  conn_.addStatement(
      "insert",
      "INSERT INTO wms_task_events(task_id, seq, state, robot, reason, stamp_ns, station, logged_ns, "
      "priority, deadline_ns, eta_ns) SELECT $1::text, $2::bigint, $3::text, $4::text, $5::text, "
      "$6::bigint, $7::text, $8::bigint, $9::integer, $10::bigint, $11::bigint WHERE $2::bigint IS "
      "NULL OR NOT EXISTS (SELECT 1 FROM wms_task_events WHERE task_id = $1::text AND seq = "
      "$2::bigint)");
  conn_.addStatement("after", std::string(kSelect) + " WHERE id > $1 ORDER BY id LIMIT $2");
  conn_.addStatement("last",
                     "SELECT GREATEST((SELECT COALESCE(MAX(id), 0) FROM wms_task_events), "
                     "(SELECT pruned_through FROM wms_event_log))");
  orThrow(url_, pg::checkUrl(url_));
  {
    // The tables first (statements are prepared on connecting); two replicas starting at once
    // make them under the lock.
    pg::Connection setup(url_);
    orThrow(url_, setup.begin());
    orThrow(url_, setup.exec("lock the event log", kLock));
    orThrow(url_, setup.exec("create the event log", kSchema));
    orThrow(url_, setup.commit());
  }
  orThrow(url_, conn_.ensure());
}

std::vector<LoggedEvent> PostgresEventStore::append(const std::vector<msg::TaskEvent>& events,
                                                    std::int64_t nowNs, std::int64_t known) {
  std::lock_guard lock(m_);
  std::vector<std::vector<pg::Param>> rows;
  rows.reserve(events.size());
  for (const auto& e : events) {
    rows.push_back({e.task_id, e.seq == 0 ? pg::Param() : pg::Param(std::to_string(e.seq)),
                    std::string(msg::toString(e.state)), e.robot_id, e.reason, std::to_string(e.stamp_ns),
                    e.station, std::to_string(nowNs),
                    e.changed ? pg::Param(std::to_string(e.priority)) : pg::Param(),
                    e.changed ? pg::Param(std::to_string(e.deadline_ns)) : pg::Param(),
                    e.eta_ns > 0 ? pg::Param(std::to_string(e.eta_ns)) : pg::Param()});
  }
  if (!rows.empty()) {
    orThrow(url_, conn_.begin());
    auto locked = conn_.exec("lock the event log", kLock);
    auto inserted = locked ? conn_.runAll("log task events", "insert", rows)
                           : Expected<std::vector<pg::Result>>(unexpected(locked.error()));
    if (!inserted) {
      conn_.rollback();
      throw failed(url_, inserted.error());
    }
    orThrow(url_, conn_.commit());
  }
  return rowsOf(orThrow(url_, conn_.run("read the event log", "after",
                                        {std::to_string(known), std::to_string(std::int64_t{1} << 20)})));
}

std::vector<LoggedEvent> PostgresEventStore::after(std::int64_t after, std::size_t limit) const {
  std::lock_guard lock(m_);
  return rowsOf(orThrow(
      url_, conn_.run("read the event log", "after", {std::to_string(after), std::to_string(limit)})));
}

std::int64_t PostgresEventStore::lastId() const {
  std::lock_guard lock(m_);
  const auto r = orThrow(url_, conn_.run("read the event log", "last", {}));
  return r.rows() > 0 ? r.integer(0, 0) : 0;
}

std::int64_t PostgresEventStore::prunedThrough() const {
  std::lock_guard lock(m_);
  const auto r = orThrow(url_, conn_.exec("read the event log",
                                          "SELECT GREATEST(pruned_through, COALESCE((SELECT MIN(id) - 1 FROM "
                                          "wms_task_events), pruned_through)) FROM wms_event_log"));
  return r.rows() > 0 ? r.integer(0, 0) : 0;
}

std::int64_t PostgresEventStore::prune(std::int64_t keep, std::int64_t beforeNs) {
  std::lock_guard lock(m_);
  orThrow(url_, conn_.begin());
  (void)conn_.exec("lock the event log", kLock);
  // The newest id before the deletes: what is pruned through when they leave no row.
  const auto last = conn_.run("read the event log", "last", {});
  const std::string newest = last && last->rows() > 0 ? last->text(0, 0) : "0";
  (void)conn_.exec("prune the event log", "DELETE FROM wms_task_events WHERE id <= $1::bigint - $2::bigint",
                   {newest, std::to_string(keep)});
  (void)conn_.exec("prune the event log", "DELETE FROM wms_task_events WHERE logged_ns < $1",
                   {std::to_string(beforeNs)});
  (void)conn_.exec("prune the event log",
                   "UPDATE wms_event_log SET pruned_through = GREATEST(pruned_through, "
                   "COALESCE((SELECT MIN(id) - 1 FROM wms_task_events), $1::bigint))",
                   {newest});
  auto through = conn_.exec("prune the event log", "SELECT pruned_through FROM wms_event_log");
  orThrow(url_, conn_.commit());  // a failed statement above fails the commit
  return through && through->rows() > 0 ? through->integer(0, 0) : 0;
}

}  // namespace fleet::wms
