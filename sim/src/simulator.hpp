// The simulator's loop on DDS: the world stepped on the wall clock or in lockstep with its
// participants, sensor frames and ground truth out, commands in, the replay and summary written
// (docs/simulator.md).
#pragma once

#include <atomic>
#include <string>

#include "fleet/service/service_ops.hpp"
#include "fleet/sim/world.hpp"
#include "simulator_options.hpp"

namespace fleet::simulator {

/// Runs `world` as `o` says until its duration is over or `stop` is set; the process's exit code.
int runSimulation(sim::World& world, const Options& o, bool lockstep, service::ServiceOps& ops,
                  const std::atomic<bool>& stop);

/// Writes `text` to `path`; false (and nothing said) when it cannot.
bool writeText(const std::string& path, const std::string& text);

}  // namespace fleet::simulator
