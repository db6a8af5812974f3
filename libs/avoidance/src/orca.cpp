#include "fleet/avoidance/orca.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fleet/avoidance/clearance.hpp"
#include "fleet/avoidance/dynamic_window.hpp"
#include "fleet/core/angles.hpp"

namespace fleet::avoidance {

namespace {

constexpr double kEps = 1e-9;

// Planes are handled as directed lines: direction d = normal rotated by −90°, so the permitted
// side is to the left of d (det(d, x − point) ≥ 0).
Vec2 dirOf(const OrcaHalfPlane& h) {
  return {h.normal.y, -h.normal.x};
}

double violation(const OrcaHalfPlane& h, Vec2 x) {
  return -(x - h.point).dot(h.normal);
}

// Optimum on the boundary line of plane i subject to planes [0, i) and the speed disc.
bool lp1(std::span<const OrcaHalfPlane> planes, std::size_t i, double r, Vec2 opt, bool dir_opt,
         Vec2& result) {
  const Vec2 pi = planes[i].point;
  const Vec2 di = dirOf(planes[i]);
  const double dot = pi.dot(di);
  const double disc = dot * dot + r * r - pi.squaredNorm();
  if (disc < 0.0)
    return false;  // the line misses the speed disc
  const double s = std::sqrt(disc);
  double t_lo = -dot - s;
  double t_hi = -dot + s;
  for (std::size_t j = 0; j < i; ++j) {
    const Vec2 dj = dirOf(planes[j]);
    const double denom = di.cross(dj);
    const double numer = dj.cross(pi - planes[j].point);
    if (std::abs(denom) <= kEps) {
      if (numer < 0.0)
        return false;  // parallel and entirely outside plane j
      continue;
    }
    const double t = numer / denom;
    if (denom > 0.0) {
      t_hi = std::min(t_hi, t);
    } else {
      t_lo = std::max(t_lo, t);
    }
    if (t_lo > t_hi)
      return false;
  }
  double t = 0.0;
  if (dir_opt) {
    t = opt.dot(di) > 0.0 ? t_hi : t_lo;
  } else {
    t = std::clamp(di.dot(opt - pi), t_lo, t_hi);
  }
  result = pi + di * t;
  return true;
}

// Returns planes.size() on success, else the index of the first plane that could not be met
// (result then holds the optimum of the planes before it).
std::size_t lp2(std::span<const OrcaHalfPlane> planes, double r, Vec2 opt, bool dir_opt, Vec2& result) {
  if (dir_opt) {
    result = opt * r;
  } else if (opt.squaredNorm() > r * r) {
    result = opt.normalized() * r;
  } else {
    result = opt;
  }
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (violation(planes[i], result) > 0.0) {
      const Vec2 keep = result;
      if (!lp1(planes, i, r, opt, dir_opt, result)) {
        result = keep;
        return i;
      }
    }
  }
  return planes.size();
}

// 3D LP of the paper: minimise the largest violation of the soft planes, planes [0, hard) kept.
void lp3(std::span<const OrcaHalfPlane> planes, std::size_t hard, std::size_t begin, double r, Vec2& result) {
  double worst = 0.0;
  std::vector<OrcaHalfPlane> proj;
  for (std::size_t i = begin; i < planes.size(); ++i) {
    if (violation(planes[i], result) <= worst)
      continue;
    proj.assign(planes.begin(), planes.begin() + static_cast<std::ptrdiff_t>(hard));
    const Vec2 pi = planes[i].point;
    const Vec2 di = dirOf(planes[i]);
    for (std::size_t j = hard; j < i; ++j) {
      const Vec2 pj = planes[j].point;
      const Vec2 dj = dirOf(planes[j]);
      const double det = di.cross(dj);
      Vec2 point;
      if (std::abs(det) <= kEps) {
        if (di.dot(dj) > 0.0)
          continue;  // same direction: plane i's violation bounds plane j's
        point = (pi + pj) * 0.5;
      } else {
        point = pi + di * (dj.cross(pi - pj) / det);
      }
      // The locus of equal violation of planes i and j: its permitted side is where j is
      // violated less than i.
      const Vec2 d = (dj - di).normalized();
      proj.push_back({point, Vec2{-d.y, d.x}});
    }
    const Vec2 keep = result;
    // Optimise in the direction that reduces the violation of plane i the fastest.
    if (lp2(proj, r, planes[i].normal, true, result) < proj.size())
      result = keep;  // only possible through round-off: the previous result was feasible
    worst = violation(planes[i], result);
  }
}

}  // namespace

OrcaHalfPlane orcaHalfPlane(Vec2 v_a, Vec2 rel_pos, Vec2 rel_vel, double R, double tau, double dt,
                            double share) {
  const double dist2 = rel_pos.squaredNorm();
  const double R2 = R * R;
  Vec2 u;
  Vec2 n;
  if (dist2 > R2) {
    // Truncated cone: apex at the origin, cut off by the disc of radius R/tau around rel_pos/tau.
    const Vec2 w = rel_vel - rel_pos / tau;
    const double w2 = w.squaredNorm();
    const double wp = w.dot(rel_pos);
    if (w2 <= kEps * kEps) {
      // Relative velocity at the centre of the cut-off disc: every direction is equally short;
      // back off straight away from the other disc.
      n = -rel_pos.normalized();
      u = n * (R / tau);
    } else if (wp < 0.0 && wp * wp > R2 * w2) {
      // Closest boundary point is on the cut-off arc.
      const double wl = std::sqrt(w2);
      n = w / wl;
      u = n * (R / tau - wl);
    } else {
      // Closest boundary point is on a leg; the leg is rel_pos turned by ±asin(R/|rel_pos|).
      const double leg = std::sqrt(dist2 - R2);
      Vec2 d;
      if (rel_pos.cross(w) > 0.0) {
        d = Vec2{rel_pos.x * leg - rel_pos.y * R, rel_pos.x * R + rel_pos.y * leg} / dist2;
        n = d.perp();  // left leg: outside is to its left
      } else {
        d = Vec2{rel_pos.x * leg + rel_pos.y * R, -rel_pos.x * R + rel_pos.y * leg} / dist2;
        n = -d.perp();  // right leg: outside is to its right
      }
      u = d * rel_vel.dot(d) - rel_vel;
    }
  } else {
    // Already overlapping: get apart within one cycle.
    const Vec2 w = rel_vel - rel_pos / dt;
    const double wl = std::sqrt(w.squaredNorm());
    n = wl > kEps ? w / wl : -rel_pos.normalized();
    u = n * (R / dt - wl);
  }
  return {v_a + u * share, n};
}

Vec2 orcaSolve(std::span<const OrcaHalfPlane> planes, std::size_t hard, Vec2 v_pref, double vMax) {
  Vec2 result;
  const std::size_t fail = lp2(planes, vMax, v_pref, false, result);
  if (fail < planes.size())
    lp3(planes, std::min(hard, fail), fail, vMax, result);
  return result;
}

Expected<void> OrcaParams::validate() const {
  if (!(tau > 0.0) || !(tauStatic > 0.0) || margin < 0.0 || trackingError < 0.0 || rightBias < 0.0 ||
      !(kOmega > 0.0) || staticRange < 0.0 || maxStatic < 0) {
    return fleet::unexpected("invalid_orca_params",
                             "need tau, tau_static, k_omega > 0 and non-negative margin, tracking_error, "
                             "static_range, max_static");
  }
  return {};
}

Command OrcaPlanner::plan(const LocalView& view) {
  const Pose2& pose = view.robot.pose;
  const Vec2 p = pose.position();
  const Vec2 goal = view.goal();
  const double dg = fastDistance(p, goal);
  last_v_ = {};
  if (dg <= view.goalTolerance)
    return {{}, PlanStatus::kGoalReached, false};
  const double vmax = view.limits.vMax;
  const Vec2 carrot = carrotOnPath(view.path, p, 1.5);
  // Brake on the last stretch (v ≤ sqrt(2·a·d)) so the tolerance is not overshot.
  const double v_goal = std::min(vmax, std::sqrt(2.0 * view.limits.accelMax * dg));
  const Vec2 v_pref = (carrot - p).normalized() * v_goal;
  // The velocity the robot is really executing (it moves along its heading).
  const Vec2 v_cur = pose.heading() * view.robot.twist.v;
  const double r = view.robot.radius + params_.margin + params_.trackingError;

  planes_.clear();
  // Static points first: hard constraints, full responsibility (they do not move).
  if (params_.maxStatic > 0 && !view.scan.empty()) {
    thread_local std::vector<std::pair<double, Vec2>> near;
    near.clear();
    const double range2 = (params_.staticRange + r) * (params_.staticRange + r);
    for (const Vec2& q : view.scan) {
      const double d2 = (q - p).squaredNorm();
      if (d2 <= range2)
        near.emplace_back(d2, q);
    }
    const std::size_t k = std::min(near.size(), static_cast<std::size_t>(params_.maxStatic));
    std::partial_sort(near.begin(), near.begin() + static_cast<std::ptrdiff_t>(k), near.end(),
                      [](const auto& a, const auto& b) { return a.first < b.first; });
    for (std::size_t i = 0; i < k; ++i) {
      planes_.push_back(orcaHalfPlane(v_cur, near[i].second - p, v_cur, r, params_.tauStatic, view.dt, 1.0));
    }
  }
  const std::size_t hard = planes_.size();
  for (const MovingDisc& d : view.discs) {
    planes_.push_back(orcaHalfPlane(v_cur, d.position - p, v_cur - d.velocity,
                                    r + d.radius + params_.trackingError, params_.tau, view.dt, 0.5));
  }
  // Perfectly symmetric encounters (circle swap) are a fixed point of ORCA: every robot's optimum
  // is to slow down straight ahead. A shared convention breaks the symmetry: while the preferred
  // velocity is not permitted, prefer passing on the right (rotate it clockwise).
  // Only towards moving discs: a robot standing still (arrived, parked) takes no part in the
  // convention, and biasing against it kept the last robots of the 100-robot swap circling outside
  // the ring of arrived robots instead of entering their goal's gap.
  Vec2 opt = v_pref;
  for (std::size_t i = hard; i < planes_.size(); ++i) {
    if (view.discs[i - hard].velocity.squaredNorm() > 0.05 * 0.05 && violation(planes_[i], v_pref) > 0.0) {
      const double c = std::cos(params_.rightBias);
      const double s = std::sin(params_.rightBias);
      opt = Vec2{c * v_pref.x + s * v_pref.y, -s * v_pref.x + c * v_pref.y};
      break;
    }
  }
  const Vec2 v = orcaSolve(planes_, hard, opt, vmax);
  last_v_ = v;
  const double speed = std::sqrt(v.squaredNorm());
  if (speed < 1e-6)
    return {{}, PlanStatus::kMoving, false};
  const double err = angleDiff(std::atan2(v.y, v.x), pose.theta);
  const double fwd = speed * std::max(0.0, std::cos(err));
  const double w = std::clamp(params_.kOmega * err, -view.limits.omegaMax, view.limits.omegaMax);
  return {{fwd, w}, PlanStatus::kMoving, false};
}

}  // namespace fleet::avoidance
