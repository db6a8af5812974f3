#include "fleet_launch.hpp"

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <nlohmann/json.hpp>
#include <random>

#include "fleet/core/dds_domain_lock.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/transport/dds.hpp"
#include "run_files.hpp"
#include "standby_managers.hpp"
#include "vda5050_setup.hpp"

namespace fleet::ctl {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;
using Env = std::vector<std::pair<std::string, std::string>>;

/// The loopback Cyclone configuration of deploy/cyclonedds-local.xml, plus Cyclone's own packet
/// dropper (Internal/Test/XmitLossiness, per mille of outgoing packets) for the drop-dds fault.
std::string cycloneConfig(double drop) {
  return transport::loopbackConfig(false, static_cast<int>(std::lround(drop * 1000.0))) + "\n";
}

/// The DDS Security identity each process joins as (scripts/dds-security).
std::string identityOf(const std::string& process) {
  if (process.rfind("agent-", 0) == 0) {
    return process;  // made for the run with its robots (makeIdentities)
  }
  static const std::map<std::string, std::string> kIdentity = {{"fleet_manager", "fleet-manager"},
                                                               {"fleet_manager_2", "fleet-manager"},
                                                               {"vda5050_bridge", "vda5050-bridge"},
                                                               {"wms_adapter", "wms-adapter"},
                                                               {"risk_map", "risk-map"},
                                                               {"traffic_manager", "traffic-manager"},
                                                               {"fleet-sim", "simulator"}};
  const auto it = kIdentity.find(process);
  return it == kIdentity.end() ? process : it->second;
}

std::string joined(const std::vector<std::string>& ids) {
  std::string list;
  for (const auto& r : ids) {
    list += (list.empty() ? "" : ",") + r;
  }
  return list;
}

struct Builder {
  const LoadtestOptions& o;
  const RunScenario& run;
  const fs::path& out;
  FleetPlan& plan;
  Env env;

  [[nodiscard]] std::string bin(const std::string& rel) const { return (fs::path(o.binDir) / rel).string(); }
  [[nodiscard]] std::string abs(const std::string& file) const { return fs::absolute(out / file).string(); }

  void writeConfigs() {
    std::error_code ec;
    plan.db = out / "fleet.db";
    fs::remove(plan.db, ec);
    fs::remove(out / "fleet.db-wal", ec);
    fs::remove(out / "fleet.db-shm", ec);
    fs::remove(out / "traffic_manager_summary.json", ec);  // not a previous run's
    json manager{{"stations", fs::absolute(run.file).string()},
                 {"db", fs::absolute(plan.db).string()},
                 {"clock", "sim"},
                 {"lease_s", 3.0},
                 {"station_capacity", o.stationCapacity == "queue" ? json(o.stationCapacity)
                                                                   : json(std::stoi(o.stationCapacity))},
                 {"station_load", o.stationLoad},
                 {"travel_cost", o.travelCost},
                 {"metrics_file", abs("manager_metrics.json")}};
    if (o.guidance >= 0.0) {
      manager["roadmap"] = json{{"guidance", o.guidance}};
    }
    writeTextFile(out / "manager.json", manager.dump(1));
    // 0.1 m cells up to ~1.2 M cells, coarser beyond (the fusion cost grows with the cell count);
    // the site gives the grid's origin and extent (a ROS map's origin need not be 0, 0).
    const double area = run.widthM * run.heightM;
    const double res = area / 0.01 <= 1.2e6 ? 0.1 : (area / 0.04 <= 1.2e6 ? 0.2 : 0.25);
    writeTextFile(out / "risk_map.json", json{{"clock", "sim"},
                                              {"lockstep", !o.wallClock},
                                              {"rate_hz", 2},
                                              {"site", run.siteFile},
                                              {"grid", {{"resolution", res}}}}
                                             .dump(1));
    json tm{{"site", run.siteFile}, {"clock", "sim"}, {"lockstep", !o.wallClock}, {"seed", o.seed}};
    if (o.letPass >= 0) {
      tm["let_pass"] = o.letPass;
    }
    if (!o.core.empty()) {
      tm["core"] = o.core;
    }
    if (o.yieldAfterS >= 0.0) {
      tm["yield_after_s"] = o.yieldAfterS;
    }
    if (o.guidance >= 0.0) {
      tm["roadmap"] = json{{"guidance", o.guidance}};
    }
    tm["summary_file"] = abs("traffic_manager_summary.json");
    writeTextFile(out / "traffic_manager.json", tm.dump(1));
  }

  void services(StandbyManagers* standby) {
    const std::string scn = fs::absolute(run.file).string();
    plan.manager = {"fleet_manager",
                    bin("services/fleet_manager/fleet_manager"),
                    {"--config", abs("manager.json"), "--log-level", "warn"},
                    env,
                    plan.logOf("fleet_manager")};
    plan.specs = {plan.manager,
                  {"wms_adapter",
                   bin("services/wms_adapter/wms_adapter"),
                   {"--stations", scn, "--port", std::to_string(plan.port), "--log-level", "warn"},
                   env,
                   plan.logOf("wms_adapter")},
                  {"risk_map",
                   bin("services/risk_map/risk_map"),
                   // At info: its one start-up line names the site and the grid laid over it.
                   {"--config", abs("risk_map.json"), "--id", "risk_map", "--log-level", "info"},
                   env,
                   plan.logOf("risk_map")}};
    if (standby != nullptr) {
      auto two = standby->specs(plan.manager, freePort(), freePort());
      plan.specs.front() = two[0];
      plan.specs.insert(plan.specs.begin() + 1, two[1]);
    }
    plan.specs.push_back(
        {"traffic_manager",
         bin("services/traffic_manager/traffic_manager"),
         {"--config", abs("traffic_manager.json"), "--id", "traffic_manager", "--log-level", "info"},
         env,
         plan.logOf("traffic_manager")});
  }

  /// VDA 5050 vehicles: the last N robots, with a broker and the bridge of their own.
  Expected<std::string> vda5050() {
    if (o.vda5050 <= 0) {
      return std::string();
    }
    const auto& robots = run.robots;
    if (o.vda5050 > static_cast<int>(robots.size())) {
      return unexpected("vda5050", "--vda5050 " + std::to_string(o.vda5050) + " needs at most " +
                                       std::to_string(robots.size()) + " robots");
    }
    if (!o.wallClock && (o.maxSpeed <= 0.0 || o.maxSpeed > 10.0)) {
      // MQTT runs on the wall clock: at 100x a millisecond in the broker is a tenth of a simulated
      // second, and the vehicles wait for their orders (docs/operator-guide.md#pod).
      plan.warnings.push_back(
          "warning: --max-speed " +
          (o.maxSpeed <= 0.0 ? std::string("0 (no cap)") : std::to_string(o.maxSpeed)) +
          " with VDA 5050 vehicles: MQTT runs on the wall clock, so above 10x their orders arrive late in "
          "simulated time (stops at base ends, rejected updates); 4 (the default) or 10 keep it small");
    }
    const std::vector<std::string> ids(robots.end() - o.vda5050, robots.end());
    plan.vdaRobots.insert(ids.begin(), ids.end());
    auto site = fleet::loadSiteFile(run.siteFile);
    auto vda = prepareVda5050(out, ids, site ? site->name : std::string("site"), freePort(),
                              bin("services/vda5050_bridge/vda5050_bridge"), env, !o.wallClock);
    if (!vda) {
      return unexpected(vda.error());
    }
    plan.specs.insert(plan.specs.begin(), vda->broker);
    plan.specs.push_back(vda->bridge);
    plan.robotsOfProcess["vda5050_bridge"].assign(plan.vdaRobots.begin(), plan.vdaRobots.end());
    return vda->vehicles_file.string();
  }

  ProcessSpec agentSpec(const std::string& name, const std::vector<std::string>& ids) {
    plan.robotsOfProcess[name] = ids;
    std::error_code ec;
    fs::remove(out / (name + "_metrics.json"), ec);  // not a previous run's
    fs::remove(out / (name + "_poses.json"), ec);
    std::vector<std::string> args = {
        "--scenario", fs::absolute(run.file).string(), "--clock", o.wallClock ? "wall" : "lockstep",
        "--metrics", abs(name + "_metrics.json"), "--id", name, "--robots", joined(ids), "--local-planner",
        o.localPlanner, "--return-home", std::to_string(o.returnHomeS),
        // A restarted agent (a fault, the supervisor) resumes where its robots are.
        "--pose-file", abs(name + "_poses.json"), "--log-level", "warn"};
    if (!o.agentConfig.empty()) {
      args.emplace_back("--config");
      args.push_back(fs::absolute(o.agentConfig).string());
    }
    return ProcessSpec{name, bin("services/robot_agent/robot_agent"), args, env, plan.logOf(name)};
  }

  /// Robots: a process of their own for each stalled robot, the rest round robin over --agents.
  void agents(const std::vector<Fault>& faults) {
    std::set<std::string> alone;
    for (const auto& f : faults) {
      if (f.kind == Fault::Kind::StallRobot) {
        alone.insert(f.robot);
      }
    }
    std::vector<std::vector<std::string>> groups(static_cast<std::size_t>(std::max(o.agents, 1)));
    std::size_t next = 0;
    for (const auto& r : run.robots) {
      if (plan.vdaRobots.count(r)) {
        continue;
      }
      if (alone.count(r)) {
        plan.agentOfRobot[r] = "agent-" + r;
        continue;
      }
      groups[next % groups.size()].push_back(r);
      plan.agentOfRobot[r] = "agent-" + std::to_string(next % groups.size());
      ++next;
    }
    for (std::size_t g = 0; g < groups.size(); ++g) {
      if (!groups[g].empty()) {
        plan.specs.push_back(agentSpec("agent-" + std::to_string(g), groups[g]));
        plan.agentNames.push_back(plan.specs.back().name);
      }
    }
    for (const auto& r : alone) {
      plan.specs.push_back(agentSpec("agent-" + r, {r}));
      plan.agentNames.push_back(plan.specs.back().name);
    }
  }

  /// The simulator waits for the risk map, the agents, the traffic manager and the bridge to
  /// register (a traffic manager it does not wait for falls behind the robots).
  void simulator(const std::vector<Fault>& faults, const std::string& vdaVehiclesFile) {
    const int participants =
        1 + static_cast<int>(plan.agentNames.size()) + 1 + (vdaVehiclesFile.empty() ? 0 : 1);
    std::vector<std::string> args = {"--scenario",     fs::absolute(run.file).string(),
                                     "--duration",     std::to_string(o.durationS),
                                     "--replay",       abs("replay.jsonl.gz"),
                                     "--summary",      abs("sim_summary.json"),
                                     "--html",         abs("viewer.html"),
                                     "--localization", abs("localization.json"),
                                     "--log-level",    "warn",
                                     "--clock"};
    for (const auto& f : faults) {
      if (f.kind == Fault::Kind::HideLandmarks) {
        args.insert(args.begin(),
                    {"--hide-landmarks", describe(f).substr(std::string("hide-landmarks@").size())});
      }
    }
    if (!vdaVehiclesFile.empty()) {
      args.insert(args.begin(), {"--vda5050", vdaVehiclesFile});
    }
    if (o.wallClock) {
      args.emplace_back("wall");
    } else {
      for (const std::string& a :
           {std::string("lockstep"), std::string("--participants"), std::to_string(participants),
            std::string("--start-timeout-ms"), std::string("60000"), std::string("--step-timeout-ms"),
            std::to_string(o.stepTimeoutMs), std::string("--max-speed"), std::to_string(o.maxSpeed)}) {
        args.push_back(a);
      }
    }
    plan.sim = {"fleet-sim", bin("sim/src/fleet-sim"), args, env, plan.logOf("fleet-sim")};
  }

  /// DDS Security: each process joins as its identity of the folder (scripts/dds-security).
  void secure(ProcessSpec& s) const {
    if (!o.ddsSecurity.empty()) {
      s.env.emplace_back(
          "CYCLONEDDS_URI",
          "file://" + fs::absolute(fs::path(o.ddsSecurity) / identityOf(s.name) / "cyclonedds.xml").string());
    }
  }
};

}  // namespace

std::string FleetPlan::logOf(const std::string& process) const {
  return fs::absolute(out / (process + ".log")).string();
}

// A domain of 100..219 (tests take 10..209: the lock files keep the two apart).
int lockFreeDomain() {
  return lockFreeDdsDomain(100, 120, static_cast<int>(std::random_device{}() % 120));
}

int freePort() {
  const int fd = socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  a.sin_port = 0;
  socklen_t len = sizeof a;
  int port = 0;
  if (bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0 &&
      getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0) {
    port = ntohs(a.sin_port);
  }
  close(fd);
  return port;
}

Expected<void> checkDdsSecurity(const LoadtestOptions& o, double dropFraction) {
  if (o.ddsSecurity.empty()) {
    return {};
  }
  if (dropFraction > 0) {
    return unexpected(
        "dds_security",
        "--dds-security and a drop-packets fault both need their own CYCLONEDDS_URI; give one of them");
  }
  std::vector<std::string> missing;
  for (const char* id : {"fleet-manager", "wms-adapter", "risk-map", "traffic-manager", "simulator"}) {
    if (!fs::exists(fs::path(o.ddsSecurity) / id / "cyclonedds.xml")) {
      missing.emplace_back(id);
    }
  }
  if (!fs::exists(fs::path(o.ddsSecurity) / "ca.key")) {
    missing.emplace_back("the agent processes (the site CA's key ca.key is not there to make them)");
  }
  if (!missing.empty()) {
    std::string names;
    for (const auto& m : missing) {
      names += (names.empty() ? "" : ", ") + m;
    }
    return unexpected("dds_security", "--dds-security " + o.ddsSecurity + ": no identity for " + names +
                                          " (make them with: scripts/dds-security deployment " +
                                          o.ddsSecurity + " agents)");
  }
  return {};
}

Expected<FleetPlan> planFleet(const LoadtestOptions& o, const RunScenario& run,
                              const std::vector<Fault>& faults, const fs::path& out,
                              StandbyManagers* standby) {
  FleetPlan plan;
  plan.out = out;
  plan.db = out / "fleet.db";
  plan.port = o.port > 0 ? o.port : freePort();
  plan.domain = o.domain;
  if (plan.domain < 0) {
    const char* env = std::getenv("FLEET_DDS_DOMAIN");
    plan.domain = env ? std::atoi(env) : lockFreeDomain();
  }
  Builder b{o, run, out, plan, {{"FLEET_DDS_DOMAIN", std::to_string(plan.domain)}}};
  if (const double drop = dropFraction(faults); drop > 0) {
    writeTextFile(out / "cyclonedds.xml", cycloneConfig(drop));
    b.env.emplace_back("CYCLONEDDS_URI", "file://" + fs::absolute(out / "cyclonedds.xml").string());
  }
  b.writeConfigs();
  b.services(standby);
  auto vehicles = b.vda5050();
  if (!vehicles) {
    return unexpected(vehicles.error());
  }
  b.agents(faults);
  b.simulator(faults, *vehicles);
  for (auto& s : plan.specs) {
    b.secure(s);
  }
  b.secure(plan.sim);
  return plan;
}

Expected<void> makeIdentities(const LoadtestOptions& o, const FleetPlan& plan) {
  if (o.ddsSecurity.empty()) {
    return {};
  }
  for (const auto& [process, ids] : plan.robotsOfProcess) {
    const std::string role = process == "vda5050_bridge" ? "vda5050-bridge" : "robot-agent";
    const std::string cmd = "'" + o.securityScript + "' identity '" + fs::absolute(o.ddsSecurity).string() +
                            "' '" + identityOf(process) + "' " + role + " --robots '" + joined(ids) +
                            "' >/dev/null";
    if (std::system(cmd.c_str()) != 0) {
      return unexpected("dds_security", "cannot make the DDS Security identity of " + process + ": " + cmd);
    }
  }
  return {};
}

}  // namespace fleet::ctl
