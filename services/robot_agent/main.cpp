// robot_agent: runs the stack of one or many robots (one DDS participant per process), in wall-clock
// or lockstep mode against the simulator or real robot drivers speaking the same topics.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <thread>

#include "agent.hpp"
#include "fleet/avoidance/planner_config.hpp"
#include "fleet/control/cruise.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/sample_edge.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/service/site_stations.hpp"
#include "fleet/sim/scenario.hpp"
#include "fleet/site/reachability.hpp"
#include "fleet/site/wall_segments.hpp"
#include "fleet/site/zone_costs.hpp"
#include "fleet/transport/dds.hpp"
#include "risk_lookup_of.hpp"
#include "worker_pool.hpp"

using namespace fleet;
using namespace std::chrono_literals;
using nlohmann::json;

namespace {

/// What the agents need of the world: the map, the landmarks and their robots with their starts.
/// From a site and a list of robots (a deployment) or from a simulator scenario.
struct World {
  std::shared_ptr<const planning::OccupancyGrid> map;
  std::shared_ptr<const site::Site> site;  ///< its zones (null: a scenario with its map inline)
  std::vector<std::pair<std::int32_t, Vec2>> landmarks;
  struct Robot {
    std::string id;
    Pose2 start;
    double radius = 0.3;
    double wheelBase = 0.4;
    control::VelocityLimits limits;
  };
  std::vector<Robot> robots;
  double dt = 0.1;  // control period, s
  std::string name;
};

std::shared_ptr<const planning::OccupancyGrid> gridOf(const sim::GridMap& m) {
  auto g = std::make_shared<planning::OccupancyGrid>(m.width, m.height, m.resolution, m.origin);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      if (m.blocked(x, y)) {
        g->setBlocked({x, y});
      }
    }
  }
  return g;
}

World fromScenario(const sim::Scenario& scn) {
  World w;
  w.map = gridOf(scn.map);
  if (scn.site && scn.site->map.width() == w.map->width() && scn.site->map.height() == w.map->height()) {
    w.site = scn.site;
  }
  for (const auto& l : scn.landmarks) {
    w.landmarks.emplace_back(l.id, l.position);
  }
  for (const auto& r : scn.robots) {
    w.robots.push_back({r.id, r.start, r.radius, r.wheelBase, r.limits});
  }
  w.dt = scn.dt;
  w.name = scn.name;
  return w;
}

/// `--robot ID@PLACE`: PLACE is a station of the site or "x,y,theta" in the map frame. Every
/// problem is collected (ConfigError): a bad id, an unknown station, a start the robot does not
/// fit on, an id given twice.
World fromSite(const site::Site& st, const std::vector<std::string>& specs) {
  World w;
  w.map = std::make_shared<const planning::OccupancyGrid>(st.map);
  w.site = std::make_shared<const site::Site>(st);
  for (const auto& l : st.landmarks) {
    w.landmarks.emplace_back(l.id, l.position);
  }
  w.name = st.name;
  std::vector<std::string> problems;
  for (const auto& spec : specs) {
    const auto at = spec.find('@');
    const std::string robot = spec.substr(0, at);
    const std::string place = at == std::string::npos ? "" : spec.substr(at + 1);
    const std::string where = "--robot " + spec + ": ";
    if (!isValidId(robot) || place.empty()) {
      problems.push_back(where +
                         "expected ID@STATION or ID@x,y,theta with an id of 1 to 63 of A-Z a-z 0-9 _ . : -");
      continue;
    }
    World::Robot r{robot, {}, st.robot.radius, st.robot.wheelBase, st.robot.limits};
    if (const auto* station = st.station(place)) {
      r.start = station->pose;
    } else {
      double x = 0, y = 0, th = 0;
      char tail = 0;
      if (std::sscanf(place.c_str(), "%lf,%lf,%lf%c", &x, &y, &th, &tail) != 3 || !std::isfinite(x) ||
          !std::isfinite(y) || !std::isfinite(th)) {
        problems.push_back(where + "'" + place + "' is neither a station of site '" + st.name +
                           "' nor x,y,theta");
        continue;
      }
      r.start = {x, y, wrapAngle(th)};
    }
    if (!site::discFits(st.map, r.start.position(), r.radius)) {
      problems.push_back(where + "a robot of radius " + std::to_string(r.radius) +
                         " m does not fit at its start");
    }
    for (const auto& o : w.robots) {
      if (o.id == robot) {
        problems.push_back(where + "robot '" + robot + "' is given twice");
      }
    }
    w.robots.push_back(r);
  }
  if (specs.empty()) {
    problems.push_back("--site needs at least one --robot ID@STATION");
  }
  if (!problems.empty()) {
    throw ConfigError(problems);
  }
  return w;
}

struct Options {
  std::vector<std::string> only;
  bool lockstep = false;
  std::string id = "agents";
  std::string localPlanner = "dwa";
  std::string globalPlanner = "astar";
  avoidance::DwaParams dwa = agent::agentDwaDefaults();
  avoidance::RiskSteppingParams riskStepping;
  avoidance::SafetyParams safety;
  unsigned threads = 0;  // 0: hardware concurrency
  double sensorTimeoutS = 0.5;
  double riskWeightGlobal = 1.0;
  double returnHomeS = 5.0;
  bool useRisk = true;
  bool useLanes = false;
  bool lineUpdates = true;           // localization.lines: laser lines matched to the site's walls
  std::string traffic = "reactive";  // or "reserved": follow the traffic manager's releases
  std::string metricsFile;           // empty: none
};

/// Cycle-time buckets (seconds): 10 µs to ~1.3 s, each 2^(1/4) (~19 %) wider than the one before,
/// so a percentile estimated inside a bucket is off by less than one bucket's width: at most ~19 %
/// of its value (docs/operator-guide.md#metrics).
std::vector<double> cycleBuckets() {
  return metrics::exponentialBuckets(1e-5, std::pow(2.0, 0.25), 68);
}

/// What the process achieved: cycles, the rate against the configured one, overruns (wall mode)
/// and the wall time of a cycle (all agents stepped and their outputs written), its percentiles
/// estimated from the histogram's buckets (max exact).
json cycleMetrics(const std::string& id, bool lockstep, std::size_t robots, unsigned threads, double dt,
                  std::uint64_t cycles, double elapsedS, std::uint64_t overruns,
                  const metrics::HistogramSnapshot& cycle) {
  return json{
      {"id", id},
      {"clock", lockstep ? "lockstep" : "wall"},
      {"robots", robots},
      {"threads", threads},
      {"configured_hz", dt > 0.0 ? 1.0 / dt : 0.0},
      {"cycles", cycles},
      {"elapsed_s", elapsedS},
      {"achieved_hz", elapsedS > 0.0 ? static_cast<double>(cycles) / elapsedS : 0.0},
      {"overruns", overruns},
      {"cycle_ms",
       {{"p50", cycle.quantile(0.5) * 1e3}, {"p99", cycle.quantile(0.99) * 1e3}, {"max", cycle.max * 1e3}}}};
}

int run(const World& scn, const Options& opt, const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("robot_agent");
  ops.health().setReady("sensors", false);
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  auto& cycleSeconds = ops.registry().histogram(
      "robot_agent_cycle_seconds",
      "Wall time of one control cycle (every hosted robot stepped, outputs written)", cycleBuckets());
  auto& cyclesTotal = ops.registry().counter("robot_agent_cycles_total", "Control cycles run");
  auto& overrunsTotal = ops.registry().counter("robot_agent_cycle_overruns_total",
                                               "Wall mode: cycles that took longer than the period");
  const auto& only = opt.only;
  const bool lockstep = opt.lockstep;
  const std::string& id = opt.id;
  // Robots plan on the map with the site's no-go zones blocked; the walls the localizer matches its
  // scan lines against come from the map itself (a zone is no wall).
  std::shared_ptr<const planning::OccupancyGrid> raw = scn.map;
  planning::CostLayers zoneLayers;
  std::function<double(Vec2)> speedLimit;
  if (scn.site) {
    const auto& noGo = scn.site->layers.noGo;
    if (std::any_of(noGo.begin(), noGo.end(), [](std::uint8_t c) { return c != 0; })) {
      raw = std::make_shared<const planning::OccupancyGrid>(scn.site->drivable());
    }
    zoneLayers = site::zoneCostLayers(scn.site, control::kAgentCruiseSpeed);
    const auto& limits = scn.site->layers.speedLimit;
    if (std::any_of(limits.begin(), limits.end(), [](float v) { return std::isfinite(v); })) {
      speedLimit = [s = scn.site](Vec2 p) { return s->speedLimitAt(p); };
    }
    spdlog::info("robot agent: site '{}': {} zones, {} cost layers{}", scn.site->name, scn.site->zones.size(),
                 zoneLayers.size(), speedLimit ? ", speed limits enforced" : "");
  }
  std::map<double, std::shared_ptr<const planning::OccupancyGrid>> inflatedByRadius;
  std::shared_ptr<const planning::LaneMap> lanes;
  if (opt.useLanes) {
    lanes = std::make_shared<const planning::LaneMap>(planning::LaneMap::derive(*raw));
    spdlog::info("robot agent: {} one-way aisle cells", lanes->oneWayCells());
  }
  // The walls every localizer matches its scan lines against: faces of 0.5 m and more (the line
  // extractor keeps nothing shorter).
  auto walls = std::make_shared<std::vector<estimation::MapSegment>>();
  for (const auto& w : site::wallSegments(*scn.map, agent::agentLineExtraction().minLength)) {
    walls->push_back({w.a, w.b, w.normal});
  }
  spdlog::info("robot agent: {} wall faces for the line updates ({})", walls->size(),
               opt.lineUpdates ? "on" : "off: localization.lines is false");
  std::vector<std::unique_ptr<agent::Agent>> agents;
  std::map<std::string, agent::Agent*> byId;
  for (const auto& r : scn.robots) {
    if (!only.empty() && std::find(only.begin(), only.end(), r.id) == only.end()) {
      continue;
    }
    auto& grid = inflatedByRadius[r.radius];
    if (!grid) {
      // Plan with a margin beyond the footprint so paths keep to the middle of aisles.
      grid = agent::inflate(*raw, r.radius + 0.2);
    }
    agent::AgentParams p;
    p.id = r.id;
    p.start = r.start;
    p.radius = r.radius;
    p.wheelBase = r.wheelBase;
    p.vMax = control::agentCruiseSpeed(r.limits);
    p.wMax = r.limits.omegaMax;
    p.localPlanner = opt.localPlanner;
    p.dwa = opt.dwa;
    p.riskStepping = opt.riskStepping;
    p.safety = opt.safety;
    p.globalPlanner = opt.globalPlanner;
    p.sensorTimeoutS = opt.sensorTimeoutS;
    p.returnHomeS = opt.returnHomeS;
    p.riskWeightGlobal = opt.riskWeightGlobal;
    p.lanes = lanes;
    p.zoneLayers = zoneLayers;
    p.speedLimit = speedLimit;
    p.traffic = opt.traffic;
    p.limits = r.limits;
    p.limits.vMax = p.vMax;
    p.landmarks = scn.landmarks;
    p.walls = walls;
    p.lineUpdates = opt.lineUpdates;
    agents.push_back(std::make_unique<agent::Agent>(p, grid, raw));
    byId[r.id] = agents.back().get();
  }
  if (agents.empty()) {
    spdlog::critical("robot agent: none of the requested robots is in the scenario");
    return 2;
  }
  transport::Participant part;
  transport::Reader<msg::SensorFrame> frames(part, transport::qos::sensor(lockstep));
  transport::Reader<msg::TaskAssignment> assignments(part);
  transport::Reader<msg::Clock> clockIn(part);
  transport::Reader<msg::RobotState> others(part);
  transport::Reader<msg::RiskMap> riskMaps(part);
  transport::Writer<msg::VelocityCommand> commands(part, transport::qos::command(lockstep));
  transport::Writer<msg::RobotState> states(part);
  transport::Writer<msg::PredictedDiscs> discs(part);
  transport::Writer<msg::TaskStatus> statuses(part);
  transport::Writer<msg::StepDone> stepDone(part);
  // Reserved traffic only: a reactive agent neither reads releases nor tells the traffic manager
  // anything (it counts as a robot that does not follow).
  const bool reserved = opt.traffic == "reserved";
  std::optional<transport::Reader<msg::TrafficRelease>> releases;
  std::optional<transport::Writer<msg::TrafficProgress>> trafficProgress;
  if (reserved) {
    releases.emplace(part);
    trafficProgress.emplace(part);
  }
  transport::WaitSet ws(part);
  ws.attach(clockIn);
  ws.attach(frames);
  const unsigned threads =
      std::max(1u, std::min(opt.threads == 0 ? std::thread::hardware_concurrency() : opt.threads,
                            static_cast<unsigned>(agents.size())));
  agent::WorkerPool pool(threads);
  std::vector<agent::AgentOutput> outs(agents.size());
  spdlog::info("robot agent {}: {} robots, {} mode, {} threads, local planner {}, risk {}, {} traffic", id,
               agents.size(), lockstep ? "lockstep" : "wall", pool.threads(), opt.localPlanner,
               opt.useRisk ? "on" : "off", opt.traffic);
  std::uint64_t badRiskMaps = 0;
  validation::Rejections rejections;  // samples refused at this process's edge, by topic and reason
  service::RateLimitedLog badInput;
  badInput.onEach([&ops](const std::string& reason) { ops.rejected(reason).inc(); });
  auto admitted = [&](auto samples) { return service::admitted(std::move(samples), rejections, badInput); };
  if (agents.size() == 1) {
    logging::setField("robot", agents.front()->id());
  }
  ops.watchMatchedWriters("SensorFrame", [&] { return frames.matchedWriters(); });
  ops.watchMatchedWriters("TaskAssignment", [&] { return assignments.matchedWriters(); });
  ops.watchMatchedReaders("VelocityCommand", [&] { return commands.matchedReaders(); });
  ops.watchMatchedReaders("RobotState", [&] { return states.matchedReaders(); });
  ops.watchMatchedReaders("TaskStatus", [&] { return statuses.matchedReaders(); });
  std::uint64_t steps = 0;
  std::map<std::string, metrics::Gauge*> byMode;
  // Robots by mode, counted from the last cycle's states once a second (and readiness: a robot
  // agent can do its job once a sensor source, simulator or driver, is matched).
  auto refreshOps = [&] {
    if (!ops.refresh()) {
      return;
    }
    ops.health().setReady("sensors", frames.matchedWriters() > 0);
    for (auto& [m, g] : byMode) {
      g->set(0.0);
    }
    for (const auto& o : outs) {
      if (steps == 0) {
        break;  // no cycle yet: the states are defaults, not the robots'
      }
      const std::string mode(msg::toString(o.state.mode));
      auto [it, fresh] = byMode.try_emplace(mode, nullptr);
      if (fresh) {
        it->second = &ops.registry().gauge("robot_agent_robots", "Robots hosted by this process, by mode",
                                           {{"mode", mode}});
      }
      it->second->add(1.0);
    }
  };

  bool haveClock = false;
  auto lastRegister = std::chrono::steady_clock::now() - 1s;
  std::int64_t simNow = 0;
  double dt = scn.dt;
  auto cycle = [&](std::int64_t now) {
    const auto cycleStart = std::chrono::steady_clock::now();
    for (const auto& f : admitted(frames.take())) {
      if (auto it = byId.find(f.robot_id); it != byId.end()) {
        it->second->onFrame(f);
      }
    }
    for (const auto& s : admitted(others.take())) {
      if (byId.count(s.robot_id) != 0) {
        continue;  // hosted here: handed over in-process after the step (below)
      }
      for (auto& a : agents) {
        a->onOtherRobot(s);
      }
    }
    for (auto& a : assignments.take()) {
      const auto it = byId.find(a.robot_id);
      validation::Rejection why;
      if (validation::admit(a, rejections, &why)) {
        if (it != byId.end()) {
          it->second->onAssignment(a);
        }
        continue;
      }
      badInput.warn(why.topic + ":" + why.reason, "refused " + why.topic + ": " + why.detail);
      if (it != byId.end() && isValidId(a.task_id)) {
        it->second->refuseAssignment(a, why.detail);  // the manager hears why and retries elsewhere
      }
    }
    if (releases) {
      for (const auto& r : admitted(releases->take())) {
        if (auto it = byId.find(r.robot_id); it != byId.end()) {
          it->second->onRelease(r);
        }
      }
    }
    if (auto maps = admitted(riskMaps.take()); !maps.empty() && opt.useRisk) {
      // Only the newest map matters; it is decoded once and shared read-only by every agent.
      if (auto field = agent::riskLookupOf(maps.back())) {
        for (auto& a : agents) {
          a->onRiskMap(*field);
        }
      } else {
        ops.rejected("risk_map").inc();
        if (badRiskMaps++ % 100 == 0) {
          spdlog::warn("robot agent {}: RiskMap ignored ({} so far): {}", id, badRiskMaps,
                       field.error().message);
        }
      }
    }
    // Agents step in parallel (each touches only its own state and const shared maps); outputs
    // are written afterwards in robot order, so the DDS traffic of a lockstep run does not depend
    // on thread timing.
    pool.forEach(agents.size(), [&](std::size_t i) {
      logging::ScopedField robotField("robot", agents[i]->id());  // on whatever a step logs
      outs[i] = agents[i]->step(now, dt);
    });
    for (std::size_t i = 0; i < agents.size(); ++i) {
      auto& a = agents[i];
      auto& out = outs[i];
      out.command.seq = static_cast<std::uint32_t>(steps);
      commands.write(out.command);
      states.write(out.state);
      discs.write(out.discs);
      if (out.status) {
        statuses.write(*out.status);
        ops.registry()
            .counter("robot_agent_task_reports_total", "TaskStatus reports sent, by the state reported",
                     {{"state", std::string(msg::toString(out.status->state))}})
            .inc();
        logging::ScopedField robotField("robot", a->id());
        logging::ScopedField taskField("task", out.status->task_id);
        spdlog::debug("{}: task {} {}", a->id(), out.status->task_id, msg::toString(out.status->state));
      }
      if (out.traffic && trafficProgress) {
        trafficProgress->write(*out.traffic);
      }
    }
    // Robots of this process learn each other's state directly, exactly one cycle later. Over DDS
    // a sample came one or two cycles late depending on timing, and what the local planner makes
    // of a neighbour's position and velocity made lockstep replays differ between runs.
    pool.forEach(agents.size(), [&](std::size_t j) {
      for (std::size_t i = 0; i < agents.size(); ++i) {
        if (i != j) {
          agents[j]->onOtherRobot(outs[i].state);
        }
      }
    });
    ++steps;
    cyclesTotal.inc();
    // Constant cost and memory whatever the uptime (a bucket increment, no sample kept).
    cycleSeconds.observe(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - cycleStart).count());
  };

  auto wallNext = std::chrono::steady_clock::now();
  const auto started = wallNext;
  std::uint64_t overruns = 0;
  std::optional<std::chrono::steady_clock::time_point> firstCycle;  // lockstep: the first step
  auto writeMetrics = [&] {
    if (opt.metricsFile.empty()) {
      return;
    }
    const auto from = lockstep && firstCycle ? *firstCycle : started;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
    auto m = cycleMetrics(id, lockstep, agents.size(), pool.threads(), dt, steps, elapsed, overruns,
                          cycleSeconds.snapshot());
    // How the robots of this process dealt with each other (docs/algorithms.md, fleet conduct).
    agent::Agent::Conduct c;
    for (const auto& a : agents) {
      c.standoffs += a->conduct().standoffs;
      c.mutualBlocks += a->conduct().mutualBlocks;
      c.backoffs += a->conduct().backoffs;
      c.returns += a->conduct().returns;
      c.detours += a->conduct().detours;
      c.plannerRecoveries += a->conduct().plannerRecoveries;
    }
    m["samples"] = rejections.toJson();
    m["conduct"] = {{"standoffs", c.standoffs}, {"wait_cycles", c.mutualBlocks},
                    {"backoffs", c.backoffs},   {"returns", c.returns},
                    {"detours", c.detours},     {"planner_recoveries", c.plannerRecoveries}};
    agent::LineStats ls;
    for (const auto& a : agents) {
      const auto& l = a->lineStats();
      ls.scans += l.scans;
      ls.scansNoLines += l.scansNoLines;
      ls.extracted += l.extracted;
      ls.matched += l.matched;
      ls.accepted += l.accepted;
      ls.rejectedByFilter += l.rejectedByFilter;
      ls.noWallFacing += l.noWallFacing;
      ls.outsideGate += l.outsideGate;
      ls.noOverlap += l.noOverlap;
      ls.ambiguous += l.ambiguous;
    }
    m["localization"] = {{"line_updates", opt.lineUpdates},
                         {"scans", ls.scans},
                         {"skipped_no_lines", ls.scansNoLines},
                         {"lines_extracted", ls.extracted},
                         {"lines_matched", ls.matched},
                         {"lines_accepted", ls.accepted},
                         {"lines_rejected_by_filter", ls.rejectedByFilter},
                         {"unmatched_no_wall_facing", ls.noWallFacing},
                         {"unmatched_outside_gate", ls.outsideGate},
                         {"unmatched_no_overlap", ls.noOverlap},
                         {"unmatched_ambiguous", ls.ambiguous}};
    agent::ReleaseCounts rc;
    for (const auto& a : agents) {
      rc.accepted += a->releases().accepted;
      rc.foreign += a->releases().foreign;
      rc.stale += a->releases().stale;
      rc.offNode += a->releases().offNode;
      rc.malformed += a->releases().malformed;
    }
    m["traffic"] = {
        {"mode", opt.traffic},       {"releases_taken", rc.accepted},  {"ignored_foreign", rc.foreign},
        {"ignored_stale", rc.stale}, {"ignored_off_node", rc.offNode}, {"ignored_malformed", rc.malformed}};
    std::ofstream f(opt.metricsFile + ".tmp");
    f << m.dump(1) << "\n";
    f.close();
    std::error_code ec;
    std::filesystem::rename(opt.metricsFile + ".tmp", opt.metricsFile, ec);
  };
  // Wall mode: the achieved control rate against the configured one, logged every 10 s.
  auto rateSince = wallNext;
  std::uint64_t rateCycles = 0;
  while (!service::stopRequested()) {
    if (lockstep) {
      if (!haveClock && std::chrono::steady_clock::now() - lastRegister > 100ms) {
        stepDone.write({id, msg::StepDone::kRegister});
        lastRegister = std::chrono::steady_clock::now();
      }
      ws.wait(100ms);
      refreshOps();
      for (const auto& c : clockIn.take()) {
        haveClock = true;
        simNow = c.sim_time_ns;
        dt = nsToSec(c.dt_ns);
        cycle(simNow);
        stepDone.write({id, c.step});
        if (!firstCycle) {
          firstCycle = std::chrono::steady_clock::now();
        }
      }
    } else {
      std::this_thread::sleep_until(wallNext);
      const auto period = std::chrono::microseconds(static_cast<std::int64_t>(dt * 1e6));
      wallNext += period;
      if (const auto t = std::chrono::steady_clock::now(); t > wallNext) {
        ++overruns;  // a cycle took longer than the period: do not burst to catch up
        overrunsTotal.inc();
        wallNext = t;
      }
      if (++rateCycles; std::chrono::steady_clock::now() - rateSince >= 10s) {
        const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - rateSince).count();
        spdlog::info("robot agent {}: {:.2f} cycles/s (configured {:.1f} Hz), {} overruns so far", id,
                     static_cast<double>(rateCycles) / s, 1.0 / dt, overruns);
        rateSince = std::chrono::steady_clock::now();
        rateCycles = 0;
        writeMetrics();
      }
      for (const auto& c : clockIn.take()) {
        simNow = c.sim_time_ns;
      }
      cycle(WallClock{}.nowNs());
      refreshOps();
    }
  }
  if (lockstep) {
    stepDone.write({id, msg::StepDone::kLeave});
  }
  writeMetrics();
  spdlog::info("robot agent {}: stopped after {} cycles", id, steps);
  return 0;
}

/// The --config file: planner choice and parameters (docs/operator-guide.md, robot agent). Command
/// line options given explicitly win over the file. Every problem is reported at once.
void applyConfigFile(const std::string& path, Options& opt, bool localFromCli, bool globalFromCli,
                     bool trafficFromCli) {
  Config cfg = Config::fromFile(path);
  const std::string local = cfg.string("local_planner", opt.localPlanner);
  const std::string global = cfg.string("global_planner", opt.globalPlanner, {"astar", "wavefront", "ompl"});
  const std::string traffic = cfg.string("traffic", opt.traffic, {"reactive", "reserved"});
  Config dwa = cfg.child("dwa");
  Config stepping = cfg.child("risk_stepping");
  Config safety = cfg.child("safety");
  opt.dwa = avoidance::dwaParams(dwa, opt.dwa);
  opt.riskStepping = avoidance::riskSteppingParams(stepping, opt.riskStepping);
  opt.safety = avoidance::safetyParams(safety);
  Config localization = cfg.child("localization");
  opt.lineUpdates = localization.boolean("lines", opt.lineUpdates);
  localization.rejectUnknownKeys({"lines"});
  cfg.rejectUnknownKeys(
      {"local_planner", "global_planner", "traffic", "dwa", "risk_stepping", "safety", "localization"});
  if (!localFromCli) {
    opt.localPlanner = local;
  }
  if (!globalFromCli) {
    opt.globalPlanner = global;
  }
  if (!trafficFromCli) {
    opt.traffic = traffic;
  }
  if (opt.localPlanner != "follow") {
    if (auto p = avoidance::makePlanner(opt.localPlanner); !p) {
      cfg.problem("local_planner", p.error().message + " (or \"follow\")");
    }
  }
  cfg.finish();
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"robot_agent: the local stack of one or many robots"};
  std::string scenario;
  std::string robots;
  std::string clock = "wall";
  std::string id = "agents";
  Options opt;
  bool noRisk = false;
  app.add_option(
         "--global-planner", opt.globalPlanner,
         "astar (default; the risk map as cell cost), wavefront, or ompl (Informed RRT*, 50 ms per plan)")
      ->check(CLI::IsMember({"astar", "wavefront", "ompl"}));
  app.add_option("--local-planner", opt.localPlanner,
                 "dwa (default; with the risk map's term), risk_stepping (thesis 000 §3.2.3), "
                 "risk_stepping_weighted, vo, potential_field, ... (a libs/avoidance planner behind "
                 "the safety layer) or follow (the Lyapunov path follower)");
  app.add_option("--threads", opt.threads, "worker threads stepping the agents (0: hardware concurrency)")
      ->check(CLI::Range(0u, 256u));
  app.add_option("--sensor-timeout", opt.sensorTimeoutS,
                 "s without a SensorFrame (agent clock) before a robot stops and reports RM_FAULT")
      ->check(CLI::Range(0.05, 60.0));
  app.add_option("--risk-weight", opt.riskWeightGlobal,
                 "global planner: cell cost = length x (1 + w p); paths stay within (1 + w) x the shortest")
      ->check(CLI::Range(0.0, 10.0));
  app.add_option("--return-home", opt.returnHomeS,
                 "s idle before a robot drives back to its start (parking) pose; negative: stay put")
      ->check(CLI::Range(-1.0, 3600.0));
  app.add_flag("--no-risk", noRisk, "ignore RiskMap (planners without the risk term)");
  bool lanes = false;
  bool noLanes = false;
  app.add_flag("--lanes", lanes,
               "plan on the lane map (one-way narrow aisles, keep-right bands) instead of plain A*; "
               "off by default: 20 robots finish ~15 % fewer tasks with it (docs/benchmarks.md)");
  app.add_flag("--no-lanes", noLanes, "plain A* (the default; wins over --lanes)");
  app.add_option(
         "--traffic", opt.traffic,
         "reactive (default: robots keep clear of each other by standoffs, yielding and detours) or "
         "reserved (drive only what the traffic manager releases: TrafficRelease in, TrafficProgress out)")
      ->check(CLI::IsMember({"reactive", "reserved"}));
  std::string sitePath;
  std::vector<std::string> robotSpecs;
  auto* scenarioOpt =
      app.add_option("--scenario", scenario, "simulator scenario (its site, its robots and their starts)");
  app.add_option("--site", sitePath, "site file (site.json, a ROS map .yaml or a .map): a deployment")
      ->excludes(scenarioOpt);
  app.add_option("--robot", robotSpecs,
                 "with --site: a robot and where it stands, ID@STATION or ID@x,y,theta (repeat)");
  app.add_option("--robots", robots, "comma-separated robot ids (default: every robot of the scenario)");
  app.add_option("--clock", clock, "wall or lockstep")->check(CLI::IsMember({"wall", "lockstep"}));
  app.add_option("--id", id, "participant id in lockstep");
  service::CommonOptions common;
  service::addCommonOptions(app, common);
  app.add_option("--metrics", opt.metricsFile,
                 "write cycle metrics (achieved rate, overruns, cycle time p50/p99) to this JSON file every "
                 "10 s in wall mode and at exit");
  std::string configFile;
  app.add_option("-c,--config", configFile,
                 "JSON file: local_planner, global_planner, traffic, dwa {weights, samples, horizon...}, "
                 "risk_stepping {rule: iso_level | weighted, levels, ...}, "
                 "safety {zones}, localization {lines} (docs/operator-guide.md); options given on the "
                 "command line win");
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("robot_agent", common);
    if (!configFile.empty()) {
      applyConfigFile(configFile, opt, app.count("--local-planner") > 0, app.count("--global-planner") > 0,
                      app.count("--traffic") > 0);
    }
    World world;
    if (!sitePath.empty()) {
      auto st = service::loadSiteFile(sitePath);
      if (!st) {
        throw ConfigError({st.error().message});
      }
      world = fromSite(*st, robotSpecs);
    } else if (!scenario.empty()) {
      if (!robotSpecs.empty()) {
        throw ConfigError(
            {"--robot goes with --site; a scenario names its robots (select them with --robots)"});
      }
      world = fromScenario(sim::loadScenario(scenario));
    } else {
      throw ConfigError(
          {"give --site FILE --robot ID@STATION ... (a deployment) or --scenario FILE (the simulator)"});
    }
    std::stringstream ss(robots);
    for (std::string r; std::getline(ss, r, ',');) {
      if (!r.empty()) {
        opt.only.push_back(r);
      }
    }
    opt.lockstep = clock == "lockstep";
    opt.id = id;
    opt.useRisk = !noRisk;
    service::installStopHandlers();
    opt.useLanes = lanes && !noLanes;
    return run(world, opt, common.ops);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("robot agent: {}", e.what());
    return 1;
  }
}
