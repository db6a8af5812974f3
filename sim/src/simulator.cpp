#include "simulator.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <optional>
#include <random>
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

namespace fleet::simulator {

bool writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
  return static_cast<bool>(out);
}

namespace {

using namespace std::chrono_literals;

// The simulated drivers' run: new and nonzero each time the process starts (its wheel totals start
// from zero again), so an agent never takes the totals of two runs for motion. From the operating
// system's entropy, not the scenario's seed: a restart with the same seed is another run.
std::uint64_t driverSession() {
  static const std::uint64_t session = [] {
    std::random_device rd;
    const std::uint64_t s = (static_cast<std::uint64_t>(rd()) << 32U) ^ rd();
    return s != 0 ? s : 1;
  }();
  return session;
}

msg::SensorFrame toMsg(const sim::World& w, const sim::SensorReading& r, std::int64_t stamp) {
  msg::SensorFrame f;
  f.robot_id = w.scenario().robots[r.robot].id;
  f.stamp_ns = stamp;
  f.seq = r.seq;
  f.ds_left = r.dsLeft;
  f.ds_right = r.dsRight;
  f.wheel_totals_valid = true;
  f.wheel_left_total = r.wheelLeftTotal;
  f.wheel_right_total = r.wheelRightTotal;
  f.driver_session = driverSession();
  f.angle_min = r.angleMin;
  f.angle_increment = r.angleIncrement;
  f.range_max = r.rangeMax;
  f.ranges = r.ranges;
  f.compass_valid = r.compassValid;
  f.compass = r.compass;
  for (const auto& [id, b] : r.landmarks) {
    f.landmarks.push_back({id, b});
  }
  for (const auto& d : r.detections) {
    f.detections.push_back({d.human ? msg::SourceKind::Human : msg::SourceKind::Robot, d.x, d.y, d.r});
  }
  f.battery = r.battery;
  f.charging = r.charging;
  return f;
}

class Simulator {
 public:
  Simulator(sim::World& w, const Options& o, bool lockstep, service::ServiceOps& ops,
            const std::atomic<bool>& stop)
      : stop_(stop),
        ops_(ops),
        stepSeconds_(ops.registry().histogram(
            "fleet_sim_step_seconds", "Wall time of one simulation step (commands applied, world advanced)",
            metrics::exponentialBuckets(1e-5, 2.0, 20))),
        steps_(ops.registry().counter("fleet_sim_steps_total", "Simulation steps done")),
        stepTimeouts_(ops.registry().counter("fleet_sim_step_timeouts_total",
                                             "Lockstep steps that timed out waiting for a participant")),
        simSeconds_(ops.registry().gauge("fleet_sim_simulated_seconds", "Simulated time")),
        w_(w),
        o_(o),
        lockstep_(lockstep),
        sensorW_(p_, transport::qos::sensor(lockstep)),
        truthW_(p_),
        discsW_(p_),
        clockW_(p_),
        cmdR_(p_, transport::qos::command(lockstep)),
        doneR_(p_),
        stateR_(p_),
        riskR_(p_),
        stepWs_(p_),
        errors_(1.0, o.hiddenLandmarks) {
    stepWs_.attach(doneR_);
    stepWs_.attach(cmdR_);
    // The traffic layer for the replay viewer (roadmap, releases); the simulator runs on without
    // it where its DDS permissions predate it.
    try {
      roadmapR_ = std::make_unique<transport::Reader<msg::Roadmap>>(p_);
      releaseR_ = std::make_unique<transport::Reader<msg::TrafficRelease>>(p_);
    } catch (const std::exception& e) {
      roadmapR_.reset();
      spdlog::warn("fleet-sim: the replay will not show the traffic layer ({})", e.what());
    }
    ops_.registry()
        .gauge("fleet_sim_bodies", "Bodies in the world", {{"kind", "robot"}})
        .set(static_cast<double>(w_.robots().size()));
    ops_.registry()
        .gauge("fleet_sim_bodies", "Bodies in the world", {{"kind", "human"}})
        .set(static_cast<double>(w_.humans().size()));
    ops_.watchMatchedReaders("SensorFrame", [this] { return sensorW_.matchedReaders(); });
    ops_.watchMatchedReaders("Clock", [this] { return clockW_.matchedReaders(); });
    ops_.watchMatchedWriters("VelocityCommand", [this] { return cmdR_.matchedWriters(); });
    ops_.watchForeign([this] { return stateR_.foreign(); });
    ops_.watchForeign([this] { return cmdR_.foreign(); });
    discsW_.forRobots({""});  // people's discs: the default partition (not a robot's)
    ops_.watchMatchedWriters("StepDone", [this] { return doneR_.matchedWriters(); });
  }

  int run() {
    if (!o_.vda5050.empty()) {
      sim::Vda5050FleetConfig config;
      try {
        config = sim::readVda5050FleetConfig(Config::fromFile(o_.vda5050));
      } catch (const ConfigError& e) {
        spdlog::error("--vda5050: {}", e.what());
        return 2;
      }
      auto fleet = sim::Vda5050Fleet::start(config, w_);
      if (!fleet) {
        spdlog::error("{}", fleet.error().message);
        return 2;
      }
      vda_ = std::move(*fleet);
      spdlog::info("vda5050: {} robot(s) are VDA 5050 vehicles on broker {}:{}", config.vehicles.size(),
                   config.host, config.port);
    }
    if (!o_.replay.empty()) {
      auto r = sim::ReplayWriter::open(o_.replay);
      if (!r) {
        spdlog::error("{}", r.error().message);
        return 1;
      }
      replay_.emplace(std::move(*r));
      (void)replay_->write(sim::replayHeader(w_));
    }
    const auto total = static_cast<std::int64_t>(std::llround(w_.scenario().durationS / w_.scenario().dt));
    spdlog::info("scenario '{}': {} robots, {} humans, {} steps of {} s, clock {}, seed {}",
                 w_.scenario().name, w_.robots().size(), w_.humans().size(), total, w_.scenario().dt,
                 lockstep_ ? "lockstep" : "wall", w_.scenario().seed);
    if (lockstep_) {
      waitForParticipants();
    }
    const auto start = std::chrono::steady_clock::now();
    const auto dt = std::chrono::nanoseconds(secToNs(w_.scenario().dt));
    for (std::int64_t k = 0;; ++k) {
      barrier_.begin(k);
      publish();
      if (k >= total || stop_) {
        break;
      }
      if (lockstep_) {
        awaitStep(k);
        if (o_.maxSpeed > 0.0) {
          // Services on the wall clock (fleet manager, WMS adapter, the load generator) see time
          // pass maxSpeed times slower than the robots do: a cap keeps their latencies meaningful.
          std::this_thread::sleep_until(
              start + std::chrono::duration_cast<std::chrono::nanoseconds>(dt * (k + 1) / o_.maxSpeed));
        }
      } else {
        const auto due = start + dt * (k + 1);
        if (std::chrono::steady_clock::now() > due && ++w_.counters().wallOverruns % 100 == 1) {
          spdlog::warn("wall clock: step {} overran dt; the simulation is behind real time ({} overruns)", k,
                       w_.counters().wallOverruns);
        }
        std::this_thread::sleep_until(due);
        pollStepDone();
      }
      const auto t0 = std::chrono::steady_clock::now();
      applyCommands();
      stepVehicles();
      w_.advance();
      stepSeconds_.observe(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
      steps_.inc();
      simSeconds_.set(w_.time());
      if (ops_.refresh()) {
        contacts();
      }
    }
    const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return finish(wall);
  }

 private:
  const std::atomic<bool>& stop_;
  std::int64_t stamp() const { return lockstep_ ? w_.timeNs() : wall_.nowNs(); }

  void waitForParticipants() {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(o_.startTimeoutMs);
    while (static_cast<int>(barrier_.registered()) < o_.participants && !stop_) {
      if (std::chrono::steady_clock::now() > deadline) {
        spdlog::warn("lockstep: only {} of {} participants registered after {} ms; starting anyway",
                     barrier_.registered(), o_.participants, o_.startTimeoutMs);
        break;
      }
      doneR_.waitForData(50ms);
      ops_.refresh();
      pollStepDone();
    }
    spdlog::info("lockstep: {} participant(s) registered", barrier_.registered());
  }

  void pollStepDone() {
    for (auto& d : doneR_.take()) {
      // Commands for robots the world does not have are ignored when applied: not waited for.
      sim::LockstepBarrier::Marks marks;
      for (auto& c : d.commands) {
        if (w_.robotIndex(c.robot_id) >= 0) {
          marks.emplace_back(std::move(c.robot_id), c.seq);
        }
      }
      if (!barrier_.onStepDone(d.participant_id, d.step, std::move(marks))) {
        spdlog::debug("StepDone({}) from unregistered '{}' ignored", d.step, d.participant_id);
      } else if (d.step < 0) {
        spdlog::info("lockstep: '{}' {}", d.participant_id, d.step == -1 ? "registered" : "left");
      }
    }
  }

  /// Takes the commands that have arrived; they wait in pending_ until the step is applied.
  void pollCommands() {
    for (auto& c : cmdR_.take()) {
      if (w_.robotIndex(c.robot_id) >= 0) {
        barrier_.onCommand(c.robot_id, c.seq);
      }
      pending_.push_back(std::move(c));
    }
    w_.counters().foreignCommands = cmdR_.foreign();
  }

  void awaitStep(std::int64_t k) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(o_.stepTimeoutMs);
    pollStepDone();
    pollCommands();
    while (!barrier_.complete(k) && !stop_) {
      if (std::chrono::steady_clock::now() > deadline) {
        ++w_.counters().stepTimeouts;
        stepTimeouts_.inc();
        const auto missing = barrier_.missing(k);
        std::string who;
        for (const auto& m : missing) {
          who += (who.empty() ? "" : ", ") + m;
        }
        if (w_.counters().stepTimeouts <= 10 || w_.counters().stepTimeouts % 100 == 0) {
          spdlog::warn("lockstep: step {} timed out after {} ms waiting for {} (timeouts so far: {})", k,
                       o_.stepTimeoutMs, who, w_.counters().stepTimeouts);
        }
        return;
      }
      stepWs_.wait(5ms);
      ops_.health().beat();
      pollStepDone();
      pollCommands();
    }
  }

  void applyCommands() {
    pollCommands();
    // In arrival order: a robot's commands come from one writer, in the order written; which
    // robot's come first does not matter.
    std::vector<msg::VelocityCommand> commands;
    commands.swap(pending_);
    for (const auto& c : commands) {
      if (w_.command(c.robot_id, c.v, c.w) == sim::CommandOutcome::Ignored) {
        ops_.rejected(w_.robotIndex(c.robot_id) < 0 ? "velocity_command_unknown_robot"
                                                    : "velocity_command_not_finite")
            .inc();
        if (++ignoredLogged_ <= 10) {
          spdlog::warn("ignored VelocityCommand for '{}' (v={}, w={}): {}", c.robot_id, c.v, c.w,
                       w_.robotIndex(c.robot_id) < 0 ? "unknown robot" : "not finite");
        }
      }
    }
    for (const auto& s : stateR_.take()) {
      const int i = w_.robotIndex(s.robot_id);
      if (i >= 0) {
        w_.setLabel(
            static_cast<std::size_t>(i), msg::toString(s.mode), s.task_id,
            s.activity == msg::RobotActivity::Unset ? std::string() : std::string(toString(s.activity)));
        if (lockstep_) {  // stamps are simulated time only in lockstep
          errors_.estimate(static_cast<std::size_t>(i), s.stamp_ns, s.pose);
        }
      }
    }
  }

  void stepVehicles() {
    if (!vda_) {
      return;
    }
    vda_->step(w_, w_.time(), stamp());
    for (const auto& warning : vda_->takeWarnings()) {
      if (++vdaWarnings_ <= 50) {
        spdlog::warn("vda5050: {}", warning);
      }
    }
  }

  void publish() {
    const std::int64_t st = stamp();
    const double now = static_cast<double>(w_.timeNs()) * 1e-9;
    const bool hidden = std::any_of(o_.hiddenLandmarks.begin(), o_.hiddenLandmarks.end(),
                                    [&](const auto& h) { return now >= h.first && now < h.second; });
    if (lockstep_) {
      std::vector<Pose2> truth;
      truth.reserve(w_.robots().size());
      for (const auto& r : w_.robots()) {
        truth.push_back(r.pose);
      }
      errors_.truth(w_.timeNs(), truth);
    }
    for (auto& r : w_.sensorFrames(!o_.noScan)) {
      if (hidden) {
        r.landmarks.clear();  // after the draws: the sensor noise stream stays the same
      }
      const bool silent = std::any_of(o_.outages.begin(), o_.outages.end(), [&](const SensorOutage& o) {
        return w_.robotIndex(o.robot) == static_cast<int>(r.robot) && now >= o.fromS && now < o.toS;
      });
      if (!silent && !(vda_ && vda_->controls(r.robot))) {
        sensorW_.write(toMsg(w_, r, st));
      }
    }
    msg::GroundTruth gt;
    gt.step = w_.step();
    gt.sim_time_ns = w_.timeNs();
    for (std::size_t i = 0; i < w_.robots().size(); ++i) {
      const auto& r = w_.robots()[i];
      gt.bodies.push_back({w_.scenario().robots[i].id, msg::SourceKind::Robot, r.pose, r.twist.v,
                           w_.scenario().robots[i].radius});
    }
    for (std::size_t i = 0; i < w_.humans().size(); ++i) {
      const auto& h = w_.humans()[i];
      gt.bodies.push_back(
          {h.id, msg::SourceKind::Human, Pose2{h.p.x, h.p.y, std::atan2(h.v.y, h.v.x)}, h.v.norm(), h.r});
      msg::PredictedDiscs pd;
      pd.source_id = h.id;
      pd.kind = msg::SourceKind::Human;
      pd.t0_ns = st;
      pd.dt = static_cast<float>(w_.scenario().predictionDt);
      for (const auto& d : w_.predictHuman(i)) {
        pd.discs.push_back({static_cast<float>(d.x), static_cast<float>(d.y), static_cast<float>(d.r),
                            static_cast<float>(d.sigma)});
      }
      discsW_.write(pd);
    }
    for (const auto& c : w_.contacts()) {
      gt.contacts.push_back({w_.bodyId(c.a), w_.bodyId(c.b), c.depth});
    }
    truthW_.write(gt);
    if (replay_) {
      auto line = sim::replayStep(w_);
      // The newest risk map (if the risk service runs) goes into the step it arrived at, for the viewer.
      auto maps = riskR_.take();
      if (!maps.empty()) {
        const auto& m = maps.back();
        nlohmann::json runs = nlohmann::json::array();
        for (const auto& r : m.runs) {
          runs.push_back({r.level, r.count});
        }
        line["risk"] = {{"origin", {m.origin_x, m.origin_y}},
                        {"resolution", m.resolution},
                        {"width", m.width},
                        {"height", m.height},
                        {"levels", m.levels},
                        {"runs", runs}};
      }
      if (roadmapR_ && releaseR_) {
        addTraffic(line);
      }
      (void)replay_->write(line);
    }
    clockW_.write({w_.step(), lockstep_ ? w_.timeNs() : st, secToNs(w_.scenario().dt), lockstep_});
  }

  /// The traffic layer into the replay step it arrived at: a new roadmap (its open flags change
  /// with closures) and the releases that changed, for the viewer.
  void addTraffic(nlohmann::json& line) {
    auto maps = roadmapR_->take();
    if (!maps.empty() && !validation::check(maps.back())) {
      line["roadmap"] = sim::replayRoadmap(maps.back());
      if (maps.back().epoch != roadmapEpoch_) {
        line["releases_reset"] = true;  // a new traffic manager: earlier releases no longer hold
      }
      roadmapEpoch_ = maps.back().epoch;
    }
    nlohmann::json rel = nlohmann::json::object();
    for (const auto& r : releaseR_->take()) {
      if (validation::check(r) || r.epoch < roadmapEpoch_) {
        continue;  // malformed, or from a traffic manager before the roadmap's
      }
      rel[r.robot_id] = sim::replayRelease(r);
    }
    if (!rel.empty()) {
      line["releases"] = std::move(rel);
    }
  }

  /// Contacts so far, by pair kind (the world counts them; the counters follow).
  void contacts() {
    const auto& m = w_.metrics();
    const std::pair<const char*, std::uint64_t> kinds[] = {
        {"robot_robot", static_cast<std::uint64_t>(m.robotRobotContacts)},
        {"robot_human", static_cast<std::uint64_t>(m.robotHumanContacts)},
        {"robot_shelf", static_cast<std::uint64_t>(m.robotShelfContacts)}};
    for (const auto& [kind, n] : kinds) {
      auto& c = ops_.registry().counter("fleet_sim_contacts_total", "Contacts between bodies, by kind",
                                        {{"kind", kind}});
      if (n > c.value()) {
        c.inc(n - c.value());
      }
    }
  }

  int finish(double wallS) {
    auto s = sim::summary(w_);
    if (vda_) {
      s["vda5050"] = {{"states_sent", vda_->counters().states_sent},
                      {"refused_messages", vda_->counters().refused_messages},
                      {"rejected_orders", vda_->counters().rejected_orders},
                      {"base_starved_stops", vda_->baseStarvedStops()}};
      // Order-to-motion (p99 <= 100 ms through the broker): the bridge stamps an order
      // when it publishes it, on its clock; on the wall clock that is the simulator's too.
      std::vector<double> ms;
      for (const std::int64_t ns : vda_->orderToMotionNs()) {
        ms.push_back(static_cast<double>(ns) / 1e6);
      }
      const auto p = fleet::percentiles(std::move(ms));
      s["vda5050"]["order_to_motion"] = {{"clock", lockstep_ ? "simulated" : "wall"},
                                         {"count", p.count},
                                         {"untimed", vda_->untimedOrders()},
                                         {"p50_ms", p.p50},
                                         {"p99_ms", p.p99},
                                         {"max_ms", p.max}};
      vda_.reset();  // OFFLINE on the connection topic, then a clean disconnect
    }
    if (replay_) {
      if (auto r = replay_->close(); !r) {
        spdlog::error("{}", r.error().message);
        return 1;
      }
    }
    if (!o_.localization.empty()) {
      std::vector<std::string> ids;
      for (const auto& r : w_.scenario().robots) {
        ids.push_back(r.id);
      }
      if (!writeText(o_.localization, errors_.toJson(ids).dump(1) + "\n")) {
        spdlog::error("cannot write '{}'", o_.localization);
        return 1;
      }
      spdlog::info("localization error: {} estimates compared, {} of no instant held", errors_.samples(),
                   errors_.unmatched());
    }
    if (!o_.summary.empty() && !writeText(o_.summary, s.dump(2) + "\n")) {
      spdlog::error("cannot write summary '{}'", o_.summary);
      return 1;
    }
    if (!o_.html.empty()) {
      auto lines = sim::readReplayLines(o_.replay);
      if (o_.replay.empty() || !lines) {
        spdlog::error("--html needs --replay (the page embeds the replay)");
        return 1;
      }
      if (!writeText(o_.html, sim::viewerHtml(*lines))) {
        spdlog::error("cannot write '{}'", o_.html);
        return 1;
      }
    }
    spdlog::info(
        "done: {} steps ({} s simulated) in {:.2f} s wall; contacts rr={} rh={} rs={}; step timeouts {}",
        w_.step(), w_.time(), wallS, w_.metrics().robotRobotContacts, w_.metrics().robotHumanContacts,
        w_.metrics().robotShelfContacts, w_.counters().stepTimeouts);
    std::cout << s.dump() << std::endl;
    return 0;
  }

  service::ServiceOps& ops_;
  metrics::Histogram& stepSeconds_;
  metrics::Counter& steps_;
  metrics::Counter& stepTimeouts_;
  metrics::Gauge& simSeconds_;
  sim::World& w_;
  const Options& o_;
  bool lockstep_;
  WallClock wall_;
  transport::Participant p_;
  transport::Writer<msg::SensorFrame> sensorW_;
  transport::Writer<msg::GroundTruth> truthW_;
  transport::Writer<msg::PredictedDiscs> discsW_;
  transport::Writer<msg::Clock> clockW_;
  transport::Reader<msg::VelocityCommand> cmdR_;
  transport::Reader<msg::StepDone> doneR_;
  transport::Reader<msg::RobotState> stateR_;
  transport::Reader<msg::RiskMap> riskR_;
  std::unique_ptr<transport::Reader<msg::Roadmap>> roadmapR_;
  std::unique_ptr<transport::Reader<msg::TrafficRelease>> releaseR_;
  std::uint32_t roadmapEpoch_ = 0;
  transport::WaitSet stepWs_;                  // lockstep: StepDone or a command arrived
  std::vector<msg::VelocityCommand> pending_;  // arrived, not yet applied
  sim::LockstepBarrier barrier_;
  std::optional<sim::ReplayWriter> replay_;
  sim::LocalizationErrorLog errors_;
  int ignoredLogged_ = 0;
  std::unique_ptr<sim::Vda5050Fleet> vda_;
  int vdaWarnings_ = 0;
};

}  // namespace

int runSimulation(sim::World& world, const Options& o, bool lockstep, service::ServiceOps& ops,
                  const std::atomic<bool>& stop) {
  Simulator s(world, o, lockstep, ops, stop);
  return s.run();
}

}  // namespace fleet::simulator
