#pragma once

// Starts and stops the fleet's processes. Every child runs in its own process group (so a signal
// reaches whatever it spawned, and the terminal's Ctrl-C reaches only the supervisor, which then
// stops the children in order) and has PR_SET_PDEATHSIG = SIGKILL (so a crashed supervisor leaves
// no orphans). Output goes to a log file per process.

#include <sys/types.h>

#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace fleet::ctl {

struct ProcessSpec {
  std::string name;
  std::string exe;
  std::vector<std::string> args;
  std::vector<std::pair<std::string, std::string>> env;
  std::string log;  // file, appended to (a restarted process continues the same log)
};

class Supervisor {
 public:
  Supervisor() = default;
  Supervisor(const Supervisor&) = delete;
  Supervisor& operator=(const Supervisor&) = delete;
  ~Supervisor() { stopAll(0.0); }

  /// Starts (or restarts) the process called spec.name. Returns false when fork/exec failed.
  bool start(const ProcessSpec& spec);
  /// Restarts a process by name with its last spec.
  bool restart(const std::string& name);
  /// Sends a signal to the process group of `name` (no-op when it is not running).
  void signal(const std::string& name, int sig);
  /// SIGKILL and reap, for faults: the process counts as stopped on purpose.
  void killHard(const std::string& name);
  [[nodiscard]] bool running(const std::string& name) const;
  /// Reaps ended children; returns the names and exit statuses (128+signal) of those that ended
  /// without being stopped on purpose.
  std::vector<std::pair<std::string, int>> reapUnexpected();
  /// Waits up to `graceS` for `name` to exit on its own; true when it did.
  bool waitExit(const std::string& name, double graceS);
  /// SIGTERM to every group (in reverse start order), SIGKILL after `graceS`, reap all; but the
  /// process called `keep`, when one is named.
  void stopAll(double graceS, const std::string& keep = "");
  /// Stops one process the same way.
  void stop(const std::string& name, double graceS);

 private:
  struct Child {
    ProcessSpec spec;
    pid_t pid = -1;
    bool expectedExit = false;
    int status = 0;
  };
  std::map<std::string, Child> children_;
  std::vector<std::string> order_;
};

}  // namespace fleet::ctl
