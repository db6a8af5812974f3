#include "localizer.hpp"

#include "fleet/validation/sample_checks.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/core/clock.hpp"

namespace fleet::agent {
namespace {

estimation::PoseEkf makeEkf(const LocalizerParams& p) {
  estimation::EkfParams ep;
  ep.wheelBase = p.wheelBase;
  ep.compassVariance = 0.02 * 0.02;
  ep.bearingVariance = 0.01 * 0.01;
  Eigen::Matrix3d p0 = Eigen::Matrix3d::Zero();
  p0.diagonal() << p.startVarianceXY, p.startVarianceXY, p.startVarianceTheta;
  auto e = estimation::PoseEkf::create(ep, p.start, p0);
  return std::move(*e);  // parameters are constants above: cannot fail
}

}  // namespace

estimation::LineExtractionParams agentLineExtraction() {
  estimation::LineExtractionParams p;
  p.seedPoints = 4;
  p.minPoints = 5;
  p.minLength = 0.5;
  // Rays 5° apart land 0.35 m apart at 4 m and further on a wall seen at a slant; a cross aisle
  // (1.5 m and more) still ends a run.
  p.maxPointGap = 0.75;
  p.pointSigma = 0.01;
  return p;
}

std::vector<Vec2> Perception::scanPoints(double maxRange) const {
  std::vector<Vec2> pts;
  for (const auto& ray : scan) {
    if (ray.range < maxRange) {
      pts.push_back(ray.map);
    }
  }
  return pts;
}

Localizer::Localizer(LocalizerParams params) : p_(std::move(params)), ekf_(makeEkf(p_)) {
  seen_.pose = ekf_.pose();
  if (p_.startWheels) {
    haveTotals_ = true;
    wheelLeft_ = p_.startWheels->left;
    wheelRight_ = p_.startWheels->right;
    session_ = p_.startWheels->session;
    checkResumeRoll_ = true;
  }
}

std::optional<WheelTotals> Localizer::wheelTotals() const {
  if (!haveTotals_) {
    return std::nullopt;
  }
  return WheelTotals{wheelLeft_, wheelRight_, session_};
}

bool Localizer::plausible() const {
  const Pose2 p = ekf_.pose();
  return p.isFinite() && std::abs(p.x) <= validation::kMaxCoordinate &&
         std::abs(p.y) <= validation::kMaxCoordinate && ekf_.covariance().allFinite();
}

void Localizer::onReading(const SensorReading& f) {
  // With the wheel totals the motion since the last reading received is exact, however many were
  // lost in between. Without them (ds* are increments since the previous reading sent), whatever
  // the robot moved while none arrived is missing from the estimate: after a gap longer than the
  // sensor timeout (the robot kept its last command that long, then braked) widen the covariance
  // by that much, so the landmark bearings, which the Mahalanobis gate would otherwise reject as
  // outliers, can pull the estimate back.
  double dsLeft = f.dsLeft;
  double dsRight = f.dsRight;
  const bool totals =
      f.wheelTotalsValid && std::isfinite(f.wheelLeftTotal) && std::isfinite(f.wheelRightTotal);
  // Totals of another run of the driver (it restarted and counts from zero): their difference to
  // the last is no motion (up to 10 m of it passed the odometry's plausibility check as a jump).
  // A driver that told a session and now tells another (or none) is not the run it was.
  const bool otherRun = totals && session_ != 0 && f.driverSession != session_;
  if (otherRun && !checkResumeRoll_) {
    ++driverRestarts_;
    haveTotals_ = false;
  }
  if (totals && haveTotals_) {
    dsLeft = f.wheelLeftTotal - wheelLeft_;
    dsRight = f.wheelRightTotal - wheelRight_;
  }
  if (checkResumeRoll_) {
    checkResumeRoll_ = false;
    // Totals kept over a restart: only a roll a robot makes after its process stopped is believed.
    // Anything else (the driver counts from zero again: another session, or totals that moved by
    // more than a roll when the driver tells none) leaves the motion since unknown.
    if (!totals || otherRun ||
        !(std::abs(dsLeft) <= kResumeRollMaxM && std::abs(dsRight) <= kResumeRollMaxM)) {
      resumeTotalsRefused_ = true;
      haveTotals_ = false;
      dsLeft = f.dsLeft;
      dsRight = f.dsRight;
      Eigen::Matrix3d wide = ekf_.covariance();
      wide(0, 0) = std::max(wide(0, 0), kResumeVarianceXY);
      wide(1, 1) = std::max(wide(1, 1), kResumeVarianceXY);
      wide(2, 2) = std::max(wide(2, 2), kResumeVarianceTheta);
      (void)ekf_.reset(ekf_.pose(), wide);
    }
  }
  if (totals) {
    wheelLeft_ = f.wheelLeftTotal;
    wheelRight_ = f.wheelRightTotal;
    session_ = f.driverSession;
  }
  const bool motionKnown = totals && haveTotals_;
  haveTotals_ = totals;
  // The stamps are the driver's (any value, backwards or far ahead): the gap in double cannot
  // overflow as the int64 difference could, and the widening counts at most the timeout.
  const double gapS = (static_cast<double>(f.stampNs) - static_cast<double>(lastStampNs_)) * 1e-9;
  if (!motionKnown && seen_.valid && gapS > p_.sensorTimeoutS) {
    const double t = std::min(gapS, p_.sensorTimeoutS);
    const double d = p_.vMax * t + p_.vMax * p_.vMax / (2.0 * p_.accelMax);
    const double a = p_.wMax * t + p_.wMax * p_.wMax / (2.0 * p_.alphaMax);
    Eigen::Matrix3d widened = ekf_.covariance();
    widened += Eigen::Vector3d(d * d, d * d, a * a).asDiagonal();
    (void)ekf_.reset(ekf_.pose(), widened);
  }
  // Seed 003's order (eq. 3.33's z = [φ, r_1, ψ_1, …, r_N, ψ_N, γ] and Table 3.3's rows): odometry,
  // compass, laser lines, camera bearings. The compass first makes the heading good before the lines
  // are matched, since a heading error turns every predicted line about the robot.
  updates_.clear();
  updates_.push_back(Update::kOdometry);
  if (ekf_.predict(dsLeft, dsRight) != estimation::UpdateStatus::kAccepted) {
    ++rejected_;
  }
  if (f.compassValid) {
    updates_.push_back(Update::kCompass);
    if (ekf_.updateCompass(f.compass) != estimation::UpdateStatus::kAccepted) {
      ++rejected_;
    }
  }
  updateLines(f);
  for (const auto& [seenId, bearing] : f.bearings) {
    for (const auto& [id, pos] : p_.landmarks) {
      if (id != seenId) {
        continue;
      }
      updates_.push_back(Update::kBearing);
      if (ekf_.updateBearing(pos, static_cast<double>(bearing)) != estimation::UpdateStatus::kAccepted) {
        ++rejected_;
      }
    }
  }
  track(f);
  lastStampNs_ = f.stampNs;
  seen_.valid = true;
  readingSinceCheck_ = true;
}

void Localizer::updateLines(const SensorReading& f) {
  if (!p_.lineUpdates || !p_.walls || p_.walls->empty() || f.ranges.empty()) {
    return;
  }
  estimation::LaserScan scan;
  scan.angle_min = static_cast<double>(f.angleMin);
  scan.angle_increment = static_cast<double>(f.angleIncrement);
  scan.rangeMin = 0.05;
  // A ray without a return reads exactly rangeMax: keep it out of the fits.
  scan.range_max = static_cast<double>(f.rangeMax) - 1e-3;
  scan.ranges.assign(f.ranges.begin(), f.ranges.end());
  std::vector<estimation::ExtractedLine> lines = estimation::extractLines(scan, p_.lines);
  ++lineStats_.scans;
  if (lines.empty()) {
    ++lineStats_.scansNoLines;
    return;
  }
  lineStats_.extracted += lines.size();
  for (auto& l : lines) {
    l.line.varR += p_.lineRangeSigma * p_.lineRangeSigma;
    l.line.varPsi += p_.lineAngleSigma * p_.lineAngleSigma;
  }
  // Matched once against the estimate after the compass; the updates then run one by one, each
  // re-linearised at the estimate the previous one left (and gated again by the filter).
  estimation::LineGate gate = p_.lineGate;
  gate.maxRange = scan.range_max + 1.0;
  const auto m = estimation::matchLines(ekf_.pose(), ekf_.covariance(), *p_.walls, lines, gate);
  lineStats_.noWallFacing += m.noWallFacing;
  lineStats_.outsideGate += m.outsideGate;
  lineStats_.noOverlap += m.noOverlap;
  lineStats_.ambiguous += m.ambiguous;
  for (const auto& match : m.matches) {
    ++lineStats_.matched;
    updates_.push_back(Update::kLine);
    if (ekf_.updateLine(match.line, lines[match.observation].line) == estimation::UpdateStatus::kAccepted) {
      ++lineStats_.accepted;
    } else {
      ++lineStats_.rejectedByFilter;
    }
  }
}

void Localizer::track(const SensorReading& f) {
  // Everything in the map frame as of this reading's estimate (it holds until the next reading).
  const Pose2 pose = ekf_.pose();
  seen_.pose = pose;
  seen_.scan.clear();
  for (std::size_t i = 0; i < f.ranges.size(); ++i) {
    const double range = static_cast<double>(f.ranges[i]);
    if (range < static_cast<double>(f.rangeMax)) {
      const double a =
          static_cast<double>(f.angleMin) + static_cast<double>(i) * static_cast<double>(f.angleIncrement);
      const Vec2 local{range * std::cos(a), range * std::sin(a)};
      seen_.scan.push_back({range, local, pose.transform(local)});
    }
  }
  seen_.detections.clear();
  for (const auto& d : f.sightings) {
    const Vec2 local{static_cast<double>(d.x), static_cast<double>(d.y)};
    seen_.detections.push_back({d.kind, local, static_cast<double>(d.r), pose.transform(local)});
  }
  // Track people from reading to reading (nearest previous detection within 0.5 m) for a velocity.
  std::vector<Person> seen;
  const double dtFrame =
      peopleStampNs_ >= 0 && f.stampNs > peopleStampNs_ ? nsToSec(f.stampNs - peopleStampNs_) : 0.0;
  for (const auto& d : f.sightings) {
    if (d.kind != SeenKind::kHuman || !std::isfinite(d.x) || !std::isfinite(d.y)) {
      continue;
    }
    Person p{pose.transform({static_cast<double>(d.x), static_cast<double>(d.y)}),
             {},
             static_cast<double>(d.r),
             false};
    const Person* prev = nullptr;
    for (const auto& q : seen_.people) {
      if (distance(q.pos, p.pos) < 0.5 &&
          (prev == nullptr || distance(q.pos, p.pos) < distance(prev->pos, p.pos))) {
        prev = &q;
      }
    }
    if (prev != nullptr && dtFrame > 0.0 && dtFrame < 1.0) {
      // Smoothed: detections jitter by a few centimetres per frame.
      p.velocity = prev->velocity * 0.5 + ((p.pos - prev->pos) / dtFrame) * 0.5;
      p.tracked = true;
    }
    seen.push_back(p);
  }
  seen_.people = std::move(seen);
  peopleStampNs_ = f.stampNs;
}

StreamCheck Localizer::checkStream(std::int64_t nowNs) {
  if (readingSinceCheck_ || lastReadingNs_ < 0) {
    lastReadingNs_ = nowNs;
  }
  const bool fresh = readingSinceCheck_;
  readingSinceCheck_ = false;
  StreamCheck c;
  c.lost = !fresh && nsToSec(nowNs - lastReadingNs_) > p_.sensorTimeoutS;
  if (c.lost == lost_) {
    return c;
  }
  lost_ = c.lost;
  if (c.lost) {
    lostSinceNs_ = nowNs;
    c.change = StreamCheck::Change::kLost;
    c.silentS = nsToSec(nowNs - lastReadingNs_);
  } else {
    c.change = StreamCheck::Change::kBack;
    c.outageNs = nowNs - lostSinceNs_;
  }
  return c;
}

}  // namespace fleet::agent
