#pragma once

// A PostgreSQL server of the test's own (fleet::pgserver::PostgresServer: a fresh temporary
// directory, a Unix socket only, dies with the test), its data directory copied from a template
// made once per build tree by initdb (FLEET_BINARY_DIR/pg-template). Tests link fleet::pgserver.
//
// A server that cannot start leaves error() set: tests that need it FAIL with that message.

#include <filesystem>
#include <string>

#include "fleet/fleet/pg_connection.hpp"
#include "fleet/pgserver/postgres_server.hpp"

namespace fleet::test {

/// The initdb template of this build tree.
inline std::filesystem::path postgresTemplate() {
#ifdef FLEET_BINARY_DIR
  return std::filesystem::path(FLEET_BINARY_DIR) / "pg-template";
#else
  return std::filesystem::temp_directory_path() / "fleet-pg-template";
#endif
}

class PostgresServer : public pgserver::PostgresServer {
 public:
  /// `durable`: fsync and synchronous commit as in production (benchmarks); tests run without.
  explicit PostgresServer(bool durable = false) : pgserver::PostgresServer(options(durable)) {}
  /// A server with these options (the template is this build tree's unless one is given).
  explicit PostgresServer(Options o) : pgserver::PostgresServer(withTemplate(std::move(o))) {}

  /// The URL, optionally confined to `schema` (its tables are created there: each test gets a
  /// fresh schema, see freshUrl).
  [[nodiscard]] std::string url(const std::string& schema = {}) const {
    std::string u = pgserver::PostgresServer::url();
    if (!schema.empty()) {
      u += "&options=-csearch_path%3D" + schema;
    }
    return u;
  }
  /// A new empty schema and the URL confined to it.
  std::string freshUrl() {
    const std::string schema = "t" + std::to_string(++schemas_);
    pg::Connection c(url());
    auto r = c.exec("create schema", "CREATE SCHEMA " + schema);
    if (!r) {
      setupError_ = r.error().message;
    }
    return url(schema);
  }
  [[nodiscard]] bool ok() const { return pgserver::PostgresServer::ok() && setupError_.empty(); }
  [[nodiscard]] std::string error() const {
    return setupError_.empty() ? pgserver::PostgresServer::error() : setupError_;
  }
  /// Runs SQL as the superuser (for tests that set a database up as an older or newer binary would
  /// have left it). Empty on success, else the error.
  std::string sql(const std::string& schemaUrl, const std::string& statements) const {
    pg::Connection c(schemaUrl);
    auto r = c.exec("test setup", statements);
    return r ? std::string() : r.error().message;
  }

 private:
  static Options options(bool durable) {
    Options o;
    o.durable = durable;
    return withTemplate(std::move(o));
  }
  static Options withTemplate(Options o) {
    if (o.templateDir.empty()) {
      o.templateDir = postgresTemplate();
    }
    return o;
  }

  int schemas_ = 0;
  std::string setupError_;
};

}  // namespace fleet::test
