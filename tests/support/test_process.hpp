#pragma once

// A child process for multi-process tests: started with fork/exec, killed (SIGKILL) when the
// object goes out of scope so a failing test never leaves orphans.

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdlib>
#include <stdexcept>
#include <string>
#include <thread>
#include <utility>
#include <vector>

#include "fleet/core/dds_domain_lock.hpp"

namespace fleet::test {

class ChildProcess {
 public:
  ChildProcess(const std::string& exe, const std::vector<std::string>& args,
               const std::vector<std::pair<std::string, std::string>>& env = {}) {
    pid_ = fork();
    if (pid_ < 0) {
      throw std::runtime_error("fork failed");
    }
    if (pid_ == 0) {
      // Die with the parent, even when it is killed or crashes before its destructors run.
      prctl(PR_SET_PDEATHSIG, SIGKILL);
      for (const auto& [k, v] : env) {
        setenv(k.c_str(), v.c_str(), 1);
      }
      std::vector<char*> argv;
      argv.push_back(const_cast<char*>(exe.c_str()));
      for (const auto& a : args) {
        argv.push_back(const_cast<char*>(a.c_str()));
      }
      argv.push_back(nullptr);
      execv(exe.c_str(), argv.data());
      _exit(127);
    }
  }
  ChildProcess(const ChildProcess&) = delete;
  ChildProcess& operator=(const ChildProcess&) = delete;
  ~ChildProcess() { kill(SIGKILL); }

  [[nodiscard]] pid_t pid() const { return pid_; }

  void kill(int sig) {
    if (pid_ > 0 && !exited_) {
      ::kill(pid_, sig);
      if (sig == SIGKILL) {
        (void)wait(std::chrono::seconds(10));
      }
    }
  }

  /// Waits for exit; returns the exit status (128+signal when killed), or -1 on timeout.
  int wait(std::chrono::milliseconds timeout) {
    if (exited_) {
      return status_;
    }
    const auto end = std::chrono::steady_clock::now() + timeout;
    while (true) {
      int st = 0;
      const pid_t r = waitpid(pid_, &st, WNOHANG);
      if (r == pid_) {
        exited_ = true;
        status_ = WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
        return status_;
      }
      if (std::chrono::steady_clock::now() > end) {
        return -1;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  }

 private:
  pid_t pid_ = -1;
  bool exited_ = false;
  int status_ = -1;
};

/// A DDS domain id that no other test process on this machine holds, so parallel ctest runs (and
/// two checkouts testing at once) never hear each other: the first of 10..209, starting from one
/// derived from the pid, whose lock file this process can lock. The lock is held until exit.
inline int uniqueDomain() {
  static const int domain = lockFreeDdsDomain(10, 200, static_cast<int>(getpid() % 200));
  return domain;
}

/// A TCP port on 127.0.0.1 that no other test process takes and no outgoing connection is given:
/// each process owns the 40 ports 20000 + 40 * uniqueDomain() + k (all below the kernel's
/// ephemeral range, 32768 and up), and each call returns the next of them that binds now. A port
/// the kernel picks (bind to 0) can be handed to some client's connect() before the service under
/// test binds it, which failed CI once ("cannot listen on 127.0.0.1:34918").
inline int freePort() {
  static int next = 0;
  for (int tries = 0; tries < 40; ++tries) {
    const int port = 20000 + 40 * uniqueDomain() + (next++ % 40);
    const int fd = socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    const bool ok = fd >= 0 && bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0;
    if (fd >= 0) {
      close(fd);
    }
    if (ok) {
      return port;
    }
  }
  throw std::runtime_error("no free port in this test process's block");
}

}  // namespace fleet::test
