#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "fleet/core/angles.hpp"
#include "fleet/sim/world.hpp"
#include "sim_fixtures.hpp"

using namespace fleet;
using namespace fleet::sim;

namespace {

// Distance from p along angle a to the inside of the axis-aligned box [x0, x1] x [y0, y1] (p inside).
double toBox(Vec2 p, double a, double x0, double x1, double y0, double y1) {
  const double c = std::cos(a);
  const double s = std::sin(a);
  double t = 1e300;
  if (c > 1e-12)
    t = std::min(t, (x1 - p.x) / c);
  if (c < -1e-12)
    t = std::min(t, (x0 - p.x) / c);
  if (s > 1e-12)
    t = std::min(t, (y1 - p.y) / s);
  if (s < -1e-12)
    t = std::min(t, (y0 - p.y) / s);
  return t;
}

}  // namespace

TEST(Sensors, ScanOfEmptyRoomMatchesBoxGeometry) {
  auto j = test::room(20, 16);  // inside free space [0.5, 9.5] x [0.5, 7.5]
  j["robot_defaults"]["sensors"]["range_max"] = 20.0;
  j["robots"] = {{{"id", "r"}, {"start", {3.3, 2.7, 0.4}}}};
  World w(test::parse(j));
  const auto r = w.scan(0);
  ASSERT_EQ(r.size(), 72U);
  for (std::size_t k = 0; k < r.size(); ++k) {
    const double a = 0.4 - kPi + 2.0 * kPi / 72.0 * static_cast<double>(k);
    EXPECT_NEAR(r[k], toBox({3.3, 2.7}, a, 0.5, 9.5, 0.5, 7.5), 1e-4) << k;
  }
}

TEST(Sensors, ScanSeesOtherBodiesLikeBruteForceRayDiscIntersection) {
  auto j = test::room(60, 60);
  j["robot_defaults"]["sensors"]["range_max"] = 8.0;
  j["robot_defaults"]["sensors"]["rays"] = 360;
  j["robot_fleet"] = {{"count", 40}, {"area", {2.0, 2.0, 28.0, 28.0}}, {"spacing", 3.1}};
  j["humans"] = {{"count", 40}};
  World w(test::parse(j));
  for (int k = 0; k < 5; ++k) {
    w.advance();
  }
  // Brute force: every body, every ray, then the wall distance from the box.
  std::vector<std::pair<Vec2, double>> bodies;
  for (std::size_t i = 0; i < w.robots().size(); ++i) {
    bodies.emplace_back(w.robots()[i].pose.position(), w.scenario().robots[i].radius);
  }
  for (const auto& h : w.humans()) {
    bodies.emplace_back(h.p, h.r);
  }
  for (std::size_t ri = 0; ri < w.robots().size(); ri += 7) {
    const auto scan = w.scan(ri);
    const Pose2 pose = w.robots()[ri].pose;
    for (std::size_t k = 0; k < scan.size(); ++k) {
      const double a = pose.theta - kPi + 2.0 * kPi / 360.0 * static_cast<double>(k);
      double best = std::min(8.0, toBox(pose.position(), a, 0.5, 29.5, 0.5, 29.5));
      const Vec2 u{std::cos(a), std::sin(a)};
      for (std::size_t b = 0; b < bodies.size(); ++b) {
        if (b == ri)
          continue;
        const Vec2 d = bodies[b].first - pose.position();
        const double proj = d.dot(u);
        const double perp2 = d.squaredNorm() - proj * proj;
        const double r2 = bodies[b].second * bodies[b].second;
        if (proj > 0 && perp2 <= r2)
          best = std::min(best, proj - std::sqrt(r2 - perp2));
      }
      EXPECT_NEAR(scan[k], best, 1e-4) << "robot " << ri << " ray " << k;
    }
  }
}

TEST(Sensors, NoiseFreeFrameHasOdometryCompassLandmarksDetections) {
  auto j = test::room(40, 20);
  j["landmarks"] = {{{"id", 1}, {"position", {8.0, 2.5}}}, {{"id", 2}, {"position", {15.0, 2.5}}}};
  auto& rows = j["map"]["rows"];
  std::string s =
      rows[14].get<std::string>();  // wall cell between the robot and landmark 2 (row 14 = y 2.5..3)
  s[24] = '@';
  s[23] = '@';
  rows[14] = s;
  rows[15] = s;
  j["robots"] = {{{"id", "a"}, {"start", {2.0, 2.5, 0.3}}}, {{"id", "b"}, {"start", {5.0, 4.5, 0.0}}}};
  World w(test::parse(j));
  for (int k = 0; k < 10; ++k) {
    w.command("a", 0.5, 0.0);
    w.advance();
  }
  const auto f = w.sensorFrame(0);
  const auto& r = w.robots()[0];
  // Straight drive: both wheels report the true distance.
  EXPECT_NEAR(f.dsLeft, r.distance, 1e-9);
  EXPECT_NEAR(f.dsRight, r.distance, 1e-9);
  EXPECT_TRUE(f.compassValid);
  EXPECT_NEAR(f.compass, r.pose.theta, 1e-12);
  ASSERT_EQ(f.landmarks.size(), 1U);  // landmark 2 is behind the wall
  EXPECT_EQ(f.landmarks[0].first, 1);
  EXPECT_NEAR(f.landmarks[0].second, wrapAngle(std::atan2(2.5 - r.pose.y, 8.0 - r.pose.x) - r.pose.theta),
              1e-6);
  ASSERT_EQ(f.detections.size(), 1U);
  const Vec2 local = r.pose.inverse().transform({5.0, 4.5});
  EXPECT_FALSE(f.detections[0].human);
  EXPECT_NEAR(f.detections[0].x, local.x, 1e-5);
  EXPECT_NEAR(f.detections[0].y, local.y, 1e-5);
  // Accumulators reset after a frame.
  const auto g = w.sensorFrame(0);
  EXPECT_EQ(g.dsLeft, 0.0);
  EXPECT_EQ(g.seq, f.seq + 1);
}

TEST(Sensors, NoiseHasTheConfiguredSpread) {
  auto j = test::room(40, 20);
  j["robot_defaults"]["sensors"]["compass_sigma"] = 0.05;
  j["robot_defaults"]["noise"]["odom_sigma"] = 0.1;
  j["robots"] = {{{"id", "a"}, {"start", {2.0, 2.5, 0.0}}}};
  World w(test::parse(j));
  double sum = 0.0;
  double sum2 = 0.0;
  const int n = 4000;
  for (int k = 0; k < n; ++k) {
    const double e = w.sensorFrame(0).compass;
    sum += e;
    sum2 += e * e;
  }
  const double mean = sum / n;
  EXPECT_NEAR(mean, 0.0, 0.005);
  EXPECT_NEAR(std::sqrt(sum2 / n - mean * mean), 0.05, 0.005);
}

TEST(Sensors, FramesFollowTheConfiguredRate) {
  auto j = test::room(40, 20);
  j["robot_defaults"]["sensors"]["rate_hz"] = 5.0;  // every other 0.1 s step
  j["robots"] = {{{"id", "a"}, {"start", {2.0, 2.5, 0.0}}}};
  World w(test::parse(j));
  int frames = 0;
  for (int k = 0; k < 10; ++k) {
    frames += static_cast<int>(w.sensorFrames().size());
    w.advance();
  }
  EXPECT_EQ(frames, 5);
}
