#include "store_contents.hpp"

#include <sqlite3.h>

#include <algorithm>

#include "fleet/fleet/pg_connection.hpp"

namespace fleet::ctl {

StoreContents readSqliteStore(const std::filesystem::path& path) {
  StoreContents out;
  sqlite3* db = nullptr;
  if (sqlite3_open_v2(path.c_str(), &db, SQLITE_OPEN_READONLY, nullptr) != SQLITE_OK) {
    out.error = "cannot open " + path.string() + ": " + (db ? sqlite3_errmsg(db) : "out of memory");
    sqlite3_close(db);
    return out;
  }
  auto text = [](sqlite3_stmt* s, int c) {
    const auto* p = sqlite3_column_text(s, c);
    return p ? std::string(reinterpret_cast<const char*>(p)) : std::string();
  };
  sqlite3_stmt* s = nullptr;
  if (sqlite3_prepare_v2(db, "SELECT id, state FROM tasks", -1, &s, nullptr) == SQLITE_OK) {
    while (sqlite3_step(s) == SQLITE_ROW) {
      out.tasks.push_back({text(s, 0), text(s, 1)});
    }
  } else {
    out.error = sqlite3_errmsg(db);
  }
  sqlite3_finalize(s);
  if (sqlite3_prepare_v2(db, "SELECT task_id, to_state, stamp_ns FROM transitions ORDER BY seq", -1, &s,
                         nullptr) == SQLITE_OK) {
    while (sqlite3_step(s) == SQLITE_ROW) {
      out.transitions.push_back({text(s, 0), text(s, 1), sqlite3_column_int64(s, 2)});
    }
  } else {
    out.error = sqlite3_errmsg(db);
  }
  sqlite3_finalize(s);
  sqlite3_close(db);
  return out;
}

StoreContents readPostgresStore(const std::string& url) {
  StoreContents out;
  pg::Connection c(url);
  auto tasks = c.exec("read tasks", "SELECT id, state FROM tasks");
  auto transitions =
      c.exec("read transitions", "SELECT task_id, to_state, stamp_ns FROM transitions ORDER BY seq");
  if (!tasks || !transitions) {
    out.error = !tasks ? tasks.error().message : transitions.error().message;
    return out;
  }
  for (int i = 0; i < tasks->rows(); ++i) {
    out.tasks.push_back({tasks->text(i, 0), tasks->text(i, 1)});
  }
  for (int i = 0; i < transitions->rows(); ++i) {
    out.transitions.push_back({transitions->text(i, 0), transitions->text(i, 1), transitions->integer(i, 2)});
  }
  return out;
}

std::string copyPostgresToSqlite(const std::string& url, const std::filesystem::path& path) {
  pg::Connection c(url);
  auto tasks = c.exec("read tasks", "SELECT id, kind, body, state, robot, created_ns, updated_ns FROM tasks");
  if (!tasks) {
    return tasks.error().message;
  }
  auto transitions = c.exec(
      "read transitions",
      "SELECT seq, task_id, from_state, to_state, robot, reason, stamp_ns FROM transitions ORDER BY seq");
  if (!transitions) {
    return transitions.error().message;
  }
  std::error_code ec;
  std::filesystem::remove(path, ec);
  sqlite3* db = nullptr;
  if (sqlite3_open(path.c_str(), &db) != SQLITE_OK) {
    const std::string why = db ? sqlite3_errmsg(db) : "out of memory";
    sqlite3_close(db);
    return "cannot create " + path.string() + ": " + why;
  }
  std::string error;
  auto exec = [&](const char* sql) {
    if (error.empty() && sqlite3_exec(db, sql, nullptr, nullptr, nullptr) != SQLITE_OK) {
      error = sqlite3_errmsg(db);
    }
  };
  exec(
      "BEGIN; CREATE TABLE tasks(id TEXT PRIMARY KEY, kind TEXT, body TEXT, state TEXT, robot TEXT, "
      "created_ns INTEGER, updated_ns INTEGER); CREATE TABLE transitions(seq INTEGER PRIMARY KEY, task_id "
      "TEXT, from_state TEXT, to_state TEXT, robot TEXT, reason TEXT, stamp_ns INTEGER)");
  // Every column as text but the integers; a NULL (from_state of a new task) stays NULL.
  auto copy = [&](const char* sql, const pg::Result& rows, int columns, std::initializer_list<int> integers) {
    sqlite3_stmt* st = nullptr;
    if (!error.empty() || sqlite3_prepare_v2(db, sql, -1, &st, nullptr) != SQLITE_OK) {
      error = error.empty() ? sqlite3_errmsg(db) : error;
      return;
    }
    for (int r = 0; r < rows.rows() && error.empty(); ++r) {
      for (int col = 0; col < columns; ++col) {
        if (rows.isNull(r, col)) {
          sqlite3_bind_null(st, col + 1);
        } else if (std::find(integers.begin(), integers.end(), col) != integers.end()) {
          sqlite3_bind_int64(st, col + 1, rows.integer(r, col));
        } else {
          sqlite3_bind_text(st, col + 1, rows.text(r, col).c_str(), -1, SQLITE_TRANSIENT);
        }
      }
      if (sqlite3_step(st) != SQLITE_DONE) {
        error = sqlite3_errmsg(db);
      }
      sqlite3_reset(st);
    }
    sqlite3_finalize(st);
  };
  copy("INSERT INTO tasks VALUES (?, ?, ?, ?, ?, ?, ?)", *tasks, 7, {5, 6});
  copy("INSERT INTO transitions VALUES (?, ?, ?, ?, ?, ?, ?)", *transitions, 7, {0, 6});
  exec("COMMIT");
  sqlite3_close(db);
  return error.empty() ? std::string() : "copying the PostgreSQL store to " + path.string() + ": " + error;
}

}  // namespace fleet::ctl
