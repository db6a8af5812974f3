#pragma once

// `fleetctl loadtest --store postgresql`: a PostgreSQL server of the run's own (fleet::pgserver:
// in the run folder's postgres/, a Unix socket only, fsync on as in production) and two fleet
// managers on it, one active and one standing by. kill-manager kills the active one (found by its
// /readyz) and times the takeover: from the kill until a manager's /readyz answers 200 again (the
// standby's, or the killed one's when it was restarted sooner and won the expired lease).

#include <filesystem>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "store_contents.hpp"
#include "supervisor.hpp"

namespace fleet::pgserver {
class PostgresServer;
}

namespace fleet::ctl {

class StandbyManagers {
 public:
  /// The supervised names of the two managers (either may be the active one).
  static constexpr const char* kFirst = "fleet_manager";
  static constexpr const char* kSecond = "fleet_manager_2";

  /// Starts the server in runDir/postgres (the initdb template kept in binDir/pg-template).
  StandbyManagers(const std::filesystem::path& runDir, const std::string& binDir);
  StandbyManagers(const StandbyManagers&) = delete;
  StandbyManagers& operator=(const StandbyManagers&) = delete;
  ~StandbyManagers();

  [[nodiscard]] bool ok() const;
  /// Why the server did not start (with its log).
  [[nodiscard]] std::string error() const;
  /// The managers' store URL.
  [[nodiscard]] std::string url() const;

  /// The two managers: `manager` (the run's one manager) with --store url() and an ops port each.
  std::vector<ProcessSpec> specs(const ProcessSpec& manager, int opsPort, int standbyOpsPort);
  /// The manager whose /readyz answers 200 ("" when none does).
  [[nodiscard]] std::string active() const;
  /// SIGKILLs the active manager and times the takeover on a thread of its own.
  /// Returns the name killed, "" when no manager was active (nothing killed).
  std::string killActive(Supervisor& sup);
  /// Waits for a takeover being timed to end (it gives up 30 s after the kill).
  void settle();
  /// Stops both managers (SIGTERM, SIGKILL after `graceS`): the one standing by first, so that it
  /// does not take over from the active one as that one stops.
  void stop(Supervisor& sup, double graceS);

  /// {"backend": "postgresql", "takeovers": [...], "takeover_s": percentiles}.
  [[nodiscard]] nlohmann::json reportJson();
  /// One line for the run's summary ("" before any kill).
  [[nodiscard]] std::string summaryLine();
  /// The tasks and transitions in the database.
  [[nodiscard]] StoreContents read() const { return readPostgresStore(url()); }

 private:
  [[nodiscard]] int opsPortOf(const std::string& name) const;

  std::unique_ptr<pgserver::PostgresServer> server_;
  int ports_[2] = {0, 0};
  std::thread timer_;
  std::mutex mu_;
  nlohmann::json takeovers_ = nlohmann::json::array();
};

}  // namespace fleet::ctl
