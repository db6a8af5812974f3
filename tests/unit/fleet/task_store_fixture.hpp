#pragma once

// The fixture of the TaskStore suite every backend passes (TaskStoreTest, parameterised by
// backend; instantiated as Backends/TaskStoreTest in task_store_test.cpp): SQLite in a temporary
// file, PostgreSQL in a fresh schema on a server the suite starts itself
// (tests/support/postgres_server.hpp). In a named namespace: its tests live in several files.

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <memory>
#include <string>

#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/pg_connection.hpp"
#include "fleet/fleet/postgres_task_store.hpp"
#include "fleet/fleet/sqlite_task_store.hpp"
#include "postgres_server.hpp"
#include "temp_dir.hpp"

namespace fleet::store_test {

using S = TaskState;

inline Task transport(std::string id, std::int32_t priority = 0) {
  Task t;
  t.id = std::move(id);
  t.kind = TaskKind::Transport;
  t.pickup = "P-1";
  t.dropoff = "D-1";
  t.priority = priority;
  return t;
}

// Not `"t" + std::to_string(i)`: GCC 12 reports a false -Wrestrict on it.
inline std::string numbered(std::string prefix, int i) {
  prefix += std::to_string(i);
  return prefix;
}

enum class Backend { Sqlite, Postgres };

/// One store location per test; open() opens it again (a restart of the manager).
class TaskStoreTest : public ::testing::TestWithParam<Backend> {
 public:
  /// One server for the suite, started by the first PostgreSQL test.
  static test::PostgresServer& server() {
    if (!server_) {
      server_ = std::make_unique<test::PostgresServer>();
    }
    return *server_;
  }
  static void TearDownTestSuite() { server_.reset(); }

 protected:
  void SetUp() override {
    if (GetParam() == Backend::Postgres) {
      auto& s = server();
      ASSERT_TRUE(s.ok()) << "the PostgreSQL test server did not start: " << s.error();
      location_ = s.freshUrl();
      ASSERT_TRUE(s.ok()) << s.error();
    } else {
      location_ = dir_.file("tasks.db");
    }
  }

  Expected<std::unique_ptr<TaskStore>> tryOpen() {
    if (GetParam() == Backend::Postgres) {
      auto s = PostgresTaskStore::open({location_});
      if (!s) {
        return unexpected(s.error());
      }
      return std::unique_ptr<TaskStore>(std::move(*s));
    }
    auto s = SqliteTaskStore::open({location_});
    if (!s) {
      return unexpected(s.error());
    }
    return std::unique_ptr<TaskStore>(std::move(*s));
  }
  std::unique_ptr<TaskStore> open() {
    auto s = tryOpen();
    EXPECT_TRUE(s) << s.error().message;
    return s ? std::move(s).value() : nullptr;
  }
  /// The schema version recorded in the store's database.
  std::int64_t schemaVersion() {
    if (GetParam() == Backend::Postgres) {
      pg::Connection c(location_);
      auto r = c.exec("read", "SELECT version FROM fleet_schema");
      return r && r->rows() == 1 ? r->integer(0, 0) : -1;
    }
    sqlite3* db = nullptr;
    sqlite3_open(location_.c_str(), &db);
    sqlite3_stmt* st = nullptr;
    sqlite3_prepare_v2(db, "PRAGMA user_version", -1, &st, nullptr);
    const std::int64_t v = sqlite3_step(st) == SQLITE_ROW ? sqlite3_column_int64(st, 0) : -1;
    sqlite3_finalize(st);
    sqlite3_close(db);
    return v;
  }
  /// Records `version` as a newer binary would have.
  void setSchemaVersion(int version) {
    if (GetParam() == Backend::Postgres) {
      EXPECT_EQ(server().sql(location_, "UPDATE fleet_schema SET version = " + std::to_string(version)), "");
      return;
    }
    sqlite3* db = nullptr;
    sqlite3_open(location_.c_str(), &db);
    EXPECT_EQ(sqlite3_exec(db, ("PRAGMA user_version = " + std::to_string(version)).c_str(), nullptr, nullptr,
                           nullptr),
              SQLITE_OK);
    sqlite3_close(db);
  }

  test::TempDir dir_;
  std::string location_;

 private:
  static inline std::unique_ptr<test::PostgresServer> server_;
};

}  // namespace fleet::store_test
