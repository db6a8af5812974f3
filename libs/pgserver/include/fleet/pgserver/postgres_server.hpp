#pragma once

// A PostgreSQL server of a program's own, for tests and `fleetctl loadtest --store postgresql`: a
// data directory copied from an initdb template (made once per template path, under a lock), or
// for a streaming replica taken from its primary with `pg_basebackup -R`; listening only on a Unix
// socket in its directory (listen_addresses ''). The postmaster is this process's child, in a
// process group of its own, and dies with it (PR_SET_PDEATHSIG); it is stopped when the object
// goes out of scope. PostgreSQL refuses to run as root: as root, initdb, the server and the tools
// run as the `postgres` system user, which owns the directories. Binaries: Options::binDir, else
// FLEET_PG_BIN, else /usr/lib/postgresql/15/bin (scripts/setup installs postgresql-15).
//
// A server that cannot start leaves error() set, naming what failed (with the server's log).

#include <sys/types.h>

#include <filesystem>
#include <string>
#include <vector>

namespace fleet::pgserver {

class PostgresServer {
 public:
  struct Options {
    /// Where initdb's template is kept (made on first use; a build tree's "pg-template").
    std::filesystem::path templateDir;
    /// The server's folder (data/, server.log and the socket). Empty: a fresh temporary folder,
    /// removed with the object; else created if need be, and only its data/ is removed at the end.
    std::filesystem::path dir;
    std::string binDir;  ///< empty: FLEET_PG_BIN or /usr/lib/postgresql/15/bin
    /// fsync and full-page writes as in production; without, a crash of the machine may lose
    /// commits (a crash of the server does not).
    bool durable = false;
    /// synchronous_standby_names of a primary (e.g. "*"): a commit returns once a standby has the
    /// WAL. Empty: commits do not wait for standbys (and, not durable, not for the disk either).
    std::string synchronousStandbys;
    /// A streaming replica of this server (pg_basebackup -R over its socket), a hot standby.
    const PostgresServer* replicaOf = nullptr;
    int maxConnections = 40;
  };

  explicit PostgresServer(Options o);
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;
  ~PostgresServer();

  [[nodiscard]] bool ok() const { return error_.empty(); }
  [[nodiscard]] const std::string& error() const { return error_; }
  [[nodiscard]] std::string socketDir() const { return socketDir_.string(); }
  [[nodiscard]] std::filesystem::path dataDir() const { return dir_ / "data"; }
  [[nodiscard]] std::filesystem::path logFile() const { return dir_ / "server.log"; }
  /// The postmaster's pid (-1 when stopped).
  [[nodiscard]] pid_t pid() const { return pid_; }

  /// The URL of database "postgres" as user "fleet" (no password: trust on the socket).
  [[nodiscard]] std::string url() const;

  /// Starts the stopped server again on the same data directory and socket.
  void restart();
  /// Immediate shutdown (SIGQUIT: no checkpoint, as after a crash), then SIGKILL if need be.
  void stop();
  /// kill -9 of every process of the server at once (its process group), as a machine's death.
  void crash();
  /// Ends recovery on a replica (`pg_ctl promote`, waiting until it accepts writes). Empty on
  /// success, else the error.
  std::string promote();
  /// The server's log so far.
  [[nodiscard]] std::string log() const;

  /// The URL of database "postgres" as user "fleet" on whichever of `servers` accepts writes
  /// (libpq's multi-host form, target_session_attrs=read-write): what a fleet on a primary and its
  /// replicas is given.
  static std::string failoverUrl(const std::vector<const PostgresServer*>& servers);

 private:
  bool makeTemplate();
  bool copyData();
  void start();
  [[nodiscard]] std::string asPostgres(const std::string& cmd) const;

  Options o_;
  std::filesystem::path dir_;
  std::filesystem::path socketDir_;
  bool ownsDir_ = false;
  bool ownsSocketDir_ = false;
  bool asRoot_ = false;
  uid_t uid_ = 0;
  gid_t gid_ = 0;
  pid_t pid_ = -1;
  std::string error_;
};

}  // namespace fleet::pgserver
