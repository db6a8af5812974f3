#pragma once

// The load test's fourth stage: the faults it injects, each at its simulated time. Process faults
// act through FaultActions (the Supervisor in a run, a recorder in tests): kill-agent,
// kill-manager and kill-traffic SIGKILL a process and restart it after the fault's down time (wall
// seconds; with two managers kill-manager kills the active one), stall SIGSTOPs a robot's agent
// process and SIGCONTs it. close shuts an area through the WMS API an operator would use, and
// hide-landmarks (which the simulator carries out itself) is only logged; both last simulated
// seconds. Every step goes to the fault log.

#include <chrono>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fault_plan.hpp"

namespace fleet::ctl {

class FaultActions {
 public:
  virtual ~FaultActions() = default;
  virtual void signal(const std::string& process, int sig) = 0;
  virtual void kill(const std::string& process) = 0;
  virtual void restart(const std::string& process) = 0;
  /// With standby managers: kills the active one; its name, "" when none was active.
  virtual std::string killActiveManager() = 0;
  /// PUT/DELETE of /v1/traffic/closures/NAME; a line for the log (status and body, or why not).
  virtual std::string putClosure(const std::string& path, const nlohmann::json& body) = 0;
  virtual std::string deleteClosure(const std::string& path) = 0;
};

class FaultInjector {
 public:
  using Clock = std::chrono::steady_clock;
  using Say = std::function<void(const std::string&)>;

  /// `agentOfRobot`: the process each robot runs in (stall). `standbyManagers`: kill-manager kills
  /// whichever manager is active.
  FaultInjector(std::vector<Fault> faults, std::map<std::string, std::string> agentOfRobot,
                bool standbyManagers, FaultActions& actions, Say say);

  /// Starts and ends what is due at simulated time `simS` and wall time `now`.
  void apply(double simS, Clock::time_point now);
  /// End of run: stalled processes go on, killed managers and traffic managers come back (so the
  /// store's final state is on disk). Returns how many processes were restarted.
  int endAll(double simS);

  [[nodiscard]] const nlohmann::json& log() const { return log_; }

 private:
  void note(double simS, const std::string& what);
  [[nodiscard]] std::string agentFor(const Fault& f) const;
  void applyLandmarks(std::size_t i, double simS);
  void applyClosure(std::size_t i, double simS);
  void applyProcess(std::size_t i, double simS, Clock::time_point now);

  std::vector<Fault> faults_;
  std::map<std::string, std::string> agentOfRobot_;
  bool standby_;
  FaultActions& act_;
  Say say_;
  std::vector<bool> started_, ended_;
  std::vector<Clock::time_point> endAt_;
  std::vector<std::string> target_;  // the process a kill fault killed (restarted D s later)
  nlohmann::json log_ = nlohmann::json::array();
};

}  // namespace fleet::ctl
