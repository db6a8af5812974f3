#pragma once

// The event log's rows in PostgreSQL, shared by every WMS adapter given the same database (the
// fleet managers' one, say): so replicas behind one load balancer number events alike, and a
// client resumes on either. Each adapter logs what it hears; a transition heard by two (same task
// id and seq) is logged once (a unique index). Appends take one advisory lock in their transaction,
// so ids become visible in order and a reader that has seen id N never later finds a smaller one.

#include <memory>
#include <mutex>
#include <string>

#include "event_store.hpp"
#include "fleet/fleet/pg_connection.hpp"

namespace fleet::wms {

class PostgresEventStore : public EventStore {
 public:
  /// Connects and creates the tables when missing. Throws std::runtime_error naming the URL
  /// (without its password) and the server's message.
  explicit PostgresEventStore(const std::string& url);
  std::vector<LoggedEvent> append(const std::vector<msg::TaskEvent>& events, std::int64_t nowNs,
                                  std::int64_t known) override;
  [[nodiscard]] std::vector<LoggedEvent> after(std::int64_t after, std::size_t limit) const override;
  [[nodiscard]] std::int64_t lastId() const override;
  [[nodiscard]] std::int64_t prunedThrough() const override;
  std::int64_t prune(std::int64_t keep, std::int64_t beforeNs) override;
  [[nodiscard]] bool durable() const override { return true; }
  [[nodiscard]] bool shared() const override { return true; }

 private:
  std::string url_;
  mutable std::mutex m_;  // one connection, one user at a time
  mutable pg::Connection conn_;
};

/// Whether an `events.log` names a PostgreSQL database rather than a SQLite file.
bool isPostgresUrl(const std::string& location);

}  // namespace fleet::wms
