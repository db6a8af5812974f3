#pragma once

// A small SQLite handle for the adapter's durable state (the event log and the webhook
// subscriptions, event_log.hpp and webhook_store.hpp): one connection, used under its mutex,
// WAL with synchronous=NORMAL (a commit survives the process being killed; the last commits
// may be lost with the machine's power, as the manager's store states for its own choice).

#include <sqlite3.h>

#include <cstdint>
#include <mutex>
#include <optional>
#include <string>

namespace fleet::wms {

class SqliteDb {
 public:
  /// Opens (creating) `path`; ":memory:" or empty for a log that ends with the process. Throws
  /// std::runtime_error naming the file and SQLite's reason.
  explicit SqliteDb(const std::string& path);
  ~SqliteDb();
  SqliteDb(const SqliteDb&) = delete;
  SqliteDb& operator=(const SqliteDb&) = delete;

  /// Runs statements without results; throws std::runtime_error with SQLite's message.
  void exec(const char* sql);
  [[nodiscard]] sqlite3* handle() const { return db_; }
  [[nodiscard]] const std::string& path() const { return path_; }
  [[nodiscard]] bool durable() const { return durable_; }
  /// Held by whoever uses the connection.
  std::recursive_mutex& mutex() { return m_; }

 private:
  sqlite3* db_ = nullptr;
  std::string path_;
  bool durable_ = false;
  std::recursive_mutex m_;
};

/// A prepared statement: bind by position (1-based), step, read columns (0-based).
class SqliteStmt {
 public:
  SqliteStmt(SqliteDb& db, const char* sql);
  ~SqliteStmt();
  SqliteStmt(const SqliteStmt&) = delete;
  SqliteStmt& operator=(const SqliteStmt&) = delete;
  /// Ready to run again (bindings cleared).
  void reset();
  SqliteStmt& bind(int i, std::int64_t v);
  SqliteStmt& bind(int i, const std::string& v);
  SqliteStmt& bindNull(int i);
  /// True while there is a row; throws on an error.
  bool step();
  /// Steps to the end (an INSERT, UPDATE or DELETE).
  void run();
  [[nodiscard]] std::int64_t integer(int col) const;
  [[nodiscard]] std::string text(int col) const;
  [[nodiscard]] bool isNull(int col) const;

 private:
  SqliteDb& db_;
  sqlite3_stmt* s_ = nullptr;
};

}  // namespace fleet::wms
