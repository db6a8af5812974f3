#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "fleet/estimation/pose_ekf.hpp"
#include "square_drive_sim.hpp"

using namespace fleet;
using namespace fleet::estimation;
using namespace fleet::estimation::sim;

namespace {

struct Rmse {
  double x = 0.0;
  double y = 0.0;
  [[nodiscard]] double xy() const { return std::hypot(x, y); }
};

Rmse rmse(Config config, unsigned first_seed, int runs) {
  double sx = 0.0;
  double sy = 0.0;
  std::size_t n = 0;
  for (int r = 0; r < runs; ++r) {
    const Log log = squareDrive(first_seed + static_cast<unsigned>(r), 2);
    runFilter(log, config, [&](const Step& st, const PoseEkf& ekf) {
      sx += std::pow(ekf.pose().x - st.truth.x, 2);
      sy += std::pow(ekf.pose().y - st.truth.y, 2);
      ++n;
    });
  }
  return {std::sqrt(sx / static_cast<double>(n)), std::sqrt(sy / static_cast<double>(n))};
}

/// χ²(k) quantile by the Wilson–Hilferty approximation (accurate to <1 % for k ≥ 30).
double chi2Quantile(double k, double z) {
  const double a = 2.0 / (9.0 * k);
  return k * std::pow(1.0 - a + z * std::sqrt(a), 3);
}

}  // namespace

TEST(FusionSimulation, RmseOrderingOfTable33) {
  // Seed 003 Table 3.3: odometry ≫ +compass > +LRF ≥ +omni camera. Pooled over 10 fixed seeds.
  const Rmse odo = rmse(Config::kOdometry, 100, 10);
  const Rmse compass = rmse(Config::kCompass, 100, 10);
  const Rmse laser = rmse(Config::kLaser, 100, 10);
  const Rmse camera = rmse(Config::kCamera, 100, 10);
  std::printf("RMSE x/y [m]: odometry %.3f/%.3f, +compass %.3f/%.3f, +laser %.4f/%.4f, +camera %.4f/%.4f\n",
              odo.x, odo.y, compass.x, compass.y, laser.x, laser.y, camera.x, camera.y);
  EXPECT_GT(odo.xy(), 3.0 * compass.xy());
  EXPECT_GT(odo.x, compass.x);
  EXPECT_GT(odo.y, compass.y);
  EXPECT_GT(compass.xy(), 2.0 * laser.xy());
  EXPECT_GE(laser.xy(), camera.xy());
}

TEST(FusionSimulation, NeesIsConsistent) {
  // Monte Carlo of N runs: at each step the run-average NEES times N is χ²(3N); it must lie in the 95 %
  // interval at about 95 % of the steps, and the grand mean must be close to 3 (the state dimension;
  // dead reckoning alone runs slightly high, ≈3.45, from the curved "banana" error the EKF linearises).
  constexpr int kRuns = 30;
  for (const Config config : {Config::kOdometry, Config::kCamera}) {
    std::vector<double> sum;
    for (int r = 0; r < kRuns; ++r) {
      const Log log = squareDrive(500 + static_cast<unsigned>(r), 1);
      sum.resize(log.steps.size(), 0.0);
      std::size_t k = 0;
      runFilter(log, config, [&](const Step& st, const PoseEkf& ekf) {
        sum[k++] += normalizedEstimationErrorSquared(st.truth, ekf.pose(), ekf.covariance());
      });
    }
    const double lo = chi2Quantile(3.0 * kRuns, -1.96) / kRuns;
    const double hi = chi2Quantile(3.0 * kRuns, 1.96) / kRuns;
    int inside = 0;
    double grand = 0.0;
    for (const double s : sum) {
      const double avg = s / kRuns;
      inside += (avg >= lo && avg <= hi) ? 1 : 0;
      grand += avg;
    }
    grand /= static_cast<double>(sum.size());
    const double frac = static_cast<double>(inside) / static_cast<double>(sum.size());
    std::printf("config %d: NEES mean %.3f, %.1f %% of steps inside [%.2f, %.2f]\n", static_cast<int>(config),
                grand, 100.0 * frac, lo, hi);
    EXPECT_GT(frac, 0.85) << static_cast<int>(config);
    EXPECT_GT(grand, 2.5) << static_cast<int>(config);
    EXPECT_LT(grand, 3.6) << static_cast<int>(config);
  }
}

TEST(FusionSimulation, CorruptedReadingsDoNotCorruptTheEstimate) {
  // The full filter on a clean log vs the same log with every 7th compass reading NaN, every 11th
  // compass reading 120° off, NaN/inf wheel increments on some steps replaced by nothing, and a
  // spurious line in every scan: the corrupted run is rejected reading by reading and stays as good.
  const Log clean = squareDrive(42, 2);
  Log bad = clean;
  for (std::size_t k = 0; k < bad.steps.size(); ++k) {
    if (k % 7 == 3) {
      bad.steps[k].compass = std::nan("");
    } else if (k % 11 == 5) {
      bad.steps[k].compass = wrapAngle(bad.steps[k].compass + 2.1);
    }
    if (!bad.steps[k].lines.empty()) {
      bad.steps[k].lines.push_back({0.4, 1.0, 1e-4, 1e-3});
    }
    if (!bad.steps[k].bearings.empty() && k % 2 == 0) {
      bad.steps[k].bearings[0].bearing = std::numeric_limits<double>::infinity();
    }
  }
  double clean_err = 0.0;
  double bad_err = 0.0;
  double max_bad = 0.0;
  runFilter(clean, Config::kCamera,
            [&](const Step& st, const PoseEkf& ekf) { clean_err += distance(st.truth, ekf.pose()); });
  EkfStats stats;
  runFilter(bad, Config::kCamera, [&](const Step& st, const PoseEkf& ekf) {
    bad_err += distance(st.truth, ekf.pose());
    max_bad = std::max(max_bad, distance(st.truth, ekf.pose()));
    ASSERT_TRUE(ekf.state().allFinite());
    stats = ekf.stats();
  });
  const auto n = static_cast<double>(clean.steps.size());
  EXPECT_LT(bad_err / n, 1.5 * clean_err / n + 0.005);
  EXPECT_LT(max_bad, 0.1);
  std::size_t nan_compass = 0;
  std::size_t off_compass = 0;
  for (std::size_t k = 0; k < bad.steps.size(); ++k) {
    nan_compass += (k % 7 == 3) ? 1 : 0;
    off_compass += (k % 7 != 3 && k % 11 == 5) ? 1 : 0;
  }
  EXPECT_EQ(stats.compass.rejectedNonFinite, nan_compass);
  EXPECT_GE(stats.compass.rejectedGate, off_compass);
  EXPECT_GT(stats.linesUnmatched, 0u);
  EXPECT_GT(stats.bearing.rejectedNonFinite, 0u);
}
