#include "fleet/sim/world.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include "fleet/core/angles.hpp"
#include "fleet/geometry/grid_raycast.hpp"
#include "world_math.hpp"

namespace fleet::sim {

using world_detail::len;
using world_detail::normal;

void World::scanInto(std::size_t ri, std::vector<float>& out) const {
  const SensorSpec& s = sc_.robots[ri].sensors;
  const Pose2 pose = robots_[ri].pose;
  const int n = s.rays;
  out.assign(static_cast<std::size_t>(n), static_cast<float>(s.rangeMax));
  if (n == 0) {
    return;
  }
  const bool full = s.fov >= 2.0 * kPi - 1e-9;
  const double inc = n > 1 ? (full ? s.fov / n : s.fov / (n - 1)) : 0.0;
  const double amin = full ? -kPi : -0.5 * s.fov;
  const geometry::GridView view = sc_.map.view();
  std::vector<double> best(static_cast<std::size_t>(n));
  std::vector<Vec2> dirs(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    const double a = pose.theta + amin + k * inc;
    dirs[static_cast<std::size_t>(k)] = {std::cos(a), std::sin(a)};
  }
  for (int k = 0; k < n; ++k) {
    const auto hit = geometry::raycastGrid(view, pose.position(), pose.theta + amin + k * inc, s.rangeMax);
    best[static_cast<std::size_t>(k)] = hit.hit ? hit.range : s.rangeMax;
  }
  // Other bodies: only the rays inside each disc's angular extent are intersected.
  const Vec2 o = pose.position();
  hash_.forEachNear(o, s.rangeMax + maxRadius_, [&](int j) {
    const auto ju = static_cast<std::size_t>(j);
    if (ju == ri) {
      return;
    }
    const Vec2 d = positions_[ju] - o;
    const double dist = len(d);
    const double rj = radii_[ju];
    if (dist <= rj || dist - rj >= s.rangeMax) {
      return;
    }
    const double half = std::asin(rj / dist);
    const double bearing = wrapAngle(std::atan2(d.y, d.x) - pose.theta);
    const int k0 = static_cast<int>(std::ceil((bearing - half - amin) / inc));
    const int k1 = static_cast<int>(std::floor((bearing + half - amin) / inc));
    for (int kk = k0; kk <= k1; ++kk) {
      int k = kk;
      if (full) {
        k = ((k % n) + n) % n;
      } else if (k < 0 || k >= n) {
        continue;
      }
      const Vec2 u = dirs[static_cast<std::size_t>(k)];
      const double proj = d.dot(u);
      const double perp2 = dist * dist - proj * proj;
      if (proj <= 0.0 || perp2 > rj * rj) {
        continue;
      }
      const double t = proj - std::sqrt(rj * rj - perp2);
      double& b = best[static_cast<std::size_t>(k)];
      b = std::min(b, t);
    }
  });
  for (int k = 0; k < n; ++k) {
    out[static_cast<std::size_t>(k)] = static_cast<float>(best[static_cast<std::size_t>(k)]);
  }
}

std::vector<float> World::scan(std::size_t robot) const {
  std::vector<float> out;
  scanInto(robot, out);
  return out;
}

SensorReading World::sensorFrame(std::size_t i, bool withScan) {
  RobotBody& r = robots_[i];
  const RobotSpec& spec = sc_.robots[i];
  const SensorSpec& s = spec.sensors;
  SensorReading f;
  f.robot = i;
  f.seq = r.frameSeq++;
  f.dsLeft = r.odomLeft;
  f.dsRight = r.odomRight;
  f.wheelLeftTotal = r.odomLeftTotal;
  f.wheelRightTotal = r.odomRightTotal;
  r.odomLeft = r.odomRight = 0.0;
  const bool full = s.fov >= 2.0 * kPi - 1e-9;
  f.angleMin = static_cast<float>(full ? -kPi : -0.5 * s.fov);
  f.angleIncrement = static_cast<float>(s.rays > 1 ? (full ? s.fov / s.rays : s.fov / (s.rays - 1)) : 0.0);
  f.rangeMax = static_cast<float>(s.rangeMax);
  if (withScan) {
    scanInto(i, f.ranges);
    for (auto& x : f.ranges) {
      if (x < f.rangeMax) {
        x = static_cast<float>(
            std::clamp(static_cast<double>(x) + normal(sensorRng_, s.rangeSigma), 0.0, s.rangeMax));
      }
    }
  }
  if (s.compass) {
    f.compassValid = true;
    f.compass = wrapAngle(r.pose.theta + normal(sensorRng_, s.compassSigma));
  }
  if (s.landmarks) {
    const geometry::GridView view = sc_.map.view();
    for (const auto& lm : sc_.landmarks) {
      const Vec2 d = lm.position - r.pose.position();
      const double dist = d.norm();
      if (dist > s.landmarkRange || f.landmarks.size() >= 64) {
        continue;
      }
      const double a = std::atan2(d.y, d.x);
      const auto hit = geometry::raycastGrid(view, r.pose.position(), a, dist);
      // A landmark mounted on a shelf face is visible when the ray stops at its own cell.
      const bool seen = !hit.hit || hit.range >= dist - 1e-6 ||
                        (hit.cx == sc_.map.cellX(lm.position.x) && hit.cy == sc_.map.cellY(lm.position.y));
      if (seen) {
        f.landmarks.emplace_back(
            lm.id, static_cast<float>(wrapAngle(a - r.pose.theta + normal(sensorRng_, s.bearingSigma))));
      }
    }
  }
  if (s.detections) {
    const Vec2 o = r.pose.position();
    std::vector<int> seen;
    hash_.forEachNear(o, s.detectionRange, [&](int j) {
      if (static_cast<std::size_t>(j) != i &&
          len(o - positions_[static_cast<std::size_t>(j)]) <= s.detectionRange) {
        seen.push_back(j);
      }
    });
    std::sort(seen.begin(), seen.end());
    const double c = std::cos(r.pose.theta);
    const double sn = std::sin(r.pose.theta);
    for (int j : seen) {
      if (f.detections.size() >= 256) {
        break;
      }
      const auto ju = static_cast<std::size_t>(j);
      const Vec2 d = positions_[ju] - o;
      const Vec2 local{c * d.x + sn * d.y, -sn * d.x + c * d.y};  // into the robot frame
      f.detections.push_back(
          {ju >= robots_.size(), static_cast<float>(local.x + normal(sensorRng_, s.rangeSigma)),
           static_cast<float>(local.y + normal(sensorRng_, s.rangeSigma)), static_cast<float>(radii_[ju])});
    }
  }
  f.battery = static_cast<float>(r.battery);
  f.charging = r.charging;
  return f;
}

std::vector<SensorReading> World::sensorFrames(bool withScan) {
  std::vector<SensorReading> out;
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    if (step_ % sensorEvery_[i] == 0) {
      out.push_back(sensorFrame(i, withScan));
    }
  }
  return out;
}

}  // namespace fleet::sim
