#pragma once

// One libpq connection and its results, for the PostgreSQL task store and the fleet manager's
// lease: text parameters, errors as Expected with the server's message.

#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"

struct pg_conn;
struct pg_result;

namespace fleet::pg {

/// A parameter: text, or SQL NULL.
using Param = std::optional<std::string>;

/// Checks that `url` is a libpq connection URI or key=value string (error "invalid" naming what
/// libpq found wrong). Connects nowhere.
Expected<void> checkUrl(const std::string& url);
/// `url` with any password replaced by "***", for logs.
std::string redacted(const std::string& url);

class Result {
 public:
  Result() = default;
  explicit Result(pg_result* r);
  [[nodiscard]] int rows() const;
  [[nodiscard]] std::string text(int row, int col) const;
  [[nodiscard]] std::int64_t integer(int row, int col) const;
  [[nodiscard]] bool isNull(int row, int col) const;
  /// Rows an INSERT, UPDATE or DELETE touched.
  [[nodiscard]] std::int64_t affected() const;

 private:
  std::shared_ptr<pg_result> r_;
};

class Connection {
 public:
  explicit Connection(std::string url) : url_(std::move(url)) {}
  ~Connection();
  Connection(const Connection&) = delete;
  Connection& operator=(const Connection&) = delete;

  /// Connects when not connected (or the connection broke); prepares `statements` on each new
  /// connection. Error "storage" with libpq's message.
  Expected<void> ensure();
  /// Closes the connection (the server ends its session and releases what the session held).
  void close();
  [[nodiscard]] bool connected() const;
  /// Statements prepared on every new connection, by name.
  void addStatement(std::string name, std::string sql) {
    statements_.push_back({std::move(name), std::move(sql)});
  }

  /// Runs one statement (several, separated by ';', when `params` is empty). Error "storage"
  /// naming `what` and the server's message.
  Expected<Result> exec(std::string_view what, const std::string& sql, const std::vector<Param>& params = {});
  /// Runs a statement given to addStatement.
  Expected<Result> run(std::string_view what, const std::string& name, const std::vector<Param>& params);
  /// A transaction: while it is open a broken connection is not opened again (the statements
  /// after the break would run outside it), and a failed statement makes commit() roll back and
  /// fail with that statement's error (PostgreSQL aborts the transaction at the first error).
  Expected<void> begin();
  Expected<void> commit();
  void rollback();

  /// Runs a statement given to addStatement once per parameter list, all sent before the first
  /// result is read (libpq's pipeline mode): one round trip for the lot. The results in order, or
  /// the first error.
  Expected<std::vector<Result>> runAll(std::string_view what, const std::string& name,
                                       const std::vector<std::vector<Param>>& all);

  /// SQLSTATE of the latest failed call ("" when none or unknown).
  [[nodiscard]] const std::string& lastState() const { return lastState_; }

 private:
  Expected<Result> check(pg_result* r, std::string_view what);

  std::string url_;
  pg_conn* conn_ = nullptr;
  std::vector<std::pair<std::string, std::string>> statements_;
  std::string lastState_;
  bool inTx_ = false;
  std::optional<Error> txError_;
};

}  // namespace fleet::pg
