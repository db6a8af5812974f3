// robot_agent: runs the stack of one or many robots (one DDS participant per process), in wall-clock
// or lockstep mode against the simulator or real robot drivers speaking the same topics. The robots
// and their messages are the AgentNode's; this file wires DDS, the clock, the command line and ops.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <thread>

#include "agent_node.hpp"
#include "agent_settings.hpp"
#include "agent_world.hpp"
#include "cycle_metrics.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/core/config.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/service/command_line.hpp"
#include "fleet/service/common_options.hpp"
#include "fleet/service/dds_security_check.hpp"
#include "fleet/service/runtime.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet/service/step_order.hpp"
#include "fleet/transport/dds.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

/// Wall clock in ms since the epoch (the pose file's stamps).
std::int64_t unixMs() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(
             std::chrono::system_clock::now().time_since_epoch())
      .count();
}

/// The process around the node: how it is clocked, its lockstep id, where its metrics go.
struct Process {
  bool lockstep = false;
  std::string id = "agents";
  std::string metricsFile;  // empty: none
};

void logMapFacts(const agent::MapFacts& f, bool lineUpdates) {
  if (f.siteName) {
    spdlog::info("robot agent: site '{}': {} zones{}", *f.siteName, f.zones,
                 f.speedLimits ? ", speed limits enforced" : "");
  }
  spdlog::info("robot agent: {} wall faces for the line updates ({})", f.wallFaces,
               lineUpdates ? "on" : "off: localization.lines is false");
}

int run(const agent::World& world, const agent::Settings& settings, const Process& proc,
        const service::OpsSettings& opsSettings) {
  service::ServiceOps ops("robot_agent");
  ops.health().setReady("sensors", false);
  if (!ops.start(opsSettings)) {
    return service::kExitUsage;
  }
  auto& cycleSeconds = ops.registry().histogram(
      "robot_agent_cycle_seconds",
      "Wall time of one control cycle (every hosted robot stepped, outputs written)", agent::cycleBuckets());
  auto& cyclesTotal = ops.registry().counter("robot_agent_cycles_total", "Control cycles run");
  auto& overrunsTotal = ops.registry().counter("robot_agent_cycle_overruns_total",
                                               "Wall mode: cycles that took longer than the period");
  const bool lockstep = proc.lockstep;
  const std::string& id = proc.id;
  // Robots restarted where they were (the pose file), not at their parking places.
  agent::SavedPoses resume;
  if (!settings.poseFile.empty()) {
    auto saved = agent::readPoseFile(settings.poseFile);
    if (!saved) {
      spdlog::error("robot agent {}: {}; its robots start at their start poses", proc.id,
                    saved.error().message);
    } else {
      resume = agent::freshPoses(*saved, unixMs(), agent::kPoseFreshS);
      if (saved->size() != resume.size()) {
        spdlog::warn("robot agent {}: {} of the pose file's {} poses are older than {} s: not used", proc.id,
                     saved->size() - resume.size(), saved->size(), agent::kPoseFreshS);
      }
    }
  }
  auto created = agent::AgentNode::create(world, settings, resume);
  if (created) {
    logMapFacts((*created)->mapFacts(), settings.lineUpdates);
  } else {
    spdlog::critical("robot agent: {}", created.error().message);
    return 2;
  }
  agent::AgentNode& node = **created;
  for (const auto& [robot, saved] : resume) {
    if (node.find(robot) != nullptr) {
      spdlog::info("robot agent {}: {} resumes at ({:.2f}, {:.2f}, {:.2f}) from the pose file{}", proc.id,
                   robot, saved.pose.x, saved.pose.y, saved.pose.theta,
                   saved.wheels ? " with its wheel totals" : " without wheel totals (less certain)");
    }
  }
  agent::PoseWriter poseWriter(settings.poseFile, agent::kPoseWritePeriodMs);
  bool poseWriteFailed = false;
  auto writePoses = [&](std::int64_t clockMs) {
    agent::SavedPoses poses;
    const std::int64_t stamp = unixMs();
    for (std::size_t i = 0; i < node.size(); ++i) {
      poses[node.agent(i).id()] = agent::SavedPose{node.agent(i).pose(), stamp, node.agent(i).wheelTotals()};
    }
    const auto written = poseWriter.write(poses, clockMs);
    if (!written && !poseWriteFailed) {
      spdlog::error("robot agent {}: {} (tried again every {} ms)", proc.id, written.error().message,
                    agent::kPoseWritePeriodMs);
    }
    poseWriteFailed = !written;
  };
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
  // In lockstep the reader keeps every release of a robot until it is taken (one of the next step
  // may arrive before this one is taken; keeping the last only, it would replace this one).
  auto releaseQos = transport::qos::trafficRelease();
  releaseQos.depth = lockstep ? 16 : releaseQos.depth;
  transport::Reader<msg::TrafficRelease> releases(part, releaseQos);
  transport::Writer<msg::TrafficProgress> trafficProgress(part);
  // A writer per hosted robot and topic, each in the robot's partition (transport/
  // robot_partition.hpp), made now: readers match them during start-up, and DDS Security refuses
  // here, with the robot named, a robot this process's permissions do not grant.
  std::vector<std::string> robots;
  for (std::size_t i = 0; i < node.size(); ++i) {
    robots.push_back(node.agent(i).id());
  }
  // For operators (the dashboard): optional, as DDS permissions made before the topic existed (or
  // before it moved to the robots' partitions) do not let an agent write it; the robots drive the
  // same without it.
  std::optional<transport::Writer<msg::PeopleSeen>> peopleSeen;
  try {
    peopleSeen.emplace(part);
    peopleSeen->forRobots(robots);
  } catch (const std::exception& e) {
    peopleSeen.reset();
    spdlog::warn("robot agent {}: not publishing the people seen ({})", proc.id, e.what());
  }
  {
    commands.forRobots(robots);
    states.forRobots(robots);
    discs.forRobots(robots);
    statuses.forRobots(robots);
    trafficProgress.forRobots(robots);
  }
  transport::Writer<msg::StepDone> stepDone(part);
  transport::WaitSet ws(part);
  ws.attach(clockIn);
  ws.attach(frames);
  spdlog::info("robot agent {}: {} robots, {} mode, {} threads, local planner {}, risk {}", id, node.size(),
               lockstep ? "lockstep" : "wall", node.threads(), settings.localPlanner,
               settings.useRisk ? "on" : "off");
  service::RateLimitedLog badInput;
  badInput.onEach([&ops](const std::string& reason) { ops.rejected(reason).inc(); });
  if (node.size() == 1) {
    logging::setField("robot", node.agent(0).id());
  }
  ops.watchMatchedWriters("SensorFrame", [&] { return frames.matchedWriters(); });
  ops.watchMatchedWriters("TaskAssignment", [&] { return assignments.matchedWriters(); });
  ops.watchMatchedReaders("VelocityCommand", [&] { return commands.matchedReaders(); });
  ops.watchMatchedReaders("RobotState", [&] { return states.matchedReaders(); });
  ops.watchMatchedReaders("TaskStatus", [&] { return statuses.matchedReaders(); });
  ops.watchForeign([&] { return others.foreign(); });
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
    if (node.cycles() == 0) {
      return;  // no cycle yet: the states are defaults, not the robots'
    }
    for (const auto& o : node.outputs()) {
      const std::string mode(msg::toString(o.state.mode));
      auto [it, fresh] = byMode.try_emplace(mode, nullptr);
      if (fresh) {
        it->second = &ops.registry().gauge("robot_agent_robots", "Robots hosted by this process, by mode",
                                           {{"mode", mode}});
      }
      it->second->add(1.0);
    }
  };

  // A robot standing with its task (or on its way home) this long [s] is logged (and again
  // as often), with why it stands. The traffic manager logs whom it waits on; this is the robot's side.
  constexpr double kStandingWarnS = 60.0;
  std::vector<std::int64_t> standWarnedNs(node.size(), -1);
  auto warnStanding = [&](std::size_t i, std::int64_t now) {
    const auto& a = node.agent(i);
    const auto& st = a.standingStill();
    if (st.sinceNs < 0 || nsToSec(now - st.sinceNs) < kStandingWarnS ||
        (standWarnedNs[i] >= st.sinceNs && nsToSec(now - standWarnedNs[i]) < kStandingWarnS)) {
      return;
    }
    standWarnedNs[i] = now;
    const Pose2 pose = a.perception().pose;
    logging::ScopedField robotField("robot", a.id());
    spdlog::warn("{}: standing for {:.0f} s {} at ({:.2f}, {:.2f}, {:.2f} rad), node {}, next {}: {}", a.id(),
                 nsToSec(now - st.sinceNs), st.homing ? "on its way home" : "with its task", pose.x, pose.y,
                 pose.theta, a.trafficNode(),
                 st.next ? fmt::format("({:.2f}, {:.2f})", st.next->x, st.next->y) : std::string("none"),
                 st.why);
  };

  double dt = world.dt;
  // In lockstep a release acts from the step after the one it was made in (StepOrder). (This holds
  // as long as a release reaches the agents within the simulator's round trip of a step: a loopback
  // sample takes well under a millisecond. Waiting for acknowledgements instead cost a heartbeat a
  // step.)
  service::StepOrder<msg::TrafficRelease> releaseOrder(lockstep);
  auto cycle = [&](std::int64_t now) {
    const auto cycleStart = std::chrono::steady_clock::now();
    // Taken and handed over topic by topic, in the node's order.
    node.onFrames(frames.take());
    node.onRobotStates(others.take());
    node.onAssignments(assignments.take());
    node.onReleases(releaseOrder.due(releases.take(), now));
    node.onRiskMaps(riskMaps.take());
    const auto& outs = node.step(now, dt);
    for (const auto& r : node.takeRefusals()) {
      badInput.warn(r.key, r.message);
    }
    for (std::size_t i = 0; i < outs.size(); ++i) {
      const auto& out = outs[i];
      commands.write(out.command);
      states.write(out.state);
      discs.write(out.discs);
      if (out.status) {
        statuses.write(*out.status);
        ops.registry()
            .counter("robot_agent_task_reports_total", "TaskStatus reports sent, by the state reported",
                     {{"state", std::string(msg::toString(out.status->state))}})
            .inc();
        const std::string& robot = node.agent(i).id();
        logging::ScopedField robotField("robot", robot);
        logging::ScopedField taskField("task", out.status->task_id);
        spdlog::debug("{}: task {} {}", robot, out.status->task_id, msg::toString(out.status->state));
      }
      if (out.traffic) {
        trafficProgress.write(*out.traffic);
      }
      warnStanding(i, now);
      if (out.people && peopleSeen) {
        peopleSeen->write(*out.people);
      }
    }
    if (poseWriter.due(now / 1'000'000)) {  // the agent's clock: simulated time in lockstep
      writePoses(now / 1'000'000);
    }
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
    if (proc.metricsFile.empty()) {
      return;
    }
    const auto from = lockstep && firstCycle ? *firstCycle : started;
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
    auto m = agent::cycleMetrics(id, lockstep, node.size(), node.threads(), dt, node.cycles(), elapsed,
                                 overruns, cycleSeconds.snapshot());
    m.update(node.statsJson());
    std::ofstream f(proc.metricsFile + ".tmp");
    f << m.dump(1) << "\n";
    f.close();
    std::error_code ec;
    std::filesystem::rename(proc.metricsFile + ".tmp", proc.metricsFile, ec);
  };
  bool haveClock = false;
  auto lastRegister = std::chrono::steady_clock::now() - 1s;
  // Wall mode: the achieved control rate against the configured one, logged every 10 s.
  auto rateSince = wallNext;
  std::uint64_t rateCycles = 0;
  while (!service::stopRequested()) {
    if (lockstep) {
      // Registers only once every robot's command writer has matched the simulator's reader: a
      // volatile writer keeps a command only for the readers it knows, so one written before that
      // would never arrive, and the simulator would wait for it (StepDone names it) until the step
      // timeout.
      if (!haveClock && std::chrono::steady_clock::now() - lastRegister > 100ms &&
          commands.matchedReaders() > 0) {
        stepDone.write({id, msg::StepDone::kRegister});
        lastRegister = std::chrono::steady_clock::now();
      }
      ws.wait(100ms);
      refreshOps();
      for (const auto& c : clockIn.take()) {
        haveClock = true;
        dt = nsToSec(c.dt_ns);
        cycle(c.sim_time_ns);
        // The commands just written, one per robot: the simulator applies the step once they are in.
        msg::StepDone done{id, c.step, {}};
        for (const auto& out : node.outputs()) {
          done.commands.push_back({out.command.robot_id, out.command.seq});
        }
        stepDone.write(done);
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
      (void)clockIn.take();  // wall mode steps on its own clock; the simulator's is not used
      cycle(WallClock{}.nowNs());
      refreshOps();
    }
  }
  if (lockstep) {
    stepDone.write({id, msg::StepDone::kLeave});
  }
  writeMetrics();
  if (poseWriter.enabled()) {
    writePoses(0);
  }
  spdlog::info("robot agent {}: stopped after {} cycles", id, node.cycles());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "robot_agent: the local stack of one or many robots; each drives what the traffic manager releases "
      "to it (TrafficRelease in, TrafficProgress out)"};
  std::string scenario;
  std::string robots;
  std::string clock = "wall";
  agent::Settings settings;
  Process proc;
  bool noRisk = false;
  app.add_option("--local-planner", settings.localPlanner,
                 "dwa (default; with the risk map's term), risk_stepping (thesis 000 §3.2.3), "
                 "risk_stepping_weighted, vo, potential_field, ... (a libs/avoidance planner behind "
                 "the safety layer) or follow (the Lyapunov path follower)");
  app.add_option("--threads", settings.threads,
                 "worker threads stepping the agents (0: hardware concurrency)")
      ->check(CLI::Range(0u, 256u));
  app.add_option("--sensor-timeout", settings.sensorTimeoutS,
                 "s without a SensorFrame (agent clock) before a robot stops and reports RM_FAULT")
      ->check(CLI::Range(0.05, 60.0));
  app.add_option("--return-home", settings.returnHomeS,
                 "negative: an idle robot stays where its last task ended instead of going back to its "
                 "start (parking) pose")
      ->check(CLI::Range(-1.0, 3600.0));
  app.add_flag("--no-risk", noRisk, "ignore RiskMap (planners without the risk term)");
  app.add_option(
      "--pose-file", settings.poseFile,
      "keep each hosted robot's last pose in this file (written every 0.2 s) and, started again, "
      "start each robot's localization there instead of at its start pose (docs/operator-guide.md)");
  std::string sitePath;
  std::vector<std::string> robotSpecs;
  auto* scenarioOpt =
      app.add_option("--scenario", scenario, "simulator scenario (its site, its robots and their starts)");
  app.add_option("--site", sitePath, "site file (site.json, a ROS map .yaml or a .map): a deployment")
      ->excludes(scenarioOpt);
  app.add_option("--robot", robotSpecs,
                 "with --site: a robot and where it stands, ID@STATION or ID@x,y,theta (repeat)");
  app.add_option("--robots", robots, "comma-separated robot ids (default: every robot of the scenario)")
      ->envname("FLEET_AGENT_ROBOTS");
  app.add_option("--clock", clock, "wall or lockstep")->check(CLI::IsMember({"wall", "lockstep"}));
  app.add_option("--id", proc.id, "participant id in lockstep");
  service::CommonOptions common;
  service::addCommonOptions(app, common);
  app.add_option("--metrics", proc.metricsFile,
                 "write cycle metrics (achieved rate, overruns, cycle time p50/p99) to this JSON file every "
                 "10 s in wall mode and at exit");
  std::string configFile;
  app.add_option("-c,--config", configFile,
                 "JSON file: local_planner, dwa {weights, samples, horizon...}, "
                 "risk_stepping {rule: iso_level | weighted, levels, ...}, "
                 "safety {zones}, localization {lines} (docs/operator-guide.md); options given on the "
                 "command line win");
  if (auto code = service::parse(app, argc, argv)) {
    return *code;
  }
  try {
    service::setupLogging("robot_agent", common);
    service::checkDdsSecurity();  // exit 2 naming a missing certificate, key or document
    if (!configFile.empty()) {
      Config cfg = Config::fromFile(configFile);
      agent::readSettings(cfg, settings, {app.count("--local-planner") > 0});
      cfg.finish();
    }
    agent::World world;
    if (!sitePath.empty()) {
      auto st = fleet::loadSiteFile(sitePath);
      if (!st) {
        throw ConfigError({st.error().message});
      }
      world = agent::worldFromSite(*st, robotSpecs);
    } else if (!scenario.empty()) {
      if (!robotSpecs.empty()) {
        throw ConfigError(
            {"--robot goes with --site; a scenario names its robots (select them with --robots)"});
      }
      world = agent::worldFromScenario(scenario);
    } else {
      throw ConfigError(
          {"give --site FILE --robot ID@STATION ... (a deployment) or --scenario FILE (the simulator)"});
    }
    std::stringstream ss(robots);
    for (std::string r; std::getline(ss, r, ',');) {
      if (!r.empty()) {
        settings.only.push_back(r);
      }
    }
    proc.lockstep = clock == "lockstep";
    settings.useRisk = !noRisk;
    service::installStopHandlers();
    return run(world, settings, proc, common.ops);
  } catch (const ConfigError& e) {
    spdlog::critical("{}", e.what());
    return 2;
  } catch (const std::exception& e) {
    spdlog::critical("robot agent: {}", e.what());
    return 1;
  }
}
