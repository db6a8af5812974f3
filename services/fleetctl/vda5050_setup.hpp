#pragma once

// What `fleetctl loadtest --vda5050 N` adds to a run: a Mosquitto broker of the run's own (free
// loopback port, one generated password per vehicle, the ACL confining each to its subtree), the
// vehicles' file for fleet-sim (--vda5050) and the bridge's configuration.

#include <filesystem>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "supervisor.hpp"

namespace fleet::ctl {

struct Vda5050Run {
  ProcessSpec broker;
  ProcessSpec bridge;
  std::filesystem::path vehicles_file;  // fleet-sim --vda5050
};

/// Where the VDA 5050 files of a fleet are written and how its services will see them.
struct Vda5050Files {
  std::filesystem::path out;      ///< written here
  std::filesystem::path seen_at;  ///< the same directory as the broker and bridge read it; empty: out
  std::vector<std::string> robots;
  std::string map_id;
  std::string broker_host = "127.0.0.1";   ///< as the vehicles and the bridge reach the broker
  std::string bind_address = "127.0.0.1";  ///< the broker's listener
  int port = 0;
  bool sim_clock = true;    ///< the bridge a lockstep participant on simulated time
  bool log_to_file = true;  ///< the broker logs to out/mosquitto.log (else stderr)
};

/// Writes mosquitto.conf, mosquitto.passwd (hashed by mosquitto_passwd), mosquitto.acl, the
/// vehicles' file for fleet-sim (vda5050_vehicles.json) and the bridge's (vda5050_bridge.json),
/// one generated password per vehicle and one for the master control.
Expected<void> writeVda5050Files(const Vda5050Files& files);

/// Writes the files under `out` and returns the two processes to start (broker first).
Expected<Vda5050Run> prepareVda5050(const std::filesystem::path& out, const std::vector<std::string>& robots,
                                    const std::string& map_id, int port, const std::string& bridge_exe,
                                    const std::vector<std::pair<std::string, std::string>>& env,
                                    bool sim_clock);

}  // namespace fleet::ctl
