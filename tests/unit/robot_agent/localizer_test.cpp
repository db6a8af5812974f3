// The localizer alone: readings in, the pose estimate, the scan and detections in the map frame,
// the people tracked from reading to reading, and the stream watch out.

#include "localizer.hpp"
#include "room_scan.hpp"

#include <gtest/gtest.h>

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <random>

#include "fleet/core/angles.hpp"

using namespace fleet;
using agent::Localizer;
using agent::SeenKind;
using agent::SensorReading;
using agent::StreamCheck;

namespace {

constexpr std::int64_t kTick = 100'000'000;  // 0.1 s

agent::LocalizerParams params(Pose2 start = {1.0, 1.0, 0.0}) {
  agent::LocalizerParams p;
  p.start = start;
  p.wheelBase = 0.4;
  p.sensorTimeoutS = 0.5;
  return p;
}

// Straight ahead at `v` for one tick, as the driver reports it.
SensorReading straight(std::int64_t stampNs, double v) {
  SensorReading r;
  r.stampNs = stampNs;
  r.dsLeft = v * 0.1;
  r.dsRight = v * 0.1;
  r.rangeMax = 8.0f;
  return r;
}

}  // namespace

TEST(Localizer, DeadReckonsTheWheelTravel) {
  Localizer loc(params());
  for (int k = 1; k <= 10; ++k) {
    loc.onReading(straight(k * kTick, 0.5));
  }
  EXPECT_NEAR(loc.pose().x, 1.5, 1e-9);
  EXPECT_NEAR(loc.pose().y, 1.0, 1e-9);
  EXPECT_EQ(loc.perception().pose, loc.pose()) << "the perception is as of the latest estimate";
  EXPECT_EQ(loc.rejected(), 0u);
}

TEST(Localizer, WheelTotalsKeepTheMotionOfLostReadings) {
  Localizer loc(params());
  double total = 0.0;
  for (int k = 1; k <= 30; ++k) {
    total += 0.05;  // 0.5 m/s
    auto r = straight(k * kTick, 0.5);
    r.wheelTotalsValid = true;
    r.wheelLeftTotal = total;
    r.wheelRightTotal = total;
    if (k < 10 || k > 20) {  // readings 10..20 are lost on the way
      loc.onReading(r);
    }
  }
  EXPECT_NEAR(loc.pose().x, 2.5, 1e-9) << "1.5 m driven, 0.55 m of it unseen";
}

// A robot resumed from the pose file with the driver's wheel totals: whatever it rolled after its
// process stopped comes from the first reading's totals, so its start can be certain (a start as
// uncertain as a roll it cannot see let a line match a shelf face one row off).
TEST(Localizer, ResumedWithItsWheelTotalsTheRollSinceIsKnown) {
  auto p = params({4.0, 2.0, 0.0});
  p.startWheels = agent::WheelTotals{100.0, 100.0};
  p.startVarianceXY = agent::kResumeWheelsVarianceXY;
  p.startVarianceTheta = agent::kResumeWheelsVarianceTheta;
  Localizer loc(p);
  auto r = straight(50 * kTick, 0.0);  // a second process's first reading: its own increment 0
  r.wheelTotalsValid = true;
  r.wheelLeftTotal = 100.9;  // rolled 0.9 m while no process watched it
  r.wheelRightTotal = 100.9;
  loc.onReading(r);
  EXPECT_NEAR(loc.pose().x, 4.9, 1e-9);
  EXPECT_NEAR(loc.pose().y, 2.0, 1e-9);
  EXPECT_LT(loc.covariance()(0, 0), 0.02);
  EXPECT_FALSE(loc.resumeTotalsRefused());
  ASSERT_TRUE(loc.wheelTotals());
  EXPECT_EQ(loc.wheelTotals()->left, 100.9) << "kept for the next pose written";
}

TEST(Localizer, KeptTotalsThatDoNotFitAreRefusedAndTheStartIsUncertain) {
  for (const double total : {0.3, 102.5, 97.0}) {  // the driver restarted; rolls no robot makes
    auto p = params({4.0, 2.0, 0.0});
    p.startWheels = agent::WheelTotals{100.0, 100.0};
    p.startVarianceXY = agent::kResumeWheelsVarianceXY;
    Localizer loc(p);
    auto r = straight(kTick, 0.1);  // the driver's increment: 1 cm
    r.wheelTotalsValid = true;
    r.wheelLeftTotal = total;
    r.wheelRightTotal = total;
    loc.onReading(r);
    EXPECT_TRUE(loc.resumeTotalsRefused()) << total;
    EXPECT_NEAR(loc.pose().x, 4.01, 1e-9) << total << ": the increment, not the totals' difference";
    EXPECT_GE(loc.covariance()(0, 0), agent::kResumeVarianceXY) << total;
    EXPECT_GE(loc.covariance()(2, 2), agent::kResumeVarianceTheta) << total;
    ASSERT_TRUE(loc.wheelTotals());
    EXPECT_EQ(loc.wheelTotals()->left, total) << "counted from this reading on";
  }
  // A first reading without totals leaves the roll unknown too.
  auto p = params({4.0, 2.0, 0.0});
  p.startWheels = agent::WheelTotals{100.0, 100.0};
  Localizer loc(p);
  loc.onReading(straight(kTick, 0.1));
  EXPECT_TRUE(loc.resumeTotalsRefused());
  EXPECT_FALSE(loc.wheelTotals());
}

// Totals that would fit as a roll but come from another run of the driver (it restarted while the
// agent was down and has driven 0.4 m since): the driver's session tells them apart, where the
// roll check alone would have taken 0.4 − 0.1 m as the motion since.
TEST(Localizer, KeptTotalsOfAnotherDriverRunAreRefusedEvenWhenTheyFitAsARoll) {
  for (const std::uint64_t session : {std::uint64_t{7}, std::uint64_t{8}}) {
    auto p = params({4.0, 2.0, 0.0});
    p.startWheels = agent::WheelTotals{0.1, 0.1, 7};
    p.startVarianceXY = agent::kResumeWheelsVarianceXY;
    p.startVarianceTheta = agent::kResumeWheelsVarianceTheta;
    Localizer loc(p);
    auto r = straight(kTick, 0.1);  // the driver's increment: 1 cm
    r.wheelTotalsValid = true;
    r.wheelLeftTotal = 0.4;
    r.wheelRightTotal = 0.4;
    r.driverSession = session;
    loc.onReading(r);
    ASSERT_TRUE(loc.wheelTotals());
    EXPECT_EQ(loc.wheelTotals()->session, session) << "kept for the next pose written";
    if (session == 7) {  // the same run: a 0.3 m roll, taken
      EXPECT_FALSE(loc.resumeTotalsRefused());
      EXPECT_NEAR(loc.pose().x, 4.3, 1e-9);
      EXPECT_LT(loc.covariance()(0, 0), 0.02);
    } else {  // another run: the roll since is unknown
      EXPECT_TRUE(loc.resumeTotalsRefused());
      EXPECT_NEAR(loc.pose().x, 4.01, 1e-9) << "the increment, not the totals' difference";
      EXPECT_GE(loc.covariance()(0, 0), agent::kResumeVarianceXY);
    }
    EXPECT_EQ(loc.driverRestarts(), 0U) << "a resume is no restart under a running agent";
  }
}

// The driver restarts under a running agent and counts from zero again: the totals' difference
// (−3.95 m here, under the odometry's 10 m plausibility bound) is no motion. The reading's own
// increment is.
TEST(Localizer, ADriverRestartedUnderARunningAgentIsNoJump) {
  Localizer loc(params());
  double total = 0.0;
  for (int k = 1; k <= 80; ++k) {
    total += 0.05;
    auto r = straight(k * kTick, 0.5);
    r.wheelTotalsValid = true;
    r.wheelLeftTotal = total;
    r.wheelRightTotal = total;
    r.driverSession = 5;
    loc.onReading(r);
  }
  ASSERT_NEAR(loc.pose().x, 5.0, 1e-9);
  auto r = straight(81 * kTick, 0.5);  // the new run's first reading: 5 cm since it started
  r.wheelTotalsValid = true;
  r.wheelLeftTotal = 0.05;
  r.wheelRightTotal = 0.05;
  r.driverSession = 6;
  loc.onReading(r);
  EXPECT_NEAR(loc.pose().x, 5.05, 1e-9);
  EXPECT_EQ(loc.driverRestarts(), 1U);
  r = straight(82 * kTick, 0.5);
  r.wheelTotalsValid = true;
  r.wheelLeftTotal = r.wheelRightTotal = 0.10;
  r.driverSession = 6;
  loc.onReading(r);
  EXPECT_NEAR(loc.pose().x, 5.10, 1e-9) << "the new run's totals from then on";
  EXPECT_EQ(loc.driverRestarts(), 1U);
  r = straight(83 * kTick, 0.5);  // a driver that told a session and now tells none: another run
  r.wheelTotalsValid = true;
  r.wheelLeftTotal = r.wheelRightTotal = 0.05;
  r.driverSession = 0;
  loc.onReading(r);
  EXPECT_NEAR(loc.pose().x, 5.15, 1e-9);
  EXPECT_EQ(loc.driverRestarts(), 2U);
  EXPECT_EQ(loc.rejected(), 0U);
}

TEST(Localizer, WithoutTotalsAGapWidensTheCovariance) {
  Localizer loc(params());
  loc.onReading(straight(kTick, 0.5));
  const double before = loc.covariance()(0, 0);
  loc.onReading(straight(2 * kTick, 0.5));
  const double afterShortGap = loc.covariance()(0, 0);
  loc.onReading(straight(12 * kTick, 0.5));  // 1 s without a reading
  EXPECT_LT(afterShortGap - before, 0.01);
  EXPECT_GT(loc.covariance()(0, 0) - afterShortGap, 0.5) << "(0.8·0.5 + 0.8²/2)² ≈ 0.52 added";
}

TEST(Localizer, ScanAndDetectionsInTheMapFrame) {
  Localizer loc(params({1.0, 1.0, M_PI / 2}));
  EXPECT_FALSE(loc.perception().valid);
  EXPECT_TRUE(loc.perception().scanPoints(10.0).empty());
  SensorReading r;
  r.stampNs = kTick;
  r.angleMin = 0.0f;
  r.angleIncrement = static_cast<float>(M_PI / 2);
  r.rangeMax = 8.0f;
  r.ranges = {2.0f, 8.0f, 1.0f, 4.0f};  // ahead, left (no return), behind, right
  r.sightings = {{SeenKind::kRobot, 1.0f, 0.5f, 0.3f}};
  loc.onReading(r);
  const auto& seen = loc.perception();
  ASSERT_TRUE(seen.valid);
  ASSERT_EQ(seen.scan.size(), 3u);
  EXPECT_NEAR(seen.scan[0].map.x, 1.0, 1e-6);
  EXPECT_NEAR(seen.scan[0].map.y, 3.0, 1e-6);
  EXPECT_NEAR(seen.scan[0].local.x, 2.0, 1e-6);
  EXPECT_NEAR(seen.scan[1].map.y, 0.0, 1e-6);
  EXPECT_NEAR(seen.scan[2].map.x, 5.0, 1e-6);
  EXPECT_EQ(seen.scanPoints(3.0).size(), 2u) << "the point 4 m off is beyond 3 m";
  ASSERT_EQ(seen.detections.size(), 1u);
  EXPECT_NEAR(seen.detections[0].map.x, 0.5, 1e-6);
  EXPECT_NEAR(seen.detections[0].map.y, 2.0, 1e-6);
  EXPECT_NEAR(seen.detections[0].radius, 0.3, 1e-6);
  EXPECT_TRUE(seen.people.empty()) << "a robot is no person";
}

TEST(Localizer, TracksAPersonForAVelocity) {
  Localizer loc(params());
  for (int k = 1; k <= 3; ++k) {
    auto r = straight(k * kTick, 0.0);
    r.sightings = {{SeenKind::kHuman, 2.0f, static_cast<float>(-1.0 + 0.1 * k), 0.25f},
                   {SeenKind::kHuman, NAN, 0.0f, 0.25f}};
    loc.onReading(r);
  }
  const auto& people = loc.perception().people;
  ASSERT_EQ(people.size(), 1u) << "a detection without a position is dropped";
  EXPECT_NEAR(people[0].pos.x, 3.0, 1e-6);
  // 1 m/s walked; smoothed half and half from 0: 0.5, then 0.75.
  EXPECT_NEAR(people[0].velocity.y, 0.75, 1e-5);
  EXPECT_NEAR(people[0].velocity.x, 0.0, 1e-9);
}

TEST(Localizer, TheStreamIsLostAfterTheTimeoutAndBackWithTheNextReading) {
  Localizer loc(params());
  std::int64_t now = 0;
  loc.onReading(straight(now, 0.0));
  EXPECT_EQ(loc.checkStream(now).change, StreamCheck::Change::kNone);
  // No readings: 0.5 s is within the timeout, 0.6 s is not.
  for (int k = 1; k <= 5; ++k) {
    const auto c = loc.checkStream(now + k * kTick);
    EXPECT_FALSE(c.lost) << k;
  }
  const auto lost = loc.checkStream(now + 6 * kTick);
  EXPECT_TRUE(lost.lost);
  EXPECT_EQ(lost.change, StreamCheck::Change::kLost);
  EXPECT_NEAR(lost.silentS, 0.6, 1e-9);
  EXPECT_TRUE(loc.lost());
  EXPECT_EQ(loc.checkStream(now + 7 * kTick).change, StreamCheck::Change::kNone) << "said once";
  loc.onReading(straight(now + 20 * kTick, 0.0));
  const auto back = loc.checkStream(now + 20 * kTick);
  EXPECT_FALSE(back.lost);
  EXPECT_EQ(back.change, StreamCheck::Change::kBack);
  EXPECT_EQ(back.outageNs, 14 * kTick);
  EXPECT_FALSE(loc.lost());
}

TEST(Localizer, ARobotThatNeverGetsAReadingIsLostToo) {
  Localizer loc(params());
  EXPECT_FALSE(loc.checkStream(0).lost) << "the first check starts the count";
  EXPECT_TRUE(loc.checkStream(6 * kTick).lost);
}

// ---- Laser lines matched to the site's walls (seed 003 §3.1.2) ----

namespace {

// A 6 × 4 m room, its inner faces looking in.
std::shared_ptr<const std::vector<estimation::MapSegment>> room(Vec2 shift = {}) {
  auto w = std::make_shared<std::vector<estimation::MapSegment>>();
  const Vec2 s = shift;
  w->push_back({Vec2{0, 0} + s, Vec2{6, 0} + s, {0, 1}});
  w->push_back({Vec2{0, 4} + s, Vec2{6, 4} + s, {0, -1}});
  w->push_back({Vec2{0, 0} + s, Vec2{0, 4} + s, {1, 0}});
  w->push_back({Vec2{6, 0} + s, Vec2{6, 4} + s, {-1, 0}});
  return w;
}

// The simulator's scanner (72 rays over 360° from -π, 8 m, a miss reads 8 m exactly) in the room,
// from the true pose.
SensorReading scanFrom(const Pose2& truth, std::int64_t stampNs) {
  SensorReading r = straight(stampNs, 0.0);
  r.angleMin = static_cast<float>(-kPi);
  r.angleIncrement = static_cast<float>(fleet::test::kRoomRayStep);
  r.rangeMax = 8.0f;
  r.ranges = fleet::test::roomRanges(truth, 6.0, 4.0);
  return r;
}

agent::LocalizerParams withWalls(Pose2 start, bool lines = true, Vec2 shift = {}) {
  auto p = params(start);
  p.walls = room(shift);
  p.lineUpdates = lines;
  return p;
}

}  // namespace

TEST(LocalizerLines, UpdatesRunInTheThesisOrderOdometryCompassLinesBearings) {
  const Pose2 truth{2.0, 1.5, 0.3};
  auto p = withWalls(truth);
  p.landmarks = {{7, {5.0, 3.0}}};
  Localizer loc(p);
  SensorReading r = scanFrom(truth, kTick);
  r.compassValid = true;
  r.compass = 0.3;
  r.bearings = {{7, static_cast<float>(std::atan2(1.5, 3.0) - 0.3)}};
  loc.onReading(r);
  const auto& u = loc.lastUpdates();
  ASSERT_GE(u.size(), 5u) << "odometry, compass, >= 2 lines, the bearing";
  EXPECT_EQ(u.front(), agent::Update::kOdometry);
  EXPECT_EQ(u[1], agent::Update::kCompass);
  for (std::size_t i = 2; i + 1 < u.size(); ++i) {
    EXPECT_EQ(u[i], agent::Update::kLine) << "update " << i;
  }
  EXPECT_EQ(u.back(), agent::Update::kBearing);
  EXPECT_EQ(loc.lineStats().accepted, u.size() - 3);
}

TEST(LocalizerLines, WallsPullADriftedEstimateBackAndWithoutLinesItStaysOff) {
  const Pose2 truth{2.0, 1.5, 0.0};
  const Pose2 start{2.15, 1.4, 0.0};  // 18 cm off, inside the start covariance (σ 0.1 m)
  Localizer with(withWalls(start));
  Localizer without(withWalls(start, false));
  for (int k = 1; k <= 10; ++k) {
    with.onReading(scanFrom(truth, k * kTick));
    without.onReading(scanFrom(truth, k * kTick));
  }
  EXPECT_LT(distance(with.pose(), truth), 0.01);
  EXPECT_GT(with.lineStats().accepted, 20u);
  EXPECT_NEAR(distance(without.pose(), truth), distance(start, truth), 1e-9);
  EXPECT_EQ(without.lineStats().scans, 0u) << "line updates off: scans are not even looked at";
}

TEST(LocalizerLines, AScanWithoutLinesAndWallsThatMatchNothingAreSkippedWithAReason) {
  const Pose2 truth{2.0, 1.5, 0.0};
  // No return at all (open space beyond 8 m): no line.
  Localizer empty(withWalls(truth));
  SensorReading open = straight(kTick, 0.5);
  open.angleMin = static_cast<float>(-kPi);
  open.angleIncrement = static_cast<float>(2.0 * kPi / 72.0);
  open.ranges.assign(72, 8.0f);
  empty.onReading(open);
  empty.onReading(straight(2 * kTick, 0.5));  // and one with no scan: not counted as a scan
  EXPECT_EQ(empty.lineStats().scans, 1u);
  EXPECT_EQ(empty.lineStats().scansNoLines, 1u);
  EXPECT_NEAR(empty.pose().x, 2.1, 1e-9) << "the estimator keeps dead reckoning";
  // The map is 3 m off the room the scanner is in: every line is outside the gate or looks at
  // walls from behind; nothing is fused and the estimate stays where odometry has it.
  Localizer shifted(withWalls(truth, true, {3.0, 0.0}));
  shifted.onReading(scanFrom(truth, kTick));
  const auto& s = shifted.lineStats();
  EXPECT_GT(s.extracted, 0u);
  EXPECT_EQ(s.matched, 0u);
  EXPECT_EQ(s.outsideGate + s.noOverlap + s.ambiguous + s.noWallFacing, s.extracted);
  EXPECT_EQ(shifted.pose(), truth);
}

namespace {

// One malformed reading: stamps anywhere (backwards, huge jumps, the int64 extremes), wheel
// increments and totals from small to absurd to NaN/inf, the compass present or not and possibly
// garbage, bearings to unknown ids or NaN, scans of garbage ranges.
SensorReading malformed(std::mt19937_64& rng, std::int64_t& stamp) {
  auto pick = [&](int n) { return static_cast<int>(rng() % static_cast<std::uint64_t>(n)); };
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double inf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  auto value = [&](double scale) {
    switch (pick(8)) {
      case 0:
        return nan;
      case 1:
        return pick(2) ? inf : -inf;
      case 2:
        return unit(rng) * 1e300;
      case 3:
        return unit(rng) * 1e6;
      default:
        return unit(rng) * scale;
    }
  };
  switch (pick(6)) {
    case 0:
      stamp -= static_cast<std::int64_t>(rng() % 10'000'000'000ULL);  // backwards
      break;
    case 1:
      stamp += static_cast<std::int64_t>(rng() % 100'000'000'000ULL);  // a jump of up to 100 s
      break;
    case 2:
      stamp = pick(2) ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
      break;
    default:
      stamp += kTick;
  }
  SensorReading r;
  r.stampNs = stamp;
  r.dsLeft = value(0.1);
  r.dsRight = value(0.1);
  r.wheelTotalsValid = pick(3) == 0;
  r.wheelLeftTotal = value(100.0);
  r.wheelRightTotal = value(100.0);
  r.compassValid = pick(2) == 0;
  r.compass = value(kPi);
  for (int k = pick(3); k > 0; --k) {
    r.bearings.emplace_back(pick(4), static_cast<float>(value(kPi)));
  }
  if (pick(2) == 0) {
    r.angleMin = static_cast<float>(-kPi);
    r.angleIncrement = static_cast<float>(2.0 * kPi / 72.0);
    r.rangeMax = 8.0f;
    for (int i = 0; i < 72; ++i) {
      r.ranges.push_back(static_cast<float>(pick(4) == 0 ? value(8.0) : 2.0 + std::abs(unit(rng))));
    }
  }
  return r;
}

}  // namespace

// Property: whatever the readings, the covariance stays finite, symmetric, positive semi-definite
// and under the EKF's ceilings, and the pose stays finite. (Once, after mixed malformed samples, a
// robot's position sigma reached 2,889 m and its pose left the map.)
TEST(LocalizerProperty, MalformedReadingsKeepTheCovarianceBoundedAndThePoseFinite) {
  const estimation::EkfParams ceilings;
  for (std::uint64_t seed = 1; seed <= 40; ++seed) {
    SCOPED_TRACE(seed);
    std::mt19937_64 rng(seed);
    auto p = withWalls({3.0, 2.0, 0.3});
    p.landmarks = {{1, {0.0, 0.0}}, {2, {6.0, 4.0}}};
    Localizer loc(p);
    std::int64_t stamp = 0;
    for (int k = 0; k < 500; ++k) {
      loc.onReading(malformed(rng, stamp));
      const Eigen::Matrix3d& P = loc.covariance();
      ASSERT_TRUE(P.allFinite()) << "reading " << k;
      ASSERT_TRUE(P.isApprox(P.transpose(), 1e-12) || (P - P.transpose()).cwiseAbs().maxCoeff() < 1e-9)
          << "reading " << k;
      ASSERT_LE(P(0, 0), ceilings.maxPositionVariance) << "reading " << k;
      ASSERT_LE(P(1, 1), ceilings.maxPositionVariance) << "reading " << k;
      ASSERT_LE(P(2, 2), ceilings.maxHeadingVariance) << "reading " << k;
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(P);
      ASSERT_GE(eig.eigenvalues().minCoeff(), -1e-9 * std::max(1.0, P.diagonal().maxCoeff()))
          << "reading " << k;
      ASSERT_TRUE(loc.pose().isFinite()) << "reading " << k;
    }
  }
}

// The path of the 2,889 m sigma: absurd wheel increments (a driver reporting its odometer, a
// total that jumped) were accepted, each adding ds² of heading uncertainty to the position.
TEST(LocalizerProperty, AbsurdWheelIncrementsAreRefusedAndRepeatedGapsStopAtTheCeiling) {
  Localizer loc(params());
  auto r = straight(kTick, 0.0);
  r.dsLeft = 1e6;
  r.dsRight = -1e6;
  loc.onReading(r);
  EXPECT_EQ(loc.rejected(), 1u);
  EXPECT_NEAR(loc.pose().x, 1.0, 1e-12);
  EXPECT_LT(loc.covariance()(0, 0), 0.02);
  // Readings 10 s apart without wheel totals: each widens by the timeout's worth, up to the ceiling.
  for (int k = 2; k < 20000; ++k) {
    loc.onReading(straight(k * 100 * kTick, 0.0));
  }
  EXPECT_LE(loc.covariance()(0, 0), estimation::EkfParams{}.maxPositionVariance);
  EXPECT_LE(loc.covariance()(2, 2), estimation::EkfParams{}.maxHeadingVariance);
}
