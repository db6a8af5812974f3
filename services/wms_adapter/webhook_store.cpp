#include "webhook_store.hpp"

#include <stdexcept>

#include "pg_errors.hpp"

namespace fleet::wms {
namespace {

constexpr const char* kSelectWebhooks =
    "SELECT id, url, secret, created_ns, delivered_through, state, deliveries, failures, last_error, "
    "last_attempt_ns, last_success_ns FROM ";

}  // namespace

// ---- SQLite: the adapter's own file, beside the event log ----

SqliteWebhookStore::SqliteWebhookStore(std::shared_ptr<SqliteDb> db) : db_(std::move(db)) {
  std::lock_guard dbLock(db_->mutex());
  db_->exec(
      "CREATE TABLE IF NOT EXISTS webhooks("
      " id TEXT PRIMARY KEY, url TEXT NOT NULL, secret TEXT NOT NULL, created_ns INTEGER NOT NULL,"
      " delivered_through INTEGER NOT NULL, state TEXT NOT NULL, deliveries INTEGER NOT NULL,"
      " failures INTEGER NOT NULL, last_error TEXT NOT NULL, last_attempt_ns INTEGER NOT NULL,"
      " last_success_ns INTEGER NOT NULL)");
}

std::vector<StoredWebhook> SqliteWebhookStore::load() {
  std::vector<StoredWebhook> out;
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt q(*db_, (std::string(kSelectWebhooks) + "webhooks ORDER BY created_ns").c_str());
  while (q.step()) {
    StoredWebhook w;
    auto& st = w.status;
    st.id = q.text(0);
    st.url = q.text(1);
    w.secret = q.text(2);
    st.createdNs = q.integer(3);
    st.deliveredThrough = q.integer(4);
    st.state = q.text(5);
    st.deliveries = q.integer(6);
    st.failures = q.integer(7);
    st.lastError = q.text(8);
    st.lastAttemptNs = q.integer(9);
    st.lastSuccessNs = q.integer(10);
    out.push_back(std::move(w));
  }
  return out;
}

void SqliteWebhookStore::insert(const StoredWebhook& w) {
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt ins(*db_,
                 "INSERT INTO webhooks(id, url, secret, created_ns, delivered_through, state, deliveries, "
                 "failures, last_error, last_attempt_ns, last_success_ns) "
                 "VALUES (?1, ?2, ?3, ?4, ?5, 'active', 0, 0, '', 0, 0)");
  ins.bind(1, w.status.id)
      .bind(2, w.status.url)
      .bind(3, w.secret)
      .bind(4, w.status.createdNs)
      .bind(5, w.status.deliveredThrough);
  ins.run();
}

bool SqliteWebhookStore::remove(const std::string& id) {
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt del(*db_, "DELETE FROM webhooks WHERE id = ?1");
  del.bind(1, id).run();
  return sqlite3_changes(db_->handle()) > 0;
}

void SqliteWebhookStore::update(const WebhookStatus& st) {
  std::lock_guard dbLock(db_->mutex());
  SqliteStmt up(*db_,
                "UPDATE webhooks SET delivered_through = ?2, state = ?3, deliveries = ?4, failures = ?5, "
                "last_error = ?6, last_attempt_ns = ?7, last_success_ns = ?8 WHERE id = ?1");
  up.bind(1, st.id)
      .bind(2, st.deliveredThrough)
      .bind(3, st.state)
      .bind(4, st.deliveries)
      .bind(5, st.failures)
      .bind(6, st.lastError)
      .bind(7, st.lastAttemptNs)
      .bind(8, st.lastSuccessNs);
  up.run();
}

// ---- PostgreSQL: shared by the adapter replicas on the database ----

namespace {

using pg_errors::failed;
using pg_errors::orThrow;

}  // namespace

PostgresWebhookStore::PostgresWebhookStore(const std::string& url) : url_(url), conn_(url) {
  if (auto ok = pg::checkUrl(url_); !ok) {
    throw failed(url_, ok.error());
  }
  orThrow(
      url_,
      conn_.exec("create the webhook table",
                 // One implicit transaction: the lock is held until the table's creation commits
                 // (a session lock released inside the transaction let a second replica's CREATE
                 // race the uncommitted catalog row: "duplicate key ... pg_type_typname_nsp_index").
                 "SELECT pg_advisory_xact_lock(8606010379466966901);"
                 "CREATE TABLE IF NOT EXISTS wms_webhooks("
                 " id TEXT PRIMARY KEY, url TEXT NOT NULL, secret TEXT NOT NULL, created_ns BIGINT NOT NULL,"
                 " delivered_through BIGINT NOT NULL, state TEXT NOT NULL, deliveries BIGINT NOT NULL,"
                 " failures BIGINT NOT NULL, last_error TEXT NOT NULL, last_attempt_ns BIGINT NOT NULL,"
                 " last_success_ns BIGINT NOT NULL, owner TEXT NOT NULL DEFAULT '',"
                 " owner_until_ns BIGINT NOT NULL DEFAULT 0)"));
}

std::vector<StoredWebhook> PostgresWebhookStore::load() {
  std::lock_guard lock(m_);
  const auto r = orThrow(url_, conn_.exec("read the webhooks", std::string(kSelectWebhooks) +
                                                                   "wms_webhooks ORDER BY created_ns, id"));
  std::vector<StoredWebhook> out;
  for (int i = 0; i < r.rows(); ++i) {
    StoredWebhook w;
    auto& st = w.status;
    st.id = r.text(i, 0);
    st.url = r.text(i, 1);
    w.secret = r.text(i, 2);
    st.createdNs = r.integer(i, 3);
    st.deliveredThrough = r.integer(i, 4);
    st.state = r.text(i, 5);
    st.deliveries = r.integer(i, 6);
    st.failures = r.integer(i, 7);
    st.lastError = r.text(i, 8);
    st.lastAttemptNs = r.integer(i, 9);
    st.lastSuccessNs = r.integer(i, 10);
    out.push_back(std::move(w));
  }
  return out;
}

void PostgresWebhookStore::insert(const StoredWebhook& w) {
  std::lock_guard lock(m_);
  orThrow(url_,
          conn_.exec(
              "store the webhook",
              "INSERT INTO wms_webhooks(id, url, secret, created_ns, delivered_through, state, deliveries, "
              "failures, last_error, last_attempt_ns, last_success_ns) "
              "VALUES ($1, $2, $3, $4, $5, 'active', 0, 0, '', 0, 0)",
              {w.status.id, w.status.url, w.secret, std::to_string(w.status.createdNs),
               std::to_string(w.status.deliveredThrough)}));
}

bool PostgresWebhookStore::remove(const std::string& id) {
  std::lock_guard lock(m_);
  return orThrow(url_, conn_.exec("remove the webhook", "DELETE FROM wms_webhooks WHERE id = $1", {id}))
             .affected() > 0;
}

void PostgresWebhookStore::update(const WebhookStatus& st) {
  std::lock_guard lock(m_);
  orThrow(url_,
          conn_.exec("store the webhook's cursor",
                     "UPDATE wms_webhooks SET delivered_through = GREATEST(delivered_through, $2::bigint), "
                     "state = $3, deliveries = $4, failures = $5, last_error = $6, last_attempt_ns = $7, "
                     "last_success_ns = $8 WHERE id = $1",
                     {st.id, std::to_string(st.deliveredThrough), st.state, std::to_string(st.deliveries),
                      std::to_string(st.failures), st.lastError, std::to_string(st.lastAttemptNs),
                      std::to_string(st.lastSuccessNs)}));
}

WebhookStore::Claim PostgresWebhookStore::claim(const std::string& id, const std::string& replica,
                                                std::int64_t nowNs, std::int64_t leaseNs) {
  std::lock_guard lock(m_);
  const auto r =
      orThrow(url_, conn_.exec("claim the webhook",
                               "UPDATE wms_webhooks SET owner = $2, owner_until_ns = $3::bigint + $4::bigint "
                               "WHERE id = $1 AND (owner = $2 OR owner_until_ns < $3::bigint) "
                               "RETURNING delivered_through",
                               {id, replica, std::to_string(nowNs), std::to_string(leaseNs)}));
  if (r.rows() == 0) {
    return {false, std::nullopt};
  }
  return {true, r.integer(0, 0)};
}

}  // namespace fleet::wms
