#pragma once

// Simulated square drive in a walled room with the seed-003 sensor noise levels; shared by the fusion
// tests and the control benchmark. Every sensor reading is generated once per seed, so the filter
// configurations compared on a seed see exactly the same data.

#include <cmath>
#include <cstddef>
#include <optional>
#include <random>
#include <vector>

#include "fleet/core/angles.hpp"
#include "fleet/estimation/measurement_models.hpp"
#include "fleet/estimation/pose_ekf.hpp"

namespace fleet::estimation::sim {

struct SensorSetup {
  double wheelBase = 0.6;
  double delta = 0.0003;          // eq. 3.9
  double compass_var = 2.79e-4;   // §3.2
  double bearing_var = 2.992e-4;  // §3.4
  double line_var_r = 1e-4;       // Table 3.1, typical
  double line_var_psi = 1.68e-3;  // Table 3.1, segment 5
  int laser_every = 3;            // 100 ms odometry/compass, ~3.3 Hz lines, 2 Hz camera
  int camera_every = 5;
};

/// Room 5 × 5 m around a 2 × 2 m square (corners (0,0), (2,0), (2,2), (0,2)).
inline std::vector<MapLine> roomMap() {
  return {{3.5, 0.0}, {3.5, kPi / 2}, {1.5, kPi}, {1.5, -kPi / 2}};
}
inline std::vector<Vec2> landmarks() {
  return {{3.0, 3.0}, {-1.0, 2.5}};
}

struct LandmarkReading {
  Vec2 landmark;
  double bearing;
};

struct Step {
  Pose2 truth;  // after this step's motion
  double ds_left;
  double ds_right;
  double compass;
  std::vector<LineObservation> lines;     // empty unless a laser scan arrived
  std::vector<LandmarkReading> bearings;  // empty unless a camera frame arrived
};

struct Log {
  Pose2 start_truth;
  Pose2 start_estimate;
  Eigen::Matrix3d P0;
  std::vector<Step> steps;
};

/// `laps` laps counter-clockwise: 2 m sides at 0.3 m/s, 90° turns in place at 0.5 rad/s, Δt = 0.1 s.
inline Log squareDrive(unsigned seed, int laps, const SensorSetup& s = {}) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n01(0.0, 1.0);
  Log log;
  log.P0 = Eigen::Vector3d(1e-4, 1e-4, 1e-4).asDiagonal();
  log.start_truth = Pose2{0.0, 0.0, 0.0};
  log.start_estimate = Pose2{0.01 * n01(rng), 0.01 * n01(rng), 0.01 * n01(rng)};  // drawn from P0

  struct Motion {
    double dl;
    double dr;
  };
  std::vector<Motion> plan;
  const int straight_steps = static_cast<int>(std::lround(2.0 / 0.03));
  const int turn_steps = static_cast<int>(std::ceil((kPi / 2) / 0.05));
  const double wheel_turn = (kPi / 2) / turn_steps * s.wheelBase / 2;
  for (int lap = 0; lap < laps; ++lap) {
    for (int side = 0; side < 4; ++side) {
      for (int i = 0; i < straight_steps; ++i) {
        plan.push_back({0.03, 0.03});
      }
      for (int i = 0; i < turn_steps; ++i) {
        plan.push_back({-wheel_turn, wheel_turn});
      }
    }
  }
  const std::vector<MapLine> map = roomMap();
  const std::vector<Vec2> lms = landmarks();
  Pose2 truth = log.start_truth;
  int k = 0;
  for (const Motion& m : plan) {
    ++k;
    Step st{};
    truth = odometryModel(truth, m.dl, m.dr, s.wheelBase).pose;
    st.truth = truth;
    st.ds_left = m.dl + std::sqrt(s.delta * std::abs(m.dl)) * n01(rng);
    st.ds_right = m.dr + std::sqrt(s.delta * std::abs(m.dr)) * n01(rng);
    st.compass = wrapAngle(truth.theta + std::sqrt(s.compass_var) * n01(rng));
    if (k % s.laser_every == 0) {
      for (const MapLine& line : map) {
        const LinePrediction p = predictLine(truth, line);
        if (std::cos(p.psi) > -0.1) {  // 180° scanner: walls behind it are not seen
          st.lines.push_back({p.r + std::sqrt(s.line_var_r) * n01(rng),
                              wrapAngle(p.psi + std::sqrt(s.line_var_psi) * n01(rng)), s.line_var_r,
                              s.line_var_psi});
        }
      }
    }
    if (k % s.camera_every == 0) {
      for (const Vec2 lm : lms) {
        st.bearings.push_back(
            {lm, wrapAngle(predictBearing(truth, lm).gamma + std::sqrt(s.bearing_var) * n01(rng))});
      }
    }
    log.steps.push_back(std::move(st));
  }
  return log;
}

enum class Config { kOdometry, kCompass, kLaser, kCamera };  // each adds to the previous

/// Runs the filter over a log; calls `each(step, ekf)` after every step's updates.
template <class F>
void runFilter(const Log& log, Config config, F&& each, const SensorSetup& s = {}) {
  EkfParams params;
  params.wheelBase = s.wheelBase;
  params.delta = s.delta;
  params.compassVariance = s.compass_var;
  params.bearingVariance = s.bearing_var;
  PoseEkf ekf = PoseEkf::create(params, log.start_estimate, log.P0).value();
  const std::vector<MapLine> map = roomMap();
  for (const Step& st : log.steps) {
    ekf.predict(st.ds_left, st.ds_right);
    if (config >= Config::kCompass) {
      ekf.updateCompass(st.compass);
    }
    if (config >= Config::kLaser && !st.lines.empty()) {
      ekf.updateLines(map, st.lines);
    }
    if (config >= Config::kCamera) {
      for (const LandmarkReading& b : st.bearings) {
        ekf.updateBearing(b.landmark, b.bearing);
      }
    }
    each(st, ekf);
  }
}

}  // namespace fleet::estimation::sim
