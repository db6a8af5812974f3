// fleet-sim's command line: what the simulator is asked to run and how (docs/simulator.md).
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "fleet/service/service_ops.hpp"

namespace fleet::simulator {

/// A robot whose SensorFrames are not published during [fromS, toS) of simulated time (the robot
/// itself is still simulated and still obeys its commands): a sensor or driver outage to test with.
struct SensorOutage {
  std::string robot;
  double fromS = 0.0;
  double toS = 0.0;
};

struct Options {
  std::string scenario;
  std::vector<SensorOutage> outages;
  std::vector<std::pair<double, double>> hiddenLandmarks;  // [from, to) simulated s
  std::string localization;                                // error log file; empty: none
  std::optional<std::string> clock;
  std::optional<std::uint64_t> seed;
  std::optional<double> duration;
  int participants = 0;
  int startTimeoutMs = 10000;
  int stepTimeoutMs = 1000;
  double maxSpeed = 0.0;  // lockstep: at most this many simulated seconds per wall second (0: no cap)
  std::string replay;
  std::string summary;
  std::string html;
  std::string logLevel = "info";
  std::string logFormat = "text";
  fleet::service::OpsSettings ops;
  bool noScan = false;
  bool validateOnly = false;
  std::string makeViewerFrom;  // convert an existing replay to HTML and exit
  std::string vda5050;         // config of the robots that are VDA 5050 vehicles; empty: none
};

/// The usage text.
extern const char* const kUsage;

/// Reads the command line (and the environment variables it names) into `o`; false: print the
/// usage. Throws std::invalid_argument naming a bad value.
bool parseArgs(int argc, char** argv, Options& o);

}  // namespace fleet::simulator
