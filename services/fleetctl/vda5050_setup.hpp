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

/// Writes the files under `out` and returns the two processes to start (broker first).
Expected<Vda5050Run> prepareVda5050(const std::filesystem::path& out, const std::vector<std::string>& robots,
                                    const std::string& map_id, int port, const std::string& bridge_exe,
                                    const std::vector<std::pair<std::string, std::string>>& env,
                                    bool sim_clock);

}  // namespace fleet::ctl
