#include "motion_gate.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "map_faces.hpp"

namespace fleet::agent {
namespace {

/// m/s past a static point the route leads away from (see clearSpeed): slow enough for the
/// cross-traffic check to stop the robot should its arc turn towards the point after all.
constexpr double kCreepSpeed = 0.15;
constexpr double kInf = std::numeric_limits<double>::infinity();

/// Distance from `p` to the polyline `route`.
double distanceToRoute(const std::vector<Vec2>& route, Vec2 p) {
  double best = route.empty() ? std::numeric_limits<double>::infinity() : distance(route.front(), p);
  for (std::size_t i = 0; i + 1 < route.size(); ++i) {
    const Vec2 a = route[i];
    const Vec2 ab = route[i + 1] - a;
    const double len2 = ab.squaredNorm();
    const double t = len2 > 1e-18 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, distance(a + ab * t, p));
  }
  return best;
}

}  // namespace

MotionGate::Clearance MotionGate::clearSpeed(const GateView& view, double v, Blocker& blocker) const {
  Clearance c;
  c.speed = v;
  if (!view.seen.valid || v <= 0.0) {
    return c;
  }
  double allowed = v;
  // Docking at a station next to a shelf or wall: the last few decimetres are driven slowly, so
  // static points may come closer than the cruising stop gap (else the robot stalls short of it).
  const double staticGap = view.docking ? 0.08 : p_.stopGap;
  const double robotGap = p_.robotStopGap >= 0.0 ? p_.robotStopGap : p_.stopGap;
  // A range reading on a robot's body (one detected, or one that reports itself there) keeps the
  // robot gap: the laser sees robots as it sees shelves.
  auto onRobot = [&](Vec2 at) {
    for (const auto& d : view.seen.detections) {
      if (d.kind == SeenKind::kRobot && distance(d.map, at) < d.radius + 0.08) {
        return true;
      }
    }
    for (const auto& o : view.others) {
      if (distance(o.pos, at) < p_.radius + 0.08) {
        return true;
      }
    }
    return false;
  };
  auto limit = [&](double gap, double keep) {
    allowed = std::min(allowed, std::max(0.0, (gap - keep) / p_.headway));
  };
  for (const auto& d : view.seen.detections) {
    const double x = d.local.x;
    const double y = d.local.y;
    const double r = d.radius;
    if (x <= 0.0 || std::abs(y) > p_.radius + r + 0.05) {
      continue;  // not in the corridor the robot sweeps
    }
    const double gap = std::hypot(x, y) - p_.radius - r;
    const double before = allowed;
    limit(gap, d.kind == SeenKind::kRobot ? robotGap : p_.stopGap);
    if (allowed < before) {
      c.blockPoint = d.map;
    }
    if (allowed < before && allowed < 0.05) {
      blocker.robot = d.kind == SeenKind::kRobot;
      blocker.id = blocker.robot ? "robot" : "human";
      if (blocker.robot) {
        // Name the robot: the known robot nearest to where the detection is.
        const Vec2 at = d.map;
        double best = 1.0;
        for (const auto& o : view.others) {
          if (distance(o.pos, at) < best) {
            best = distance(o.pos, at);
            blocker.id = o.id;
          }
        }
      }
    }
  }
  // Range readings: every point that lies in the corridor the robot sweeps ahead limits the speed
  // (with a route: the corridor along the route, the gap measured straight to the point). A point
  // The route leads away from (it comes no nearer to the route than to the robot now) only slows
  // The robot to a creep while it is within the gap: held, a robot stood 595 s on a parking place's
  // approach node 0.035 m beyond the disc from a shelf corner, its route on along the corner (100
  // robots); not slowed, the arc a local planner drives may still swing into it (a
  // shelf touched in an earlier run, docs/algorithms.md "The gate beside a shelf corner").
  const double corridor = p_.radius + 0.05;
  for (const auto& ray : view.seen.scan) {
    const double ahead = ray.local.x;
    if (ahead <= 0.0) {
      continue;
    }
    const bool straight = std::abs(ray.local.y) < corridor;
    const double toRoute = view.route ? distanceToRoute(*view.route, ray.map) : 0.0;
    if (view.route ? toRoute >= corridor : !straight) {
      continue;
    }
    const double before = allowed;
    const double keep = robotGap < staticGap && onRobot(ray.map) ? robotGap : staticGap;
    const double gap = (straight ? ahead : ray.local.norm()) - p_.radius;
    if (view.route && toRoute >= ray.local.norm() - 0.01) {
      if (gap < keep) {
        allowed = std::min(allowed, kCreepSpeed);
      }
    } else {
      limit(gap, keep);
    }
    if (allowed < before) {
      c.blockPoint = ray.map;
    }
  }
  c.speed = allowed;
  return c;
}

bool MotionGate::rearClear(const GateView& view) const {
  if (!view.seen.valid) {
    return false;
  }
  const double keep = p_.radius + 0.25;
  for (const auto& d : view.seen.detections) {
    const double x = d.local.x;
    const double y = d.local.y;
    if (x < 0.0 && std::abs(y) < p_.radius + d.radius + 0.05 && -x - d.radius < keep) {
      return false;
    }
  }
  for (const auto& ray : view.seen.scan) {
    const double ahead = ray.local.x;
    if (ahead < 0.0 && std::abs(ray.local.y) < p_.radius + 0.05 && -ahead < keep) {
      return false;
    }
  }
  return true;
}

bool MotionGate::crossTrafficSafe(const GateView& view, double& v, double& w, std::string& blocker) const {
  const Pose2 pose = view.seen.pose;
  std::vector<avoidance::MovingDisc> discs;
  // Only what is ahead or beside: whoever comes from behind keeps the distance (its own stop rule
  // does); counting it here froze whole queues, each robot held by the one closing in behind it.
  // (Driving backwards, "ahead" is behind: a robot reversing onto its parking place backed into
  // A person standing behind it, whom this check ignored.)
  const Vec2 heading = Vec2{std::cos(pose.theta), std::sin(pose.theta)} * (v < 0.0 ? -1.0 : 1.0);
  auto relevant = [&](Vec2 at) {
    const Vec2 rel = at - pose.position();
    return rel.norm() < 3.0 && rel.dot(heading) > -p_.radius;
  };
  for (const auto& o : view.others) {
    if (relevant(o.pos)) {
      discs.push_back({o.pos, o.velocity, p_.radius});
    }
  }
  for (const auto& h : view.seen.people) {
    if (relevant(h.pos)) {
      discs.push_back({h.pos, h.velocity, h.radius});
    }
  }
  avoidance::LocalView local;
  local.robot = {pose, view.current, p_.radius};
  local.discs = discs;
  local.limits = p_.limits;
  local.dt = 0.1;
  auto passes = [&](const avoidance::SafetyResult& r) {
    return !r.blocked && !(r.overruled && std::abs(r.twist.v) < 0.05 && std::abs(v) > 0.1);
  };
  const auto r = discs.empty() ? avoidance::SafetyResult{{v, w}} : safety_.filter(local, {v, w});
  if (passes(r)) {
    v = r.twist.v;
    w = r.twist.omega;
    // Then the scan: a shelf corner beside the straight corridor of the stop rule is still in the
    // way of a curving robot (one brushed a corner in a 100-robot run). A stop for it is static.
    // (The map's obstacle faces too: a shelf corner between two rays is there all the same.)
    std::vector<Vec2> scan = view.seen.scanPoints(1.5);
    const std::vector<Vec2> walls = mapFaces(view.map, pose.position(), 1.0);
    scan.insert(scan.end(), walls.begin(), walls.end());
    if (scan.empty() || view.docking) {
      return true;  // (docking: the stop rule's docking gap governs the last decimetres)
    }
    local.scan = scan;
    const auto s = safety_.filter(local, {v, w});
    v = s.twist.v;
    w = s.twist.omega;
    if (passes(s)) {
      return true;
    }
    blocker.clear();
    return false;
  }
  // Name the robot in the way: the nearest one ahead.
  double best = 1e9;
  for (const auto& o : view.others) {
    const Vec2 rel = o.pos - pose.position();
    const double ahead = rel.x * std::cos(pose.theta) + rel.y * std::sin(pose.theta);
    if (ahead > 0.0 && rel.norm() < best) {
      best = rel.norm();
      blocker = o.id;
    }
  }
  for (const auto& h : view.seen.people) {
    if (distance(h.pos, pose.position()) < best) {
      best = distance(h.pos, pose.position());
      blocker = "human";
    }
  }
  v = r.twist.v;
  w = r.twist.omega;
  return false;
}

double MotionGate::zoneSpeed(const GateView& view, double v) const {
  if (!p_.speedLimit) {
    return std::numeric_limits<double>::infinity();
  }
  const Pose2& at = view.seen.pose;
  const double ahead = std::max(p_.radius, std::abs(v) * p_.headway);
  return std::min(p_.speedLimit(at.position()),
                  p_.speedLimit(at.position() + at.heading() * (v < 0.0 ? -ahead : ahead)));
}

double MotionGate::besidePeopleSpeed(const GateView& view) const {
  double speed = kInf;
  if (!view.seen.valid) {
    return speed;
  }
  const Pose2 toRobot = view.seen.pose.inverse();
  for (const auto& h : view.seen.people) {
    const Vec2 at = toRobot.transform(h.pos);
    const double side = std::abs(at.y) - p_.radius - h.radius;
    if (at.x <= -p_.radius || side > p_.personSideGap) {
      continue;  // behind the robot, or far enough beside its way
    }
    const double along = at.x - h.radius - p_.radius;  // from the robot's front to the person
    speed = std::min(speed, std::max(p_.nearPersonSpeed, along / p_.headway));
  }
  return speed;
}

MotionGate::Hold MotionGate::heldUp(const GateView& view, double& v, double& w, Blocker& blocker) const {
  if (const double limit = std::min(zoneSpeed(view, v), v > 0.0 ? besidePeopleSpeed(view) : kInf);
      std::abs(v) > limit) {
    const double scaled = std::max(0.0, limit) * (v < 0.0 ? -1.0 : 1.0);
    w *= std::abs(v) > 1e-9 ? scaled / v : 1.0;
    v = scaled;
  }
  const Clearance clear = clearSpeed(view, v, blocker);
  const double allowed = clear.speed;
  if (allowed < v - 1e-9) {
    // Keep the curvature while slowing, so the robot stays on its path. Not while docking: there
    // The turn toward the station is what frees the robot from the wall that limits its speed.
    if (std::abs(v) > 1e-9 && !view.docking) {
      w *= allowed / v;
    }
    v = allowed;
  }
  if (v < 0.0 && !rearClear(view)) {
    v = 0.0;  // the stop rule for reversing (the pose law backs onto a station it faces away from)
  }
  std::string crossing;
  const bool crossOk = crossTrafficSafe(view, v, w, crossing);
  if (!crossOk && allowed >= 0.05) {
    blocker.robot = !crossing.empty() && crossing != "human";
    blocker.id = crossing;  // empty: a static obstacle
  }
  return {allowed < 0.05 || !crossOk, clear.blockPoint};
}

}  // namespace fleet::agent
