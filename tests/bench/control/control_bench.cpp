// Cost of the robot's estimation and control step: the EKF cycle of seed 003 (odometry prediction +
// compass + landmark bearings + laser lines matched against a line map) and the pose controller / path
// follower step. Inputs come from the square-drive simulator so the filter works on realistic data.

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <vector>

#include "fleet/control/lyapunov_pose_controller.hpp"
#include "fleet/control/path_follower.hpp"
#include "fleet/estimation/line_extraction.hpp"
#include "fleet/estimation/pose_ekf.hpp"
#include "square_drive_sim.hpp"

using namespace fleet;
using namespace fleet::estimation;

namespace {

const sim::Log& driveLog() {
  static const sim::Log log = sim::squareDrive(7, 1);
  return log;
}

PoseEkf freshEkf(const sim::Log& log) {
  return PoseEkf::create(EkfParams{}, log.start_estimate, log.P0).value();
}

/// The room's 4 walls plus `extra` far-away lines that never match but must be considered by matching.
std::vector<MapLine> mapWithDistractors(int extra) {
  std::vector<MapLine> map = sim::roomMap();
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> ang(-kPi, kPi);
  std::uniform_real_distribution<double> dist(8.0, 30.0);
  for (int i = 0; i < extra; ++i) {
    map.push_back({dist(rng), ang(rng)});
  }
  return map;
}

void addPercentiles(benchmark::State& state, std::vector<double>& ns) {
  if (ns.empty()) {
    return;
  }
  std::sort(ns.begin(), ns.end());
  state.counters["p50_ns"] = ns[ns.size() / 2];
  state.counters["p99_ns"] = ns[std::min(ns.size() - 1, ns.size() * 99 / 100)];
}

}  // namespace

static void BM_EkfPredict(benchmark::State& state) {
  const sim::Log& log = driveLog();
  PoseEkf ekf = freshEkf(log);
  std::size_t k = 0;
  for (auto _ : state) {
    const sim::Step& st = log.steps[k];
    benchmark::DoNotOptimize(ekf.predict(st.ds_left, st.ds_right));
    k = (k + 1) % log.steps.size();
  }
}
BENCHMARK(BM_EkfPredict);

static void BM_EkfCompassUpdate(benchmark::State& state) {
  const sim::Log& log = driveLog();
  PoseEkf ekf = freshEkf(log);
  std::size_t k = 0;
  for (auto _ : state) {
    const sim::Step& st = log.steps[k];
    ekf.predict(st.ds_left, st.ds_right);  // keeps P from collapsing; measured separately above
    benchmark::DoNotOptimize(ekf.updateCompass(st.compass));
    k = (k + 1) % log.steps.size();
  }
  state.SetLabel("includes one predict");
}
BENCHMARK(BM_EkfCompassUpdate);

/// One full cycle as the agent runs it at 10 Hz: predict, compass, 2 landmark bearings and every
/// visible line (2–3) matched against a map of 4 walls + range(0) distractor lines, every step
/// (worst case: all sensors arrive in the same cycle).
static void BM_EkfFullCycle(benchmark::State& state) {
  const sim::Log& log = driveLog();
  const std::vector<MapLine> map = mapWithDistractors(static_cast<int>(state.range(0)));
  // Every step gets a scan and a camera frame: reuse the nearest ones in the log.
  std::vector<std::vector<LineObservation>> scans(log.steps.size());
  std::vector<std::vector<sim::LandmarkReading>> frames(log.steps.size());
  std::vector<LineObservation> last_scan;
  std::vector<sim::LandmarkReading> last_frame;
  for (std::size_t k = 0; k < log.steps.size(); ++k) {
    if (!log.steps[k].lines.empty()) {
      last_scan = log.steps[k].lines;
    }
    if (!log.steps[k].bearings.empty()) {
      last_frame = log.steps[k].bearings;
    }
    scans[k] = last_scan;
    frames[k] = last_frame;
  }
  PoseEkf ekf = freshEkf(log);
  std::vector<double> ns;
  ns.reserve(1 << 20);
  std::size_t k = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const sim::Step& st = log.steps[k];
    ekf.predict(st.ds_left, st.ds_right);
    ekf.updateCompass(st.compass);
    for (const sim::LandmarkReading& b : frames[k]) {
      ekf.updateBearing(b.landmark, b.bearing);
    }
    benchmark::DoNotOptimize(ekf.updateLines(map, scans[k]));
    const auto t1 = std::chrono::steady_clock::now();
    if (ns.size() < ns.capacity()) {
      ns.push_back(
          static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()));
    }
    if (++k == log.steps.size()) {
      k = 0;
      state.PauseTiming();
      ekf = freshEkf(log);
      state.ResumeTiming();
    }
  }
  state.counters["map_lines"] = static_cast<double>(map.size());
  addPercentiles(state, ns);
}
BENCHMARK(BM_EkfFullCycle)->Arg(0)->Arg(12)->Arg(60)->Arg(252);

static void BM_PoseControllerStep(benchmark::State& state) {
  control::LyapunovParams p;
  p.law = state.range(0) == 0 ? control::PoseLaw::kSingleLaw : control::PoseLaw::kTwoRegion;
  control::LyapunovPoseController ctl(p);
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(-3.0, 3.0);
  std::vector<Pose2> poses(4096);
  for (Pose2& q : poses) {
    q = {u(rng), u(rng), wrapAngle(u(rng))};
  }
  const Pose2 goal{0.0, 0.0, 0.3};
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ctl.step(poses[k], goal));
    k = (k + 1) & 4095u;
  }
  state.SetLabel(state.range(0) == 0 ? "single law" : "two-region");
}
BENCHMARK(BM_PoseControllerStep)->Arg(0)->Arg(1);

/// Path follower step on a zig-zag path of range(0) waypoints (the robot walks along it), to show the
/// projection cost is bounded by the search window, not the path length.
static void BM_PathFollowerStep(benchmark::State& state) {
  const auto n = static_cast<int>(state.range(0));
  std::vector<Vec2> pts;
  for (int i = 0; i < n; ++i) {
    pts.push_back({0.5 * i, (i % 2 == 0) ? 0.0 : 0.2});
  }
  control::PathFollower f;
  if (!f.setPath(pts, 0.0)) {
    state.SkipWithError("setPath failed");
    return;
  }
  std::vector<Pose2> poses;
  for (int i = 0; i < 4096; ++i) {
    const double x = 0.5 * (n - 1) * i / 4096.0;
    poses.push_back({x, 0.05, 0.1});
  }
  std::size_t k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(f.step(poses[k]));
    if (++k == poses.size()) {
      k = 0;
      state.PauseTiming();
      (void)f.setPath(pts, 0.0);
      state.ResumeTiming();
    }
  }
}
BENCHMARK(BM_PathFollowerStep)->Arg(10)->Arg(100)->Arg(1000)->Arg(10000);

/// EKF full cycle + two-region controller step: the estimation/control share of the local stack.
static void BM_EkfPlusControllerCycle(benchmark::State& state) {
  const sim::Log& log = driveLog();
  const std::vector<MapLine> map = sim::roomMap();
  PoseEkf ekf = freshEkf(log);
  control::LyapunovPoseController ctl;
  const Pose2 goal{1.0, 1.0, 0.0};
  std::vector<double> ns;
  ns.reserve(1 << 20);
  std::size_t k = 0;
  for (auto _ : state) {
    const auto t0 = std::chrono::steady_clock::now();
    const sim::Step& st = log.steps[k];
    ekf.predict(st.ds_left, st.ds_right);
    ekf.updateCompass(st.compass);
    for (const sim::LandmarkReading& b : st.bearings) {
      ekf.updateBearing(b.landmark, b.bearing);
    }
    if (!st.lines.empty()) {
      ekf.updateLines(map, st.lines);
    }
    benchmark::DoNotOptimize(ctl.step(ekf.pose(), goal));
    const auto t1 = std::chrono::steady_clock::now();
    if (ns.size() < ns.capacity()) {
      ns.push_back(
          static_cast<double>(std::chrono::duration_cast<std::chrono::nanoseconds>(t1 - t0).count()));
    }
    if (++k == log.steps.size()) {
      k = 0;
      state.PauseTiming();
      ekf = freshEkf(log);
      state.ResumeTiming();
    }
  }
  state.SetLabel("sensors at their own rates (10/3.3/2 Hz)");
  addPercentiles(state, ns);
}
BENCHMARK(BM_EkfPlusControllerCycle);

/// Line extraction from one 180° / 0.5° scan (361 beams) of a room corner seen from inside a 4-wall room
/// (the thesis's MATLAB version took 150–250 ms for 360 points).
static void BM_LineExtraction(benchmark::State& state) {
  LaserScan scan;
  scan.angle_min = -kPi / 2;
  scan.angle_increment = kPi / 360;
  const std::vector<MapLine> room = sim::roomMap();
  const Pose2 pose{0.4, -0.3, 0.5};
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.01);
  for (int i = 0; i <= 360; ++i) {
    const double a = pose.theta + scan.angle_min + i * scan.angle_increment;
    double best = 100.0;
    for (const MapLine& w : room) {
      const double den = std::cos(a) * std::cos(w.beta) + std::sin(a) * std::sin(w.beta);
      if (std::abs(den) < 1e-9) {
        continue;
      }
      const double t = (w.rho - pose.x * std::cos(w.beta) - pose.y * std::sin(w.beta)) / den;
      if (t > 0.0 && t < best) {
        best = t;
      }
    }
    scan.ranges.push_back(best + noise(rng));
  }
  std::size_t lines = 0;
  for (auto _ : state) {
    const auto out = extractLines(scan);
    lines = out.size();
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["lines"] = static_cast<double>(lines);
  state.counters["beams"] = static_cast<double>(scan.ranges.size());
}
BENCHMARK(BM_LineExtraction);

BENCHMARK_MAIN();
