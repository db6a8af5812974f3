#include "fleet/pgserver/postgres_server.hpp"

#include <fcntl.h>
#include <grp.h>
#include <pwd.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <thread>

#include "fleet/fleet/pg_connection.hpp"

namespace fleet::pgserver {
namespace fs = std::filesystem;

namespace {

struct Outcome {
  int code = -1;
  std::string output;
};

Outcome runCommand(const std::string& cmd) {
  Outcome r;
  FILE* p = ::popen((cmd + " 2>&1").c_str(), "r");
  std::array<char, 512> buf{};
  while (p != nullptr && std::fgets(buf.data(), buf.size(), p) != nullptr) {
    r.output += buf.data();
  }
  const int status = p != nullptr ? ::pclose(p) : -1;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string shellQuoted(const fs::path& p) {
  return "'" + p.string() + "'";
}

/// A Unix socket's path must fit sockaddr_un (108 bytes with the final NUL).
constexpr std::size_t kMaxSocketPath = 100;

}  // namespace

PostgresServer::PostgresServer(Options o) : o_(std::move(o)) {
  if (o_.binDir.empty()) {
    const char* env = std::getenv("FLEET_PG_BIN");
    o_.binDir = env != nullptr ? env : "/usr/lib/postgresql/15/bin";
  }
  for (const char* tool : {"postgres", "initdb", "pg_ctl", "pg_basebackup"}) {
    if (!fs::exists(fs::path(o_.binDir) / tool)) {
      error_ = "PostgreSQL's " + std::string(tool) + " not found in " + o_.binDir +
               " (scripts/setup installs postgresql-15; FLEET_PG_BIN names another directory)";
      return;
    }
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
  std::error_code ec;
  if (o_.dir.empty()) {
    std::string tmpl = (fs::temp_directory_path() / "fleet-pg-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) {
      error_ = "cannot make a temporary folder for PostgreSQL in " + fs::temp_directory_path().string();
      return;
    }
    dir_ = tmpl;
    ownsDir_ = true;
  } else {
    dir_ = fs::absolute(o_.dir);
    fs::create_directories(dir_, ec);
    fs::remove_all(dir_ / "data", ec);  // a previous run's
  }
  socketDir_ = dir_;
  if ((dir_ / ".s.PGSQL.5432").string().size() > kMaxSocketPath) {
    std::string tmpl = (fs::temp_directory_path() / "fleet-pg-socket-XXXXXX").string();
    if (::mkdtemp(tmpl.data()) == nullptr) {
      error_ = "cannot make a temporary folder for PostgreSQL's socket";
      return;
    }
    socketDir_ = tmpl;
    ownsSocketDir_ = true;
  }
  for (const auto& d : {dir_, socketDir_}) {
    if (asRoot_ && ::chown(d.c_str(), uid_, gid_) != 0) {
      error_ = "chown of " + d.string() + " to postgres failed";
      return;
    }
  }
  if (o_.replicaOf != nullptr) {
    // The base backup over the primary's socket; -R writes standby.signal and primary_conninfo.
    if (auto r = runCommand(asPostgres(o_.binDir + "/pg_basebackup -D " + shellQuoted(dataDir()) + " -h " +
                                       shellQuoted(o_.replicaOf->socketDir()) +
                                       " -U fleet -R -X stream -c fast --no-sync"));
        r.code != 0) {
      error_ = "pg_basebackup from " + o_.replicaOf->socketDir() + " failed: " + r.output;
      return;
    }
  } else if (!makeTemplate() || !copyData()) {
    return;
  }
  start();
}

PostgresServer::~PostgresServer() {
  stop();
  std::error_code ec;
  if (ownsDir_) {
    fs::remove_all(dir_, ec);
  } else if (!dir_.empty()) {
    fs::remove_all(dataDir(), ec);
  }
  if (ownsSocketDir_) {
    fs::remove_all(socketDir_, ec);
  }
}

std::string PostgresServer::url() const {
  return "postgresql:///postgres?host=" + socketDir() + "&user=fleet";
}

std::string PostgresServer::failoverUrl(const std::vector<const PostgresServer*>& servers) {
  std::string hosts;
  for (const auto* s : servers) {
    hosts += (hosts.empty() ? "" : ",") + s->socketDir();
  }
  return "postgresql:///postgres?host=" + hosts + "&user=fleet&target_session_attrs=read-write";
}

std::string PostgresServer::asPostgres(const std::string& cmd) const {
  return asRoot_ ? "runuser -u postgres -- " + cmd : cmd;
}

bool PostgresServer::makeTemplate() {
  const auto& t = o_.templateDir;
  std::error_code ec;
  fs::create_directories(t.parent_path(), ec);
  const std::string lockPath = t.string() + ".lock";
  const int lock = ::open(lockPath.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock < 0 || ::flock(lock, LOCK_EX) != 0) {
    error_ = "cannot lock " + lockPath;
    if (lock >= 0) {
      ::close(lock);
    }
    return false;
  }
  bool made = true;
  if (!fs::exists(t / "PG_VERSION")) {
    // Made whole beside it and renamed into place: a half-made template is never used.
    const auto tmp = fs::path(t.string() + ".new");
    fs::remove_all(tmp, ec);
    fs::create_directories(tmp);
    if (asRoot_ && ::chown(tmp.c_str(), uid_, gid_) != 0) {
      error_ = "chown of " + tmp.string() + " to postgres failed";
      made = false;
    } else if (auto r = runCommand(
                   asPostgres(o_.binDir + "/initdb -D " + shellQuoted(tmp) +
                              " -U fleet -A trust -E UTF8 --locale=C --no-sync --no-instructions"));
               r.code != 0) {
      error_ = "initdb failed: " + r.output;
      made = false;
    } else {
      fs::rename(tmp, t, ec);
      if (ec) {
        error_ = "cannot move the PostgreSQL template into place: " + ec.message();
        made = false;
      }
    }
  }
  ::close(lock);
  return made;
}

bool PostgresServer::copyData() {
  if (auto r = runCommand("cp -a " + shellQuoted(o_.templateDir) + " " + shellQuoted(dataDir()));
      r.code != 0) {
    error_ = "copying the PostgreSQL template failed: " + r.output;
    return false;
  }
  return true;
}

void PostgresServer::start() {
  const std::string logPath = logFile().string();
  const std::string exe = o_.binDir + "/postgres";
  std::vector<std::string> args = {exe,
                                   "-D",
                                   dataDir().string(),
                                   "-c",
                                   "listen_addresses=",
                                   "-c",
                                   "unix_socket_directories=" + socketDir(),
                                   "-c",
                                   "max_connections=" + std::to_string(o_.maxConnections),
                                   "-c",
                                   "shared_buffers=16MB"};
  // On the command line, not in postgresql.conf: a replica's base backup must not copy them (a
  // promoted replica with synchronous_standby_names would wait for a standby it does not have).
  const bool replicated = o_.replicaOf != nullptr || !o_.synchronousStandbys.empty();
  if (!o_.synchronousStandbys.empty()) {
    args.insert(args.end(),
                {"-c", "synchronous_standby_names=" + o_.synchronousStandbys, "-c", "synchronous_commit=on"});
  }
  if (!o_.durable) {
    args.insert(args.end(), {"-c", "fsync=off"});
    if (o_.synchronousStandbys.empty()) {
      args.insert(args.end(), {"-c", "synchronous_commit=off"});
    }
    if (!replicated) {
      args.insert(args.end(), {"-c", "full_page_writes=off"});
    }
  }
  pid_ = ::fork();
  if (pid_ == 0) {
    ::setpgid(0, 0);  // crash() kills the whole server at once
    const int fd = ::open(logPath.c_str(), O_CREAT | O_WRONLY | O_APPEND, 0644);
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
    // After setuid, which clears it: the postmaster dies with its parent.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    std::vector<char*> argv;
    for (auto& a : args) {
      argv.push_back(a.data());
    }
    argv.push_back(nullptr);
    ::execv(exe.c_str(), argv.data());
    _exit(127);
  }
  if (pid_ > 0) {
    ::setpgid(pid_, pid_);  // also here: whichever runs first
  }
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(30);
  while (std::chrono::steady_clock::now() < deadline) {
    int status = 0;
    if (::waitpid(pid_, &status, WNOHANG) == pid_) {
      pid_ = -1;
      error_ = "the PostgreSQL server exited at start; its log:\n" + log();
      return;
    }
    pg::Connection c(url());
    if (c.ensure()) {
      return;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  error_ = "the PostgreSQL server did not accept connections within 30 s; its log:\n" + log();
  stop();
}

void PostgresServer::restart() {
  stop();
  error_.clear();
  start();
}

void PostgresServer::stop() {
  if (pid_ <= 0) {
    return;
  }
  ::kill(pid_, SIGQUIT);
  int status = 0;
  for (int i = 0; i < 200 && ::waitpid(pid_, &status, WNOHANG) == 0; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(25));
  }
  ::kill(-pid_, SIGKILL);
  ::kill(pid_, SIGKILL);
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

void PostgresServer::crash() {
  if (pid_ <= 0) {
    return;
  }
  ::kill(-pid_, SIGKILL);
  int status = 0;
  ::waitpid(pid_, &status, 0);
  pid_ = -1;
}

std::string PostgresServer::promote() {
  auto r = runCommand(asPostgres(o_.binDir + "/pg_ctl promote -w -t 30 -D " + shellQuoted(dataDir())));
  return r.code == 0 ? std::string() : "pg_ctl promote failed: " + r.output;
}

std::string PostgresServer::log() const {
  std::ifstream in(logFile());
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

}  // namespace fleet::pgserver
