// fleet-sim: the headless warehouse simulator on DDS. See docs/simulator.md for the protocol.

#include <spdlog/spdlog.h>

#include "simulator.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/core/percentiles.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/sim/localization_error.hpp"
#include "fleet/sim/lockstep.hpp"
#include "fleet/sim/replay.hpp"
#include "fleet/sim/vda5050_fleet.hpp"
#include "fleet/sim/world.hpp"
#include "fleet/transport/dds.hpp"
#include "fleet/validation/sample_checks.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

std::atomic<bool> gStop{false};
void onSignal(int) {
  gStop = true;
}

}  // namespace

using namespace fleet::simulator;

int main(int argc, char** argv) {
  Options o;
  try {
    if (!parseArgs(argc, argv, o)) {
      std::cerr << kUsage;
      return 2;
    }
    logging::setup("fleet-sim", o.logLevel, o.logFormat);
  } catch (const std::exception& e) {
    std::cerr << "fleet-sim: " << e.what() << "\n" << kUsage;
    return 2;
  }
  if (!o.makeViewerFrom.empty()) {
    auto lines = sim::readReplayLines(o.makeViewerFrom);
    if (!lines || o.html.empty()) {
      std::cerr << "fleet-sim: " << (lines ? "--viewer needs --html OUT" : lines.error().message) << "\n";
      return 1;
    }
    return writeText(o.html, sim::viewerHtml(*lines)) ? 0 : 1;
  }
  std::optional<sim::Scenario> sc;
  try {
    sc = sim::loadScenario(o.scenario);
  } catch (const ConfigError& e) {
    std::cerr << "fleet-sim: scenario refused, " << e.what() << "\n";
    return 2;
  }
  if (o.validateOnly) {
    std::cout << "scenario '" << sc->name << "' is valid: " << sc->robots.size() << " robots\n";
    return 0;
  }
  if (o.seed) {
    sc->seed = *o.seed;
  }
  if (o.duration) {
    sc->durationS = *o.duration;
  }
  for (const auto& out : o.outages) {
    if (std::none_of(sc->robots.begin(), sc->robots.end(),
                     [&](const auto& r) { return r.id == out.robot; })) {
      std::cerr << "fleet-sim: --sensor-outage: the scenario has no robot '" << out.robot << "'\n";
      return 2;
    }
  }
  const bool lockstep = o.clock.value_or(sc->clock) == "lockstep";
  std::signal(SIGINT, onSignal);
  std::signal(SIGTERM, onSignal);
  try {
    service::ServiceOps ops("fleet_sim");
    if (!ops.start(o.ops)) {
      return 2;
    }
    sim::World world(std::move(*sc));
    return runSimulation(world, o, lockstep, ops, gStop);
  } catch (const std::exception& e) {
    spdlog::critical("fleet-sim failed: {}", e.what());
    return 1;
  }
}
