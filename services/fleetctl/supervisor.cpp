#include "supervisor.hpp"

#include <fcntl.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <thread>

namespace fleet::ctl {
namespace {

int decode(int st) {
  return WIFEXITED(st) ? WEXITSTATUS(st) : 128 + WTERMSIG(st);
}

}  // namespace

bool Supervisor::start(const ProcessSpec& spec) {
  auto& c = children_[spec.name];
  if (c.pid > 0) {
    return true;
  }
  if (std::find(order_.begin(), order_.end(), spec.name) == order_.end()) {
    order_.push_back(spec.name);
  }
  c.spec = spec;
  c.expectedExit = false;
  const pid_t parent = getpid();
  const pid_t pid = fork();
  if (pid < 0) {
    return false;
  }
  if (pid == 0) {
    setpgid(0, 0);
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (getppid() != parent) {  // the supervisor died between fork and prctl
      _exit(127);
    }
    // Children start with default signal dispositions and an empty mask.
    sigset_t none;
    sigemptyset(&none);
    sigprocmask(SIG_SETMASK, &none, nullptr);
    ::signal(SIGINT, SIG_DFL);
    ::signal(SIGTERM, SIG_DFL);
    if (!spec.log.empty()) {
      const int fd = open(spec.log.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0644);
      if (fd >= 0) {
        dup2(fd, 1);
        dup2(fd, 2);
      }
    }
    const int devnull = open("/dev/null", O_RDONLY);
    if (devnull >= 0) {
      dup2(devnull, 0);
    }
    for (const auto& [k, v] : spec.env) {
      setenv(k.c_str(), v.c_str(), 1);
    }
    std::vector<char*> argv;
    argv.push_back(const_cast<char*>(spec.exe.c_str()));
    for (const auto& a : spec.args) {
      argv.push_back(const_cast<char*>(a.c_str()));
    }
    argv.push_back(nullptr);
    execv(spec.exe.c_str(), argv.data());
    _exit(127);
  }
  setpgid(pid, pid);  // also here: whichever of parent and child runs first
  c.pid = pid;
  return true;
}

bool Supervisor::restart(const std::string& name) {
  auto it = children_.find(name);
  if (it == children_.end()) {
    return false;
  }
  if (it->second.pid > 0) {
    return true;
  }
  return start(it->second.spec);
}

void Supervisor::signal(const std::string& name, int sig) {
  auto it = children_.find(name);
  if (it != children_.end() && it->second.pid > 0) {
    ::kill(-it->second.pid, sig);
  }
}

void Supervisor::killHard(const std::string& name) {
  auto it = children_.find(name);
  if (it == children_.end() || it->second.pid <= 0) {
    return;
  }
  it->second.expectedExit = true;
  ::kill(-it->second.pid, SIGKILL);
  int st = 0;
  waitpid(it->second.pid, &st, 0);
  it->second.status = decode(st);
  it->second.pid = -1;
}

bool Supervisor::running(const std::string& name) const {
  auto it = children_.find(name);
  return it != children_.end() && it->second.pid > 0;
}

std::vector<std::pair<std::string, int>> Supervisor::reapUnexpected() {
  std::vector<std::pair<std::string, int>> out;
  for (auto& [name, c] : children_) {
    if (c.pid <= 0) {
      continue;
    }
    int st = 0;
    const pid_t pid = c.pid;
    if (waitpid(pid, &st, WNOHANG) == pid) {
      c.status = decode(st);
      c.pid = -1;
      ::kill(-pid, SIGKILL);  // whatever it left in its group
      if (!c.expectedExit) {
        out.emplace_back(name, c.status);
      }
    }
  }
  return out;
}

bool Supervisor::waitExit(const std::string& name, double graceS) {
  auto it = children_.find(name);
  if (it == children_.end() || it->second.pid <= 0) {
    return true;
  }
  auto& c = it->second;
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(graceS);
  while (true) {
    int st = 0;
    if (waitpid(c.pid, &st, WNOHANG) == c.pid) {
      c.status = decode(st);
      c.pid = -1;
      return true;
    }
    if (std::chrono::steady_clock::now() >= end) {
      return false;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

void Supervisor::stop(const std::string& name, double graceS) {
  auto it = children_.find(name);
  if (it == children_.end() || it->second.pid <= 0) {
    return;
  }
  it->second.expectedExit = true;
  const pid_t pid = it->second.pid;
  ::kill(-pid, SIGCONT);  // a stalled process must be able to handle SIGTERM
  ::kill(-pid, SIGTERM);
  if (!waitExit(name, graceS)) {
    ::kill(-pid, SIGKILL);
    waitExit(name, 10.0);
  }
  ::kill(-pid, SIGKILL);  // anything left in the group
}

void Supervisor::stopAll(double graceS, const std::string& keep) {
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    auto c = children_.find(*it);
    if (c != children_.end() && c->second.pid > 0 && *it != keep) {
      c->second.expectedExit = true;
      ::kill(-c->second.pid, SIGCONT);
      ::kill(-c->second.pid, SIGTERM);
    }
  }
  for (auto it = order_.rbegin(); it != order_.rend(); ++it) {
    if (*it != keep) {
      stop(*it, graceS);
    }
  }
}

}  // namespace fleet::ctl
