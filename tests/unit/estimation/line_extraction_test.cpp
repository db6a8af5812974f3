#include "fleet/estimation/line_extraction.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <vector>

#include "fleet/core/angles.hpp"
#include "fleet/estimation/measurement_models.hpp"
#include "fleet/estimation/pose_ekf.hpp"

using namespace fleet;
using namespace fleet::estimation;

namespace {

/// Ray-casts a 180° / 0.5° scan (361 beams, seed 003 §3.1.2) from `pose` against infinite map lines,
/// keeping the nearest hit; beams with no hit within range_max return range_max + 1 (no return).
LaserScan castScan(const Pose2& pose, const std::vector<MapLine>& walls, double sigma, std::mt19937& rng,
                   double range_max = 8.0) {
  LaserScan scan;
  scan.angle_min = -kPi / 2;
  scan.angle_increment = deg2rad(0.5);
  scan.range_max = range_max;
  std::normal_distribution<double> n(0.0, sigma);
  for (int i = 0; i <= 360; ++i) {
    const double a = pose.theta + scan.angle_min + i * scan.angle_increment;
    double best = range_max + 1.0;
    for (const MapLine& w : walls) {
      // Ray p + t·d hits x cos β + y sin β = ρ at t = (ρ − p·nβ)/(d·nβ).
      const double den = std::cos(a) * std::cos(w.beta) + std::sin(a) * std::sin(w.beta);
      if (std::abs(den) < 1e-9) {
        continue;
      }
      const double t = (w.rho - pose.x * std::cos(w.beta) - pose.y * std::sin(w.beta)) / den;
      if (t > 0.0 && t < best) {
        best = t;
      }
    }
    scan.ranges.push_back(best <= range_max ? best + (sigma > 0.0 ? n(rng) : 0.0) : best);
  }
  return scan;
}

}  // namespace

TEST(FitLine, ExactPointsAndErrors) {
  // Points on y = 2 (r = 2, ψ = π/2) and on x + y = 2 (r = √2, ψ = π/4).
  const std::vector<Vec2> horizontal{{-1, 2}, {0, 2}, {1, 2}, {3, 2}};
  const LineFit h = fitLine(horizontal, 0.01).value();
  EXPECT_NEAR(h.r, 2.0, 1e-12);
  EXPECT_NEAR(h.psi, kPi / 2, 1e-12);
  EXPECT_NEAR(h.rmsResidual, 0.0, 1e-9);
  const std::vector<Vec2> diagonal{{2, 0}, {1, 1}, {0, 2}};
  const LineFit d = fitLine(diagonal, 0.01).value();
  EXPECT_NEAR(d.r, std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(d.psi, kPi / 4, 1e-12);
  // Line behind the origin: r stays positive, ψ flips.
  const std::vector<Vec2> behind{{-3, -1}, {-3, 0}, {-3, 1}};
  const LineFit b = fitLine(behind, 0.01).value();
  EXPECT_NEAR(b.r, 3.0, 1e-12);
  EXPECT_NEAR(std::abs(b.psi), kPi, 1e-12);
  EXPECT_FALSE(fitLine(std::vector<Vec2>{{1, 1}}, 0.01).has_value());
  EXPECT_FALSE(fitLine(std::vector<Vec2>{{1, 1}, {1, 1}}, 0.01).has_value());
  EXPECT_FALSE(fitLine(horizontal, 0.0).has_value());
}

TEST(FitLine, CovarianceMatchesMonteCarlo) {
  // Predicted var/cov of (r, ψ) for isotropic point noise vs the spread of 4000 noisy fits.
  std::mt19937 rng(12);
  const double sigma = 0.02;
  std::normal_distribution<double> n(0.0, sigma);
  std::vector<Vec2> truth;
  for (int i = 0; i < 30; ++i) {
    truth.push_back({2.0 + 0.05 * i, 1.0 + 0.05 * i * 0.3});  // off-centre segment: r and ψ correlate
  }
  const LineFit nominal = fitLine(truth, sigma).value();
  double sr = 0, sp = 0, srr = 0, spp = 0, srp = 0;
  const int kTrials = 4000;
  for (int t = 0; t < kTrials; ++t) {
    std::vector<Vec2> pts = truth;
    for (Vec2& p : pts) {
      p += Vec2{n(rng), n(rng)};
    }
    const LineFit f = fitLine(pts, sigma).value();
    const double dr = f.r - nominal.r;
    const double dp = angleDiff(f.psi, nominal.psi);
    sr += dr;
    sp += dp;
    srr += dr * dr;
    spp += dp * dp;
    srp += dr * dp;
  }
  const double N = kTrials;
  const double varR = srr / N - (sr / N) * (sr / N);
  const double var_p = spp / N - (sp / N) * (sp / N);
  const double cov = srp / N - (sr / N) * (sp / N);
  EXPECT_NEAR(varR / nominal.varR, 1.0, 0.1);
  EXPECT_NEAR(var_p / nominal.varPsi, 1.0, 0.1);
  EXPECT_NEAR(cov / nominal.covRPsi, 1.0, 0.15);
  EXPECT_GT(std::abs(nominal.covRPsi) / std::sqrt(nominal.varR * nominal.varPsi), 0.5);
}

TEST(LineExtraction, TwoPerpendicularWalls) {
  // Seed 003 behaviour 8: a 180° / 0.5° scan of two perpendicular walls gives 2 segments with (r, ψ)
  // near the truth. Walls x = 3 (ahead) and y = 2 (left) seen from the origin.
  std::mt19937 rng(1);
  const std::vector<MapLine> walls{{3.0, 0.0}, {2.0, kPi / 2}};
  for (const double sigma : {0.0, 0.01}) {
    const LaserScan scan = castScan(Pose2{}, walls, sigma, rng);
    const std::vector<ExtractedLine> lines = extractLines(scan);
    ASSERT_EQ(lines.size(), 2u) << sigma;
    EXPECT_NEAR(lines[0].line.r, 3.0, 0.01);
    EXPECT_NEAR(lines[0].line.psi, 0.0, deg2rad(0.5));
    EXPECT_NEAR(lines[1].line.r, 2.0, 0.01);
    EXPECT_NEAR(lines[1].line.psi, kPi / 2, deg2rad(0.5));
    // The corner (3, 2) is where one segment ends and the next starts (within a couple of beams).
    EXPECT_LT(distance(lines[0].last, Vec2{3, 2}), 0.15);
    EXPECT_LT(distance(lines[1].first, Vec2{3, 2}), 0.15);
    for (const ExtractedLine& l : lines) {
      EXPECT_GT(l.line.varR, 0.0);
      EXPECT_GT(l.line.varPsi, 0.0);
      EXPECT_GE(l.points, 12u);
    }
  }
}

TEST(LineExtraction, ScatteredPointsAndBadInputGiveNoLines) {
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(1.0, 6.0);
  LaserScan scan;
  scan.angle_min = -kPi / 2;
  scan.angle_increment = deg2rad(0.5);
  for (int i = 0; i <= 360; ++i) {
    scan.ranges.push_back(u(rng));  // clutter
  }
  EXPECT_TRUE(extractLines(scan).empty());
  scan.ranges.assign(361, std::nan(""));
  EXPECT_TRUE(extractLines(scan).empty());
  LineExtractionParams bad;
  bad.seedPoints = 2;
  EXPECT_FALSE(bad.validate().has_value());
  EXPECT_TRUE(extractLines(castScan(Pose2{}, {{3.0, 0.0}}, 0.0, rng), bad).empty());
}

TEST(LineExtraction, ExtractedLinesLocaliseTheRobotThroughTheEkf) {
  // Scan → lines → nearest-neighbour matching → EKF: an estimate 15 cm and 3° off is pulled to the
  // truth in a room of 4 walls.
  std::mt19937 rng(3);
  const std::vector<MapLine> room{{3.5, 0.0}, {3.5, kPi / 2}, {1.5, kPi}, {1.5, -kPi / 2}};
  const Pose2 truth{0.4, -0.3, 0.5};
  Eigen::Matrix3d P0 = Eigen::Vector3d(0.04, 0.04, 0.01).asDiagonal();
  PoseEkf ekf = PoseEkf::create(EkfParams{}, Pose2{0.5, -0.19, 0.55}, P0).value();
  for (int k = 0; k < 5; ++k) {
    const std::vector<ExtractedLine> lines = extractLines(castScan(truth, room, 0.01, rng));
    ASSERT_GE(lines.size(), 2u);
    std::vector<LineObservation> obs;
    for (const ExtractedLine& l : lines) {
      obs.push_back(l.line);
    }
    const LineBatchResult r = ekf.updateLines(room, obs);
    EXPECT_EQ(r.accepted, lines.size());
  }
  EXPECT_LT(distance(ekf.pose(), truth), 0.01);
  EXPECT_LT(std::abs(angleDiff(ekf.pose().theta, truth.theta)), deg2rad(0.3));
}
