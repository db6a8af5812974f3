#include "fleet/fleet/pg_connection.hpp"

#include <libpq-fe.h>

#include <cstdlib>
#include <regex>

#include "fleet/fleet/errors.hpp"

namespace fleet::pg {

Expected<void> checkUrl(const std::string& url) {
  char* err = nullptr;
  PQconninfoOption* opts = PQconninfoParse(url.c_str(), &err);
  if (opts == nullptr) {
    std::string why = err != nullptr ? err : "out of memory";
    PQfreemem(err);
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) {
      why.pop_back();
    }
    return unexpected(errc::kInvalid, "not a PostgreSQL connection URL: " + why);
  }
  // libpq checks ports only when it connects; a typo is the URL's fault, found here.
  std::string badPort;
  for (const PQconninfoOption* o = opts; o->keyword != nullptr; ++o) {
    if (std::string_view(o->keyword) == "port" && o->val != nullptr) {
      std::string_view ports(o->val);
      for (std::size_t start = 0; start <= ports.size();) {
        const std::size_t end = std::min(ports.find(',', start), ports.size());
        const auto p = ports.substr(start, end - start);
        if (!p.empty() && p.find_first_not_of("0123456789") != std::string_view::npos) {
          badPort = std::string(p);
        }
        start = end + 1;
      }
    }
  }
  PQconninfoFree(opts);
  if (!badPort.empty()) {
    return unexpected(errc::kInvalid,
                      "not a PostgreSQL connection URL: port '" + badPort + "' is not a number");
  }
  return {};
}

std::string redacted(const std::string& url) {
  // URI user:password@ and key=value password=...
  static const std::regex uri(R"(^(postgres(?:ql)?://[^:/@?]*):[^@/]*@)");
  static const std::regex kv(R"((password\s*=\s*)('[^']*'|\S+))");
  std::string out = std::regex_replace(url, uri, "$1:***@");
  out = std::regex_replace(out, kv, "$1***");
  static const std::regex query(R"(([?&]password=)[^&]*)");
  return std::regex_replace(out, query, "$1***");
}

Result::Result(pg_result* r) : r_(r, PQclear) {}
int Result::rows() const {
  return r_ ? PQntuples(r_.get()) : 0;
}
std::string Result::text(int row, int col) const {
  return std::string(PQgetvalue(r_.get(), row, col),
                     static_cast<std::size_t>(PQgetlength(r_.get(), row, col)));
}
std::int64_t Result::integer(int row, int col) const {
  return std::strtoll(PQgetvalue(r_.get(), row, col), nullptr, 10);
}
bool Result::isNull(int row, int col) const {
  return PQgetisnull(r_.get(), row, col) != 0;
}
std::int64_t Result::affected() const {
  const char* n = r_ ? PQcmdTuples(r_.get()) : "";
  return *n == '\0' ? 0 : std::strtoll(n, nullptr, 10);
}

Connection::~Connection() {
  close();
}

void Connection::close() {
  if (conn_ != nullptr) {
    PQfinish(conn_);
    conn_ = nullptr;
  }
}

bool Connection::connected() const {
  return conn_ != nullptr && PQstatus(conn_) == CONNECTION_OK;
}

Expected<void> Connection::ensure() {
  if (connected()) {
    return {};
  }
  if (inTx_) {
    return unexpected(errc::kStorage, "the connection to PostgreSQL broke inside a transaction");
  }
  close();
  conn_ = PQconnectdb(url_.c_str());
  if (conn_ == nullptr || PQstatus(conn_) != CONNECTION_OK) {
    std::string why = conn_ != nullptr ? PQerrorMessage(conn_) : "out of memory";
    close();
    while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) {
      why.pop_back();
    }
    for (auto& c : why) {
      c = c == '\n' || c == '\t' ? ' ' : c;  // one log line
    }
    return unexpected(errc::kStorage, "cannot connect to PostgreSQL at " + redacted(url_) + ": " + why);
  }
  // Server notices (CREATE TABLE IF NOT EXISTS "already exists, skipping") are not errors: kept
  // out of stderr.
  PQsetNoticeProcessor(
      conn_, [](void*, const char*) {}, nullptr);
  for (const auto& [name, sql] : statements_) {
    if (auto r = check(PQprepare(conn_, name.c_str(), sql.c_str(), 0, nullptr), "prepare " + name); !r) {
      close();
      return unexpected(r.error());
    }
  }
  return {};
}

Expected<Result> Connection::check(pg_result* r, std::string_view what) {
  const auto st = PQresultStatus(r);
  if (st == PGRES_COMMAND_OK || st == PGRES_TUPLES_OK) {
    lastState_.clear();
    return Result(r);
  }
  const char* state = r != nullptr ? PQresultErrorField(r, PG_DIAG_SQLSTATE) : nullptr;
  lastState_ = state != nullptr ? state : "";
  std::string why = r != nullptr ? PQresultErrorMessage(r) : "";
  if (why.empty() && conn_ != nullptr) {
    why = PQerrorMessage(conn_);
  }
  PQclear(r);
  while (!why.empty() && (why.back() == '\n' || why.back() == ' ')) {
    why.pop_back();
  }
  for (auto& c : why) {
    c = c == '\n' || c == '\t' ? ' ' : c;  // one log line
  }
  if (conn_ != nullptr && PQstatus(conn_) != CONNECTION_OK) {
    close();  // opened again by the next call outside a transaction
  }
  Error e{errc::kStorage, "postgresql: " + std::string(what) + ": " + why};
  if (inTx_ && !txError_) {
    txError_ = e;
  }
  return unexpected(std::move(e));
}

Expected<void> Connection::begin() {
  txError_.reset();
  auto r = exec("begin", "BEGIN");
  if (!r) {
    return unexpected(r.error());
  }
  inTx_ = true;
  return {};
}

Expected<void> Connection::commit() {
  if (txError_) {
    Error e = *txError_;
    rollback();
    return unexpected(std::move(e));
  }
  auto r = exec("commit", "COMMIT");
  inTx_ = false;
  txError_.reset();
  if (!r) {
    return unexpected(r.error());
  }
  return {};
}

void Connection::rollback() {
  if (connected()) {
    (void)exec("rollback", "ROLLBACK");
  }
  inTx_ = false;
  txError_.reset();
}

namespace {
struct Params {
  std::vector<const char*> values;
  explicit Params(const std::vector<Param>& ps) {
    values.reserve(ps.size());
    for (const auto& p : ps) {
      values.push_back(p ? p->c_str() : nullptr);
    }
  }
};
}  // namespace

Expected<Result> Connection::exec(std::string_view what, const std::string& sql,
                                  const std::vector<Param>& params) {
  if (auto ok = ensure(); !ok) {
    return unexpected(ok.error());
  }
  if (params.empty()) {
    return check(PQexec(conn_, sql.c_str()), what);
  }
  Params p(params);
  return check(PQexecParams(conn_, sql.c_str(), static_cast<int>(params.size()), nullptr, p.values.data(),
                            nullptr, nullptr, 0),
               what);
}

Expected<std::vector<Result>> Connection::runAll(std::string_view what, const std::string& name,
                                                 const std::vector<std::vector<Param>>& all) {
  std::vector<Result> out;
  out.reserve(all.size());
  // Chunks keep what is sent before reading bounded (a blocking connection that only writes while
  // the server's results fill the socket would wait for ever).
  constexpr std::size_t kChunk = 500;
  for (std::size_t from = 0; from < all.size(); from += kChunk) {
    if (auto ok = ensure(); !ok) {
      return unexpected(ok.error());
    }
    if (PQenterPipelineMode(conn_) != 1) {
      return unexpected(errc::kStorage, "postgresql: " + std::string(what) + ": cannot enter pipeline mode");
    }
    const std::size_t to = std::min(all.size(), from + kChunk);
    for (std::size_t i = from; i < to; ++i) {
      Params p(all[i]);
      if (PQsendQueryPrepared(conn_, name.c_str(), static_cast<int>(all[i].size()), p.values.data(), nullptr,
                              nullptr, 0) != 1) {
        break;
      }
    }
    PQpipelineSync(conn_);
    std::optional<Error> failed;
    for (;;) {
      PGresult* r = PQgetResult(conn_);
      if (r == nullptr) {
        if (PQstatus(conn_) != CONNECTION_OK) {
          if (!failed) {
            failed = Error{errc::kStorage, "postgresql: " + std::string(what) + ": " + PQerrorMessage(conn_)};
          }
          break;
        }
        continue;  // the end of one statement's results
      }
      const auto st = PQresultStatus(r);
      if (st == PGRES_PIPELINE_SYNC) {
        PQclear(r);
        break;
      }
      if (st == PGRES_PIPELINE_ABORTED) {
        PQclear(r);
        continue;  // after the first error: that one is reported
      }
      auto one = check(r, what);
      if (one) {
        out.push_back(std::move(*one));
      } else if (!failed) {
        failed = one.error();
      }
    }
    if (conn_ != nullptr) {
      PQexitPipelineMode(conn_);
      if (PQstatus(conn_) != CONNECTION_OK) {
        close();
      }
    }
    if (failed) {
      if (inTx_ && !txError_) {
        txError_ = failed;
      }
      return unexpected(std::move(*failed));
    }
    if (out.size() != to) {
      return unexpected(errc::kStorage, "postgresql: " + std::string(what) + ": results missing");
    }
  }
  return out;
}

Expected<Result> Connection::run(std::string_view what, const std::string& name,
                                 const std::vector<Param>& params) {
  if (auto ok = ensure(); !ok) {
    return unexpected(ok.error());
  }
  Params p(params);
  return check(PQexecPrepared(conn_, name.c_str(), static_cast<int>(params.size()), p.values.data(), nullptr,
                              nullptr, 0),
               what);
}

}  // namespace fleet::pg
