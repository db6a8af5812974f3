// Agent cycle cost with many agents in one process: N Agent objects (the robot_agent stack: EKF,
// release following, DWA with the risk term, task execution) on a warehouse map, fed synthetic frames
// from an exact kinematic world (odometry, compass, a 181-beam scan with nothing in range, every other
// robot's state as over DDS), each with
// an endless series of pickup → drop-off tasks and its route released by the traffic manager's node
// in-process (its tick is not timed). Per-agent step time is thread CPU time; the cycle (all N agents
// through the worker pool) is wall time, from which the achievable control rate follows.

#include <benchmark/benchmark.h>
#include <time.h>

#include <algorithm>
#include <string>
#include <vector>

#include "agent.hpp"
#include "fleet/control/diff_drive_kinematics.hpp"
#include "fleet/scenario/grid_map.hpp"
#include "fleet/scenario/scenario.hpp"
#include "traffic_node.hpp"
#include "worker_pool.hpp"

using namespace fleet;

namespace {

double threadCpuS() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) {
    return 0.0;
  }
  const auto k = static_cast<std::size_t>(q * static_cast<double>(v.size() - 1));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}

struct Fleet {
  std::unique_ptr<trafficmgr::TrafficNode> traffic;
  std::vector<std::unique_ptr<agent::Agent>> agents;
  std::vector<Pose2> truth;
  std::vector<msg::VelocityCommand> last;
  std::vector<std::uint32_t> tasks;
  std::vector<sim::Station> pickups;
  std::vector<sim::Station> drops;
  double wheelBase = 0.4;

  msg::TaskAssignment order(std::size_t i) {
    msg::TaskAssignment a;
    a.robot_id = agents[i]->id();
    a.revision = ++tasks[i];
    a.task_id = a.robot_id + "-" + std::to_string(a.revision);
    const auto& p = pickups[(i + a.revision) % pickups.size()];
    const auto& d = drops[(i * 7 + a.revision) % drops.size()];
    a.goals.push_back({p.pose, p.name, msg::GoalAction::Load, 1.0});
    a.goals.push_back({d.pose, d.name, msg::GoalAction::Unload, 1.0});
    return a;
  }
};

Fleet makeFleet(const std::string& scenario, int n, const std::string& planner) {
  const auto scn = sim::loadScenario(std::string(FLEET_SOURCE_DIR) + "/sim/scenarios/" + scenario);
  if (static_cast<std::size_t>(n) > scn.robots.size()) {
    throw std::invalid_argument(scenario + " has " + std::to_string(scn.robots.size()) + " robots, not " +
                                std::to_string(n));
  }
  auto raw = std::make_shared<const planning::OccupancyGrid>(sim::toOccupancyGrid(scn.map));
  Fleet f;
  trafficmgr::Settings ts;
  ts.clock = "sim";
  ts.lockstep = true;
  f.traffic = std::make_unique<trafficmgr::TrafficNode>(*scn.site, ts, 1);
  for (const auto& s : scn.stations) {
    (s.kind == sim::StationKind::Pickup ? f.pickups : f.drops).push_back(s);
  }
  if (f.pickups.empty() || f.drops.empty()) {
    f.pickups = f.drops = scn.stations;
  }
  for (int i = 0; i < n; ++i) {
    const auto& r = scn.robots[static_cast<std::size_t>(i)];
    agent::AgentParams p;
    p.id = "b" + std::to_string(i);
    p.start = r.start;
    p.radius = r.radius;
    p.wheelBase = r.wheelBase;
    p.localPlanner = planner;
    p.limits = r.limits;
    p.limits.vMax = p.vMax = std::min(0.8, r.limits.vMax);
    f.wheelBase = r.wheelBase;
    f.agents.push_back(std::make_unique<agent::Agent>(p, raw));
    f.truth.push_back(r.start);
    f.last.push_back({});
    f.tasks.push_back(0);
  }
  for (std::size_t i = 0; i < f.agents.size(); ++i) {
    f.agents[i]->onAssignment(f.order(i));
  }
  return f;
}

void BM_AgentCycle(benchmark::State& state, const std::string& scenario, const std::string& planner) {
  const int n = static_cast<int>(state.range(0));
  const auto threads = static_cast<unsigned>(state.range(1));
  Fleet f = makeFleet(scenario, n, planner);
  agent::WorkerPool pool(threads);
  std::vector<double> stepCpu(f.agents.size());
  std::vector<double> samples;
  std::vector<double> cycles;
  std::vector<agent::AgentOutput> outs(f.agents.size());
  const double dt = 0.1;
  std::int64_t now = 0;
  msg::SensorFrame frame;
  frame.angle_min = -1.5708f;
  frame.angle_increment = 3.14159f / 180.0f;
  frame.range_max = 8.0f;
  frame.ranges.assign(181, 8.0f);
  frame.compass_valid = true;
  frame.battery = 0.9f;
  int done = 0;
  int failed = 0;
  std::size_t moving = 0;
  for (auto _ : state) {
    for (std::size_t i = 0; i < f.agents.size(); ++i) {
      const auto& c = f.last[i];
      f.truth[i] = control::DiffDriveKinematics::integrateExact(f.truth[i], {c.v, c.w}, dt);
      frame.robot_id = f.agents[i]->id();
      frame.ds_left = (c.v - c.w * f.wheelBase / 2) * dt;
      frame.ds_right = (c.v + c.w * f.wheelBase / 2) * dt;
      frame.compass = f.truth[i].theta;
      f.agents[i]->onFrame(frame);
    }
    const auto t0 = std::chrono::steady_clock::now();
    pool.forEach(f.agents.size(), [&](std::size_t i) {
      const double c0 = threadCpuS();
      outs[i] = f.agents[i]->step(now, dt);
      stepCpu[i] = threadCpuS() - c0;
    });
    cycles.push_back(std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count());
    for (std::size_t i = 0; i < f.agents.size(); ++i) {
      samples.push_back(stepCpu[i]);
      f.last[i] = outs[i].command;
      moving += std::abs(outs[i].command.v) > 0.05 ? 1 : 0;
      if (outs[i].status && outs[i].status->state == msg::TaskState::Done) {
        ++done;
      }
      if (outs[i].status && outs[i].status->state == msg::TaskState::Failed) {
        ++failed;
      }
      if (!f.agents[i]->busy()) {
        f.agents[i]->onAssignment(f.order(i));
      }
      if (outs[i].traffic) {
        (void)f.traffic->onProgress(*outs[i].traffic, now);
      }
    }
    // Every robot's state reaches every agent each cycle, as over DDS (not timed): the other
    // robots are the local planner's moving discs.
    for (std::size_t i = 0; i < f.agents.size(); ++i) {
      if (const auto o = agent::Agent::otherOf(outs[i].state)) {
        for (auto& a : f.agents)
          a->onOtherRobot(i, *o);
      }
    }
    for (const auto& r : f.traffic->tick(now)) {
      for (auto& a : f.agents) {
        if (a->id() == r.robot_id) {
          a->onRelease(r);
        }
      }
    }
    now += 100'000'000;
  }
  state.counters["agents"] = n;
  state.counters["threads"] = threads;
  state.counters["step_p50_us"] = 1e6 * percentile(samples, 0.50);
  state.counters["step_p99_us"] = 1e6 * percentile(samples, 0.99);
  state.counters["step_max_us"] = 1e6 * percentile(samples, 1.0);
  state.counters["cycle_p50_ms"] = 1e3 * percentile(cycles, 0.50);
  state.counters["cycle_p99_ms"] = 1e3 * percentile(cycles, 0.99);
  // Cycles per second the pool could sustain at the p99 cycle (the service runs at 1/dt = 10 Hz).
  state.counters["rate_at_p99_hz"] = 1.0 / std::max(1e-9, percentile(cycles, 0.99));
  // The share of agent steps that drove (the local planner runs only while a robot drives its
  // release): a bench whose robots stand measures nothing.
  state.counters["moving_share"] =
      static_cast<double>(moving) / static_cast<double>(std::max<std::size_t>(1, samples.size()));
  state.counters["tasks_done"] = done;
  state.counters["tasks_failed"] = failed;
}

}  // namespace

// Every agent on a start of its own (the scenario's robots): agents sharing a start would stand
// unplaced by the traffic manager. The small warehouse has 20 robots, the large one 300: 150 is
// one agent process's share of a 300-robot load test.
BENCHMARK_CAPTURE(BM_AgentCycle, small_dwa, std::string("small_warehouse.json"), std::string("dwa"))
    ->Args({10, 1})
    ->Args({20, 1})
    ->Args({20, 2})
    ->Iterations(600)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_AgentCycle, small_follow, std::string("small_warehouse.json"), std::string("follow"))
    ->Args({20, 1})
    ->Iterations(600)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_CAPTURE(BM_AgentCycle, large_dwa, std::string("large_warehouse.json"), std::string("dwa"))
    ->Args({100, 2})
    ->Args({150, 2})
    ->Iterations(600)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK_MAIN();
