#include "simulator_options.hpp"

#include <cstdlib>
#include <iostream>
#include <stdexcept>

#include "fleet/core/config.hpp"
#include "fleet/service/command_line.hpp"

namespace fleet::simulator {
namespace {

/// ROBOT@T+D, T and D in simulated seconds.
SensorOutage parseOutage(const std::string& text) {
  const auto at = text.find('@');
  const auto plus = text.find('+', at == std::string::npos ? 0 : at);
  SensorOutage o;
  std::size_t usedT = 0;
  std::size_t usedD = 0;
  try {
    if (at == 0 || at == std::string::npos || plus == std::string::npos) {
      throw std::invalid_argument("shape");
    }
    o.robot = text.substr(0, at);
    const std::string t = text.substr(at + 1, plus - at - 1);
    const std::string d = text.substr(plus + 1);
    o.fromS = std::stod(t, &usedT);
    o.toS = o.fromS + std::stod(d, &usedD);
    if (usedT != t.size() || usedD != d.size() || !(o.fromS >= 0.0) || !(o.toS > o.fromS)) {
      throw std::invalid_argument("values");
    }
  } catch (const std::exception&) {
    throw std::invalid_argument(
        "--sensor-outage: expected ROBOT@T+D (T >= 0 and D > 0 simulated seconds), got '" + text + "'");
  }
  return o;
}

/// T+D in simulated seconds: no landmark bearing in any SensorFrame during [T, T+D).
std::pair<double, double> parseHidden(const std::string& text) {
  const auto plus = text.find('+');
  try {
    std::size_t usedT = 0;
    std::size_t usedD = 0;
    if (plus == std::string::npos) {
      throw std::invalid_argument("shape");
    }
    const std::string t = text.substr(0, plus);
    const std::string d = text.substr(plus + 1);
    const double from = std::stod(t, &usedT);
    const double len = std::stod(d, &usedD);
    if (usedT != t.size() || usedD != d.size() || !(from >= 0.0) || !(len > 0.0) ||
        !std::isfinite(from + len)) {
      throw std::invalid_argument("values");
    }
    return {from, from + len};
  } catch (const std::exception&) {
    throw std::invalid_argument("--hide-landmarks: expected T+D (T >= 0 and D > 0 simulated seconds), got '" +
                                text + "'");
  }
}

}  // namespace

const char* const kUsage =
    "usage: fleet-sim --scenario FILE [--clock wall|lockstep] [--seed N] [--duration S]\n"
    "                 [--participants N] [--start-timeout-ms MS] [--step-timeout-ms MS]\n"
    "                 [--max-speed F] [--sensor-outage ROBOT@T+D ...] [--hide-landmarks T+D ...]\n"
    "                 [--localization OUT.json]\n"
    "                 [--replay OUT.jsonl.gz] [--summary OUT.json] [--html OUT.html] [--no-scan]\n"
    "                 [--vda5050 VEHICLES.json] [--validate] [--log-level LEVEL] [--log-format text|json]\n"
    "                 [--metrics-port PORT] [--metrics-host ADDR]\n"
    "       (environment, the options win: FLEET_METRICS_PORT, FLEET_METRICS_HOST,\n"
    "        FLEET_SIM_PARTICIPANTS, FLEET_SIM_VDA5050, FLEET_SIM_MAX_SPEED)\n"
    "       fleet-sim --version\n"
    "       fleet-sim --viewer REPLAY.jsonl.gz --html OUT.html\n";

bool parseArgs(int argc, char** argv, Options& o) {
  // As the other services read them (CLI11 envname): the options below win.
  // A bad value names its variable (std::stoi alone says only "stoi").
  auto number = [](const char* name, auto parse) -> std::optional<decltype(parse(std::string()))> {
    const char* v = std::getenv(name);
    if (v == nullptr || *v == '\0') {
      return std::nullopt;
    }
    try {
      return parse(std::string(v));
    } catch (const std::exception&) {
      throw std::invalid_argument(std::string(name) + "=" + v + " is not a number");
    }
  };
  if (const auto port = number("FLEET_METRICS_PORT", [](const std::string& t) { return std::stoi(t); })) {
    o.ops.port = *port;
  }
  if (const char* host = std::getenv("FLEET_METRICS_HOST")) {
    o.ops.host = host;
  }
  // What a deployment overlay sets without rewriting the command (deploy/compose.vda5050.yaml;
  // compose implementations differ in how they merge an overlay's command list).
  if (const auto n = number("FLEET_SIM_PARTICIPANTS", [](const std::string& t) { return std::stoi(t); })) {
    o.participants = *n;
  }
  if (const char* v = std::getenv("FLEET_SIM_VDA5050"); v != nullptr && *v != '\0') {
    o.vda5050 = v;
  }
  if (const auto m = number("FLEET_SIM_MAX_SPEED", [](const std::string& t) { return std::stod(t); })) {
    o.maxSpeed = *m;
    if (!(o.maxSpeed >= 0.0)) {
      throw std::invalid_argument("FLEET_SIM_MAX_SPEED must be >= 0 (simulated s per wall s; 0 = no cap)");
    }
  }
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    auto next = [&]() -> std::string {
      if (i + 1 >= argc) {
        throw std::invalid_argument(a + " needs a value");
      }
      return argv[++i];
    };
    if (a == "--scenario") {
      o.scenario = next();
    } else if (a == "--clock") {
      o.clock = next();
      if (*o.clock != "wall" && *o.clock != "lockstep") {
        throw std::invalid_argument("--clock must be wall or lockstep");
      }
    } else if (a == "--seed") {
      o.seed = std::stoull(next());
    } else if (a == "--duration") {
      o.duration = std::stod(next());
    } else if (a == "--participants") {
      o.participants = std::stoi(next());
    } else if (a == "--start-timeout-ms") {
      o.startTimeoutMs = std::stoi(next());
    } else if (a == "--step-timeout-ms") {
      o.stepTimeoutMs = std::stoi(next());
    } else if (a == "--max-speed") {
      o.maxSpeed = std::stod(next());
      if (!(o.maxSpeed >= 0.0)) {
        throw std::invalid_argument("--max-speed must be >= 0 (simulated s per wall s; 0 = no cap)");
      }
    } else if (a == "--sensor-outage") {
      o.outages.push_back(parseOutage(next()));
    } else if (a == "--hide-landmarks") {
      o.hiddenLandmarks.push_back(parseHidden(next()));
    } else if (a == "--localization") {
      o.localization = next();
    } else if (a == "--replay") {
      o.replay = next();
    } else if (a == "--summary") {
      o.summary = next();
    } else if (a == "--html") {
      o.html = next();
    } else if (a == "--log-level") {
      o.logLevel = next();
    } else if (a == "--vda5050") {
      o.vda5050 = next();
    } else if (a == "--log-format") {
      o.logFormat = next();
    } else if (a == "--metrics-port") {
      o.ops.port = std::stoi(next());
    } else if (a == "--metrics-host") {
      o.ops.host = next();
    } else if (a == "--version") {
      std::cout << "fleet-sim " << fleet::service::version() << "\n";
      std::exit(0);
    } else if (a == "--no-scan") {
      o.noScan = true;
    } else if (a == "--validate") {
      o.validateOnly = true;
    } else if (a == "--viewer") {
      o.makeViewerFrom = next();
    } else if (a == "--help" || a == "-h") {
      std::cout << kUsage;
      std::exit(0);
    } else {
      throw std::invalid_argument("unknown option " + a);
    }
  }
  return !o.scenario.empty() || !o.makeViewerFrom.empty();
}

}  // namespace fleet::simulator
