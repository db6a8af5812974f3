// avoidance_bench: (1) one full local-stack cycle per robot — EKF odometry prediction + compass
// update, DWA with the risk term over a 360-point scan and 6 discs, and the safety layer — with its
// per-cycle p50/p99 as counters; (2) the circle swap (N robots of radius 0.4 m to their
// antipodes) run in the same process with the stack's planner and with the VO baseline, reporting
// success, overlaps and compute per agent-step side by side (ratio counter); (3) every planner on
// every harness scenario (BM_Harness: the comparison table); (4) the arc clearance of a DWA rollout
// against 300 obstacle points, the library's sector test by cross products against the atan2 one it
// replaced (BM_ArcClearance/0 and /1, same run: compare them as a ratio).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <ctime>
#include <iterator>
#include <random>
#include <string>
#include <vector>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/avoidance/harness.hpp"
#include "fleet/avoidance/risk_stepping.hpp"
#include "fleet/avoidance/safety_layer.hpp"
#include "fleet/core/angles.hpp"
#include "fleet/estimation/pose_ekf.hpp"

namespace {

using namespace fleet;

// Per-cycle cost in thread CPU time: the machine is shared, and wall time would mostly measure
// the other builds that pre-empt us.
double threadCpuUs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e6 + static_cast<double>(ts.tv_nsec) * 1e-3;
}
using namespace fleet::avoidance;

// A 10 m × 6 m room seen by a 360-beam scan (one point per degree) from its middle, plus two boxes.
std::vector<Vec2> roomScan(Vec2 c) {
  std::vector<Vec2> pts;
  for (int i = 0; i < 360; ++i) {
    const double a = static_cast<double>(i) * 3.14159265358979323846 / 180.0;
    const Vec2 d{std::cos(a), std::sin(a)};
    // Walls x = ±5, y = ±3 around c, a box face at x = c.x + 1.5 for |y| < 0.5.
    double t = 1e9;
    if (d.x > 1e-9)
      t = std::min(t, 5.0 / d.x);
    if (d.x < -1e-9)
      t = std::min(t, -5.0 / d.x);
    if (d.y > 1e-9)
      t = std::min(t, 3.0 / d.y);
    if (d.y < -1e-9)
      t = std::min(t, -3.0 / d.y);
    if (d.x > 1e-9) {
      const double tb = 1.5 / d.x;
      if (std::abs(tb * d.y) < 0.5)
        t = std::min(t, tb);
    }
    pts.push_back(c + d * t);
  }
  return pts;
}

risk::ProbabilityGrid riskGrid() {
  risk::ProbabilityGrid g;
  g.spec = {-6.0, -4.0, 0.1, 120, 80};
  g.p.resize(g.spec.cellCount());
  for (int j = 0; j < g.spec.height; ++j) {
    for (int i = 0; i < g.spec.width; ++i) {
      const double x = g.spec.cellCentreX(i) - 1.0;
      const double y = g.spec.cellCentreY(j) + 1.0;
      g.p[g.spec.index(i, j)] = std::exp(-(x * x + y * y));
    }
  }
  return g;
}

void BM_LocalStackCycle(benchmark::State& state) {
  auto ekf = estimation::PoseEkf::create({}, {0, 0, 0}, Eigen::Matrix3d::Identity() * 1e-4);
  if (!ekf) {
    state.SkipWithError("ekf");
    return;
  }
  const auto scan = roomScan({0, 0});
  const std::vector<MovingDisc> discs{{{2.0, 1.5}, {-0.3, 0.0}, 0.4}, {{-1.0, -2.0}, {0.0, 0.5}, 0.3},
                                      {{3.0, -1.0}, {0.0, 0.0}, 0.4}, {{1.0, 2.5}, {0.2, -0.2}, 0.3},
                                      {{-3.0, 1.0}, {0.5, 0.0}, 0.4}, {{4.0, 2.0}, {0.0, 0.0}, 0.4}};
  const std::vector<Vec2> path{{1.0, 0.0}, {2.0, 1.0}, {4.0, 1.0}};
  const auto grid = riskGrid();
  SafePlanner planner(std::make_unique<DynamicWindowPlanner>());
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 1e-3);
  std::vector<double> us;
  us.reserve(1 << 16);
  LocalView view;
  view.path = path;
  view.scan = scan;
  view.discs = discs;
  view.risk = riskLookup(grid);
  view.robot.radius = 0.4;
  view.robot.twist = {0.3, 0.1};
  for (auto _ : state) {
    const double dl = 0.03 + noise(rng);
    const double dr = 0.031 + noise(rng);
    const double t0 = threadCpuUs();
    ekf->predict(dl, dr);
    ekf->updateCompass(ekf->pose().theta + noise(rng));
    view.robot.pose = ekf->pose();
    const Command c = planner.plan(view);
    const double t1 = threadCpuUs();
    benchmark::DoNotOptimize(c);
    us.push_back(t1 - t0);
    if (ekf->pose().position().squaredNorm() > 0.25) {
      state.PauseTiming();
      (void)ekf->reset({0, 0, 0}, Eigen::Matrix3d::Identity() * 1e-4);
      state.ResumeTiming();
    }
  }
  std::sort(us.begin(), us.end());
  auto q = [&](double f) {
    return us[std::min(us.size() - 1, static_cast<std::size_t>(f * static_cast<double>(us.size())))];
  };
  state.counters["cpu_p50_us"] = q(0.5);
  state.counters["cpu_p99_us"] = q(0.99);
  state.counters["cpu_max_us"] = us.back();
}
BENCHMARK(BM_LocalStackCycle)->Unit(benchmark::kMicrosecond)->MinTime(2.0);

// Circle swap: the named planner and the VO baseline in the same run.
void BM_CircleSwap(benchmark::State& state, const char* planner) {
  const int n = static_cast<int>(state.range(0));
  const double R = std::max(4.0, 0.2 * static_cast<double>(n));  // R = 20 m at n = 100: 1.26 m apart
  ScenarioResult base{};
  ScenarioResult mine{};
  for (auto _ : state) {
    Scenario sc = circleSwap(n, R);
    sc.maxSteps = 3000;  // 300 s simulated: the straight-line crossing takes 40 s at n = 100
    auto m = runScenario(sc, planner);
    auto b = runScenario(sc, "vo");
    if (!m || !b) {
      state.SkipWithError("scenario");
      return;
    }
    mine = *m;
    base = *b;
  }
  state.counters["reached"] = mine.reached;
  state.counters["robot_overlaps"] = mine.robotCollisions;
  state.counters["min_sep_m"] = mine.minSeparation;
  state.counters["makespan_s"] = mine.makespan;
  state.counters["us_per_agent_step"] = mine.computeMeanUs;
  state.counters["vo_reached"] = base.reached;
  state.counters["vo_overlaps"] = base.robotCollisions;
  state.counters["vo_makespan_s"] = base.makespan;
  state.counters["vo_us_per_agent_step"] = base.computeMeanUs;
  state.counters["compute_ratio_vs_vo"] =
      base.computeMeanUs > 0 ? mine.computeMeanUs / base.computeMeanUs : 0;
}
BENCHMARK_CAPTURE(BM_CircleSwap, vo_keep_right, "vo_keep_right")
    ->Arg(8)
    ->Arg(100)
    ->Unit(benchmark::kSecond)
    ->Iterations(1);
BENCHMARK_CAPTURE(BM_CircleSwap, orca, "orca")->Arg(8)->Arg(100)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK_CAPTURE(BM_CircleSwap, dwa, "dwa")->Arg(8)->Arg(100)->Unit(benchmark::kSecond)->Iterations(1);

// The harness comparison table of docs/benchmarks.md: every planner (behind the safety layer) on
// every harness scenario, one deterministic run each; only the µs depend on the machine.
const char* const kPlanners[] = {"dwa",
                                 "potential_field",
                                 "bug1",
                                 "bug2",
                                 "risk_stepping",
                                 "risk_stepping_weighted",
                                 "elastic_strips",
                                 "elastic_strips_bvh",
                                 "vo",
                                 "vo_keep_right",
                                 "orca"};

Scenario harnessScenario(int which) {
  switch (which) {
    case 0:
      return obstacleCourse();
    case 1:
      return aisleCrossingAlone();
    case 2:
      return circleSwap(8, 4.0);
    default:
      return aisleCrossing(2, 2, 3);
  }
}

void BM_Harness(benchmark::State& state) {
  const char* planner = kPlanners[state.range(0)];
  const Scenario sc = harnessScenario(static_cast<int>(state.range(1)));
  ScenarioResult r{};
  for (auto _ : state) {
    auto res = runScenario(sc, planner);
    if (!res) {
      state.SkipWithError(res.error().message.c_str());
      return;
    }
    r = *res;
  }
  state.SetLabel(std::string(planner) + " " + sc.name);
  state.counters["reached"] = r.reached;
  state.counters["robots"] = r.robots;
  state.counters["static_contacts"] = r.staticCollisions;
  state.counters["robot_contacts"] = r.robotCollisions;
  state.counters["human_contacts"] = r.humanCollisions;
  state.counters["driven_into_human"] = r.humanHitsByRobot;
  state.counters["min_gap_m"] = r.minSeparation;
  state.counters["mean_time_s"] = r.meanTimeToGoal;
  state.counters["mean_path_m"] = r.meanPathLength;
  state.counters["us_per_call"] = r.computeMeanUs;
}
BENCHMARK(BM_Harness)
    ->ArgsProduct({benchmark::CreateDenseRange(0, static_cast<int>(std::size(kPlanners)) - 1, 1),
                   {0, 1, 2, 3}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

// The arc clearance as it was before 2026-11-25: whether a point lies within the swept sector by
// the atan2 of its angle from the start (kept here as the reference of the benchmark).
double arcClearanceAtan2(const Pose2& start, Twist t, double duration, std::span<const Vec2> pts,
                         double radius, double cap) {
  double best = cap + radius;
  const Vec2 a = start.position();
  const Vec2 h = start.heading();
  if (std::abs(t.omega) < 1e-6) {
    const Vec2 end = a + h * (t.v * duration);
    for (const Vec2& p : pts) {
      const Vec2 ab = end - a;
      const double l2 = ab.squaredNorm();
      const double s = l2 > 0.0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
      best = std::min(best, fastDistance(a + ab * s, p));
    }
    return std::min(best - radius, cap);
  }
  const double Rs = t.v / t.omega;
  const Vec2 c = a + h.perp() * Rs;
  const double R = std::abs(Rs);
  const Vec2 r0 = a - c;
  const double sweep = std::abs(t.omega) * duration;
  const double sgn = t.omega > 0.0 ? 1.0 : -1.0;
  const double ang = t.omega * duration;
  const Vec2 end =
      c + Vec2{r0.x * std::cos(ang) - r0.y * std::sin(ang), r0.x * std::sin(ang) + r0.y * std::cos(ang)};
  for (const Vec2& p : pts) {
    const Vec2 rp = p - c;
    const double dist_c = std::sqrt(rp.squaredNorm());
    const double far = std::abs(dist_c - R);
    if (far >= best)
      continue;  // (the library skips such points the same way, by squared distances)
    double delta = sgn * std::atan2(r0.cross(rp), r0.dot(rp));
    if (delta < 0.0)
      delta += 2.0 * kPi;
    const double d =
        sweep >= 2.0 * kPi || delta <= sweep ? far : std::min(fastDistance(a, p), fastDistance(end, p));
    best = std::min(best, d);
  }
  return std::min(best - radius, cap);
}

// One DWA window's rollouts (20 x 20 twists over 1.7 s) against 300 points around the robot, the
// shape of the agent's view in an aisle (map faces within 2 m plus a scan).
void BM_ArcClearance(benchmark::State& state) {
  const bool reference = state.range(0) == 1;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Vec2> pts(300);
  for (auto& p : pts) {
    p = {u(rng), u(rng)};
  }
  const Pose2 start{0.0, 0.0, 0.3};
  double sum = 0.0;
  for (auto _ : state) {
    for (int a = 0; a < 20; ++a) {
      for (int b = 0; b < 20; ++b) {
        const Twist t{0.05 * a, -1.5 + 0.15 * b + 1e-3};
        sum += reference ? arcClearanceAtan2(start, t, 1.7, pts, 0.3, 1.0)
                         : arcClearance(start, t, 1.7, pts, 0.3, 1.0);
      }
    }
  }
  benchmark::DoNotOptimize(sum);
  state.SetLabel(reference ? "atan2 sector test (before)" : "cross-product sector test (library)");
}
BENCHMARK(BM_ArcClearance)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

}  // namespace
BENCHMARK_MAIN();
