#pragma once

// A PostgreSQL server of the test's own: a data directory copied from a template made once per
// build tree by initdb (FLEET_BINARY_DIR/pg-template), in a fresh temporary directory, listening
// only on a Unix socket in that directory (listen_addresses ''). The postmaster is this process's
// child and dies with it (PR_SET_PDEATHSIG); it is stopped and the directory removed when the
// object goes out of scope. PostgreSQL refuses to run as root: as root, initdb and the server run
// as the `postgres` system user, which owns the directories. Binaries: FLEET_PG_BIN, else
// /usr/lib/postgresql/15/bin (scripts/setup installs postgresql-15).
//
// A server that cannot start leaves error() set: tests that need it FAIL with that message.

#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>

#include "fleet/fleet/pg_connection.hpp"
#include "run_command.hpp"

namespace fleet::test {

class PostgresServer {
 public:
  /// `durable`: fsync and synchronous commit as in production (benchmarks); tests run without.
  explicit PostgresServer(bool durable = false) : durable_(durable) {
    const char* env = std::getenv("FLEET_PG_BIN");
    bin_ = env != nullptr ? env : "/usr/lib/postgresql/15/bin";
    if (!std::filesystem::exists(bin_ + "/postgres") || !std::filesystem::exists(bin_ + "/initdb")) {
      error_ = "PostgreSQL server binaries not found in " + bin_ +
               " (scripts/setup installs postgresql-15; FLEET_PG_BIN names another directory)";
      return;
    }
    if (::geteuid() == 0) {
      const passwd* pw = ::getpwnam("postgres");
      if (pw == nullptr) {
        error_ = "running as root, and there is no 'postgres' user to run PostgreSQL as";
        return;
      }
      uid_ = pw->pw_uid;
      gid_ = pw->pw_gid;
      asRoot_ = true;
    }
    std::string tmpl = (std::filesystem::temp_directory_path() / "fleet-pg-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) {
      error_ = "mkdtemp failed";
      return;
    }
    dir_ = tmpl;
    if (!makeTemplate()) {
      return;
    }
    const auto data = dir_ / "data";
    if (auto r = runCommand("cp -a '" + templateDir().string() + "' '" + data.string() + "'"); r.code != 0) {
      error_ = "copying the PostgreSQL template failed: " + r.output;
      return;
    }
    if (asRoot_ && ::chown(dir_.c_str(), uid_, gid_) != 0) {
      error_ = "chown of " + dir_.string() + " to postgres failed";
      return;
    }
    start(durable);
  }
  PostgresServer(const PostgresServer&) = delete;
  PostgresServer& operator=(const PostgresServer&) = delete;
  ~PostgresServer() {
    stop();
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }

  [[nodiscard]] bool ok() const { return error_.empty(); }
  [[nodiscard]] const std::string& error() const { return error_; }
  [[nodiscard]] std::string socketDir() const { return dir_.string(); }
  [[nodiscard]] pid_t pid() const { return pid_; }

  /// The URL of database "postgres" as user "fleet", optionally confined to `schema` (its tables
  /// are created there: each test gets a fresh schema, see freshUrl).
  [[nodiscard]] std::string url(const std::string& schema = {}) const {
    std::string u = "postgresql:///postgres?host=" + dir_.string() + "&user=fleet";
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
      error_ = r.error().message;
    }
    return url(schema);
  }
  /// Runs SQL as the superuser (for tests that set a database up as an older or newer binary would
  /// have left it). Empty on success, else the error.
  std::string sql(const std::string& schemaUrl, const std::string& statements) const {
    pg::Connection c(schemaUrl);
    auto r = c.exec("test setup", statements);
    return r ? std::string() : r.error().message;
  }

  /// Starts the stopped server again on the same data directory and socket.
  void restart() {
    stop();
    start(durable_);
  }

  /// Immediate shutdown (as a crash would: no checkpoint).
  void stop() {
    if (pid_ > 0) {
      ::kill(pid_, SIGQUIT);
      int status = 0;
      for (int i = 0; i < 200 && ::waitpid(pid_, &status, WNOHANG) == 0; ++i) {
        std::this_thread::sleep_for(std::chrono::milliseconds(25));
      }
      ::kill(pid_, SIGKILL);
      ::waitpid(pid_, &status, 0);
      pid_ = -1;
    }
  }

 private:
  static std::filesystem::path templateDir() {
#ifdef FLEET_BINARY_DIR
    return std::filesystem::path(FLEET_BINARY_DIR) / "pg-template";
#else
    return std::filesystem::temp_directory_path() / "fleet-pg-template";
#endif
  }

  std::string asPostgres(const std::string& cmd) const {
    return asRoot_ ? "runuser -u postgres -- " + cmd : cmd;
  }

  /// initdb once per build tree, under a lock (tests run in parallel), renamed into place whole.
  bool makeTemplate() {
    const auto t = templateDir();
    const std::string lockPath = t.string() + ".lock";
    const int lock = ::open(lockPath.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
    if (lock < 0 || ::flock(lock, LOCK_EX) != 0) {
      error_ = "cannot lock " + lockPath;
      return false;
    }
    bool made = true;
    if (!std::filesystem::exists(t / "PG_VERSION")) {
      const auto tmp = std::filesystem::path(t.string() + ".new");
      std::error_code ec;
      std::filesystem::remove_all(tmp, ec);
      std::filesystem::create_directories(tmp);
      if (asRoot_ && ::chown(tmp.c_str(), uid_, gid_) != 0) {
        error_ = "chown of " + tmp.string() + " to postgres failed";
        made = false;
      } else if (auto r = runCommand(
                     asPostgres(bin_ + "/initdb -D '" + tmp.string() +
                                "' -U fleet -A trust -E UTF8 --locale=C --no-sync --no-instructions"));
                 r.code != 0) {
        error_ = "initdb failed: " + r.output;
        made = false;
      } else {
        std::filesystem::rename(tmp, t, ec);
        if (ec) {
          error_ = "cannot move the PostgreSQL template into place: " + ec.message();
          made = false;
        }
      }
    }
    ::close(lock);
    return made;
  }

  void start(bool durable) {
    const std::string log = (dir_ / "server.log").string();
    const std::string data = (dir_ / "data").string();
    const std::string exe = bin_ + "/postgres";
    std::vector<std::string> args = {exe,
                                     "-D",
                                     data,
                                     "-c",
                                     "listen_addresses=",
                                     "-c",
                                     "unix_socket_directories=" + dir_.string(),
                                     "-c",
                                     "max_connections=40",
                                     "-c",
                                     "shared_buffers=16MB"};
    if (!durable) {
      for (const char* o : {"fsync=off", "synchronous_commit=off", "full_page_writes=off"}) {
        args.push_back("-c");
        args.push_back(o);
      }
    }
    pid_ = ::fork();
    if (pid_ == 0) {
      const int fd = ::open(log.c_str(), O_CREAT | O_WRONLY | O_TRUNC, 0644);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      if (asRoot_) {
        if (::fchown(fd, uid_, gid_) != 0 || ::setgroups(0, nullptr) != 0 || ::setgid(gid_) != 0 ||
            ::setuid(uid_) != 0) {
          _exit(126);
        }
      }
      // After setuid, which clears it: the postmaster dies with the test.
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      std::vector<char*> argv;
      for (auto& a : args) {
        argv.push_back(a.data());
      }
      argv.push_back(nullptr);
      ::execv(exe.c_str(), argv.data());
      _exit(127);
    }
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
    while (std::chrono::steady_clock::now() < deadline) {
      int status = 0;
      if (::waitpid(pid_, &status, WNOHANG) == pid_) {
        pid_ = -1;
        error_ = "the PostgreSQL server exited at start; its log:\n" + readLog();
        return;
      }
      pg::Connection c(url());
      if (c.ensure()) {
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(50));
    }
    error_ = "the PostgreSQL server did not accept connections within 30 s; its log:\n" + readLog();
    stop();
  }

  std::string readLog() const {
    std::ifstream in(dir_ / "server.log");
    std::stringstream ss;
    ss << in.rdbuf();
    return ss.str();
  }

  bool durable_ = false;
  std::string bin_;
  std::filesystem::path dir_;
  bool asRoot_ = false;
  uid_t uid_ = 0;
  gid_t gid_ = 0;
  pid_t pid_ = -1;
  int schemas_ = 0;
  std::string error_;
};

}  // namespace fleet::test
