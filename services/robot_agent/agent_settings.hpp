#pragma once

// How the agents of one robot_agent process run: the local planner and its parameters, from the
// command line and the --config file (docs/operator-guide.md, robot agent).

#include <string>
#include <vector>

#include "agent.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/config.hpp"

namespace fleet::agent {

struct Settings {
  // Keys of the --config file (and command-line options, except the parameter blocks).
  std::string localPlanner = "dwa";
  avoidance::DwaParams dwa = agentDwaDefaults();
  avoidance::RiskSteppingParams riskStepping;
  avoidance::SafetyParams safety;
  bool lineUpdates = true;  // localization.lines: laser lines matched to the site's walls
  ProgressParams progress;  // "progress": one notion of stalled for every local planner

  // Command line only.
  std::vector<std::string> only;  // robots to host (empty: every robot of the world)
  unsigned threads = 0;           // 0: hardware concurrency
  double sensorTimeoutS = 0.5;
  double returnHomeS = 5.0;
  bool useRisk = true;
  std::string poseFile;  // empty: none (pose_store.hpp)
};

/// The options of `Settings` that were given on the command line: they win over the file.
struct SetOnCommandLine {
  bool localPlanner = false;
};

/// Reads the --config file's keys into `s`, leaving what the command line set. Every problem is
/// recorded in `cfg` (call cfg.finish() after), among them a local planner that is none of
/// libs/avoidance's and not "follow", wherever it was named.
void readSettings(Config& cfg, Settings& s, SetOnCommandLine cli = {});

}  // namespace fleet::agent
