#pragma once

// The event log's rows in a SQLite file of the adapter's own (WAL, synchronous=NORMAL: an event
// logged survives the adapter being killed), or in memory. The file may also hold the webhook
// subscriptions (webhooks.hpp), never another program's tables.

#include <memory>

#include "event_store.hpp"
#include "sqlite_db.hpp"

namespace fleet::wms {

class SqliteEventStore : public EventStore {
 public:
  /// Creates or migrates the table. Throws std::runtime_error for a file of another program.
  explicit SqliteEventStore(std::shared_ptr<SqliteDb> db);
  std::vector<LoggedEvent> append(const std::vector<msg::TaskEvent>& events, std::int64_t nowNs,
                                  std::int64_t known) override;
  [[nodiscard]] std::vector<LoggedEvent> after(std::int64_t after, std::size_t limit) const override;
  [[nodiscard]] std::int64_t lastId() const override;
  [[nodiscard]] std::int64_t prunedThrough() const override;
  std::int64_t prune(std::int64_t keep, std::int64_t beforeNs) override;
  [[nodiscard]] bool durable() const override { return db_->durable(); }

 private:
  std::shared_ptr<SqliteDb> db_;
  std::unique_ptr<SqliteStmt> seen_;  // prepared once: an append is the hot path
  std::unique_ptr<SqliteStmt> insert_;
};

}  // namespace fleet::wms
