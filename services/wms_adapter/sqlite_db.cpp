#include "sqlite_db.hpp"

#include <stdexcept>

namespace fleet::wms {

SqliteDb::SqliteDb(const std::string& path) : path_(path.empty() ? ":memory:" : path) {
  durable_ = path_ != ":memory:";
  const int flags = SQLITE_OPEN_READWRITE | SQLITE_OPEN_CREATE | SQLITE_OPEN_FULLMUTEX;
  if (sqlite3_open_v2(path_.c_str(), &db_, flags, nullptr) != SQLITE_OK) {
    const std::string why = db_ != nullptr ? sqlite3_errmsg(db_) : "out of memory";
    sqlite3_close(db_);
    db_ = nullptr;
    throw std::runtime_error("cannot open \"" + path_ + "\": " + why);
  }
  sqlite3_busy_timeout(db_, 5000);
  try {
    exec(durable_ ? "PRAGMA journal_mode=WAL; PRAGMA synchronous=NORMAL;" : "PRAGMA synchronous=OFF;");
  } catch (...) {
    sqlite3_close(db_);
    db_ = nullptr;
    throw;
  }
}

SqliteDb::~SqliteDb() {
  sqlite3_close(db_);
}

void SqliteDb::exec(const char* sql) {
  char* err = nullptr;
  if (sqlite3_exec(db_, sql, nullptr, nullptr, &err) != SQLITE_OK) {
    const std::string why = err != nullptr ? err : "unknown error";
    sqlite3_free(err);
    throw std::runtime_error("\"" + path_ + "\": " + why);
  }
}

SqliteStmt::SqliteStmt(SqliteDb& db, const char* sql) : db_(db) {
  if (sqlite3_prepare_v2(db.handle(), sql, -1, &s_, nullptr) != SQLITE_OK) {
    throw std::runtime_error("\"" + db.path() + "\": " + sqlite3_errmsg(db.handle()));
  }
}

SqliteStmt::~SqliteStmt() {
  sqlite3_finalize(s_);
}

void SqliteStmt::reset() {
  sqlite3_reset(s_);
  sqlite3_clear_bindings(s_);
}

SqliteStmt& SqliteStmt::bindNull(int i) {
  sqlite3_bind_null(s_, i);
  return *this;
}

SqliteStmt& SqliteStmt::bind(int i, std::int64_t v) {
  sqlite3_bind_int64(s_, i, v);
  return *this;
}

SqliteStmt& SqliteStmt::bind(int i, const std::string& v) {
  sqlite3_bind_text(s_, i, v.data(), static_cast<int>(v.size()), SQLITE_TRANSIENT);
  return *this;
}

bool SqliteStmt::step() {
  const int rc = sqlite3_step(s_);
  if (rc == SQLITE_ROW) {
    return true;
  }
  if (rc == SQLITE_DONE) {
    return false;
  }
  throw std::runtime_error("\"" + db_.path() + "\": " + sqlite3_errmsg(db_.handle()));
}

void SqliteStmt::run() {
  while (step()) {
  }
}

std::int64_t SqliteStmt::integer(int col) const {
  return sqlite3_column_int64(s_, col);
}

std::string SqliteStmt::text(int col) const {
  const auto* p = sqlite3_column_text(s_, col);
  return p != nullptr ? std::string(reinterpret_cast<const char*>(p),
                                    static_cast<std::size_t>(sqlite3_column_bytes(s_, col)))
                      : std::string();
}

bool SqliteStmt::isNull(int col) const {
  return sqlite3_column_type(s_, col) == SQLITE_NULL;
}

}  // namespace fleet::wms
