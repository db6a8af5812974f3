#include "fleet/planning/return_path.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "fleet/core/angles.hpp"
#include "fleet/geometry/grid_raycast.hpp"
#include "fleet/planning/segment_free.hpp"

namespace fleet::planning {

namespace {

double freeRange(const OccupancyGrid& grid, Vec2 from, double angle, double maxRange) {
  const auto hit = geometry::raycastGrid(grid.view(), from, angle, maxRange);
  return hit.hit ? hit.range : maxRange;
}

std::vector<Vec2> dedup(const std::vector<Vec2>& pts) {
  std::vector<Vec2> out;
  for (const Vec2& p : pts) {
    if (out.empty() || (p - out.back()).norm() > 1e-12) {
      out.push_back(p);
    }
  }
  return out;
}

}  // namespace

Expected<ReturnPath> planReturnPath(const OccupancyGrid& grid, const std::vector<Vec2>& skeletonIn,
                                    const ReturnPathOptions& opt) {
  const std::vector<Vec2> sk = dedup(skeletonIn);
  if (sk.size() < 2) {
    return unexpected("bad_skeleton", "a skeleton path needs at least two distinct vertices");
  }
  for (std::size_t k = 1; k < sk.size(); ++k) {
    if (!segmentFree(grid, sk[k - 1], sk[k])) {
      return unexpected("bad_skeleton", "skeleton edge " + std::to_string(k - 1) + " crosses an obstacle");
    }
  }
  ReturnPath rp;
  rp.skeletonLength = geometry::polylineLength(sk);
  // Segments end short of the obstacle so that chords between neighbouring rays keep clear of it.
  const double margin = 1.5 * grid.resolution();
  std::vector<int> bundleEnds;  // the seed's cutting segments: the last segment of each bundle
  for (std::size_t k = 1; k + 1 < sk.size(); ++k) {
    const Vec2 v = sk[k];
    const Vec2 ein = sk[k - 1] - v;
    const Vec2 eout = sk[k + 1] - v;
    const double ain = std::atan2(ein.y, ein.x);
    const double delta = angleDiff(std::atan2(eout.y, eout.x), ain);  // signed turn from ein to eout
    if (std::abs(delta) >= kPi - 1e-9) {
      continue;  // straight through: no inner side
    }
    const double cap = std::min(opt.visionRadius, opt.spacingFraction * std::min(ein.norm(), eout.norm()));
    const double sgn = delta >= 0.0 ? 1.0 : -1.0;
    for (double s = opt.rayStep; s < std::abs(delta) - 1e-9; s += opt.rayStep) {
      const double ang = ain + sgn * s;
      const auto hit = geometry::raycastGrid(grid.view(), v, ang, cap);
      if (!hit.hit) {
        continue;  // free up to the cap: no constraint in this direction
      }
      const double len = std::max(0.0, hit.range - margin);
      rp.segments.push_back({v, v + Vec2{std::cos(ang), std::sin(ang)} * len});
    }
    if (!rp.segments.empty() &&
        (bundleEnds.empty() || bundleEnds.back() != static_cast<int>(rp.segments.size()) - 1)) {
      bundleEnds.push_back(static_cast<int>(rp.segments.size()) - 1);
    }
  }
  geometry::MmsOptions mmsOpt = opt.mms;
  if (mmsOpt.cuts.empty()) {
    mmsOpt.cuts = bundleEnds;
  }
  const auto mms = geometry::shortestPathMms(sk.front(), sk.back(), rp.segments, mmsOpt);
  rp.mmsIterations = mms.iterations;
  rp.points = dedup(mms.points);
  for (std::size_t k = 1; k < rp.points.size(); ++k) {
    if (!segmentFree(grid, rp.points[k - 1], rp.points[k])) {
      rp.usedSkeleton = true;  // a chord between two bundle rays clipped an obstacle corner
      rp.points = sk;
      break;
    }
  }
  rp.length = geometry::polylineLength(rp.points);
  return rp;
}

Expected<ExploreResult> explore(const OccupancyGrid& grid, Vec2 start, Vec2 goal, const ExploreOptions& opt) {
  const auto sc = grid.cellAt(start);
  if (!sc || !grid.cellAt(goal)) {
    return unexpected("out_of_map", "start or goal lies outside the map");
  }
  if (grid.blocked(*sc)) {
    return unexpected("start_blocked", "start cell is blocked");
  }
  const double r = opt.visionRadius;
  struct OpenPoint {
    Vec2 at;
    int node;
    bool alive;
  };
  std::vector<Vec2> nodes{start};
  std::vector<std::vector<std::pair<int, double>>> adj(1);
  std::vector<OpenPoint> open;
  ExploreResult res;
  res.route.push_back(start);
  int cur = 0;
  auto addNode = [&](Vec2 p, int from) {
    nodes.push_back(p);
    adj.emplace_back();
    const int id = static_cast<int>(nodes.size()) - 1;
    const double w = (p - nodes[static_cast<std::size_t>(from)]).norm();
    adj[static_cast<std::size_t>(from)].push_back({id, w});
    adj[static_cast<std::size_t>(id)].push_back({from, w});
    return id;
  };
  for (int scan = 0;; ++scan) {
    if (scan >= opt.maxScans) {
      return unexpected("step_limit", "goal not reached within " + std::to_string(opt.maxScans) + " scans");
    }
    const Vec2 a = nodes[static_cast<std::size_t>(cur)];
    if ((goal - a).norm() <= r && segmentFree(grid, a, goal)) {
      res.route.push_back(goal);
      res.travelled += (goal - a).norm();
      res.travelledSkeleton += (goal - a).norm();
      break;
    }
    // S1: scan the vision disc; S2: one open point per collision-free sector of <= 120 degrees.
    ++res.scans;
    const int n = std::max(8, opt.rays);
    std::vector<bool> freeRay(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) {
      freeRay[static_cast<std::size_t>(i)] = freeRange(grid, a, 2.0 * kPi * i / n, r) >= r;
    }
    auto isFree = [&](int i) { return freeRay[static_cast<std::size_t>(((i % n) + n) % n)]; };
    int first = 0;
    while (first < n && isFree(first)) {
      ++first;
    }
    std::vector<std::pair<int, int>> runs;  // [begin, length) in ray indices, circular
    if (first == n) {
      runs.push_back({0, n});
    } else {
      for (int i = first + 1; i <= first + n; ++i) {
        if (isFree(i) && !isFree(i - 1)) {
          int len = 0;
          while (len < n && isFree(i + len)) {
            ++len;
          }
          runs.push_back({i, len});
        }
      }
    }
    const double step = 2.0 * kPi / n;
    for (const auto& [b, len] : runs) {
      const double width = len * step;
      const int sectors = std::max(1, static_cast<int>(std::ceil(width / deg2rad(opt.maxSectorDeg) - 1e-9)));
      for (int s = 0; s < sectors; ++s) {
        const double ang = (b + (s + 0.5) * len / sectors - 0.5) * step;
        const Vec2 pt = a + Vec2{std::cos(ang), std::sin(ang)} * (opt.openPointFraction * r);
        bool seen = false;
        for (std::size_t k = 0; k < nodes.size() && !seen; ++k) {
          seen = static_cast<int>(k) != cur && (pt - nodes[k]).norm() < r && segmentFree(grid, nodes[k], pt);
        }
        for (const auto& o : open) {
          seen = seen || (o.alive && (o.at - pt).norm() < 0.25 * r);
        }
        if (!seen && segmentFree(grid, a, pt)) {
          open.push_back({pt, cur, true});
        }
      }
    }
    // Rank: alpha/d(t) + beta/a(t), the highest first (+inf when d or a is zero).
    int best = -1;
    double bestRank = -1.0;
    const double goalAng = std::atan2(goal.y - a.y, goal.x - a.x);
    for (std::size_t k = 0; k < open.size(); ++k) {
      if (!open[k].alive) {
        continue;
      }
      const double d = (goal - open[k].at).norm();
      const double ang = std::abs(angleDiff(std::atan2(open[k].at.y - a.y, open[k].at.x - a.x), goalAng));
      const double rank =
          (d == 0.0 || ang == 0.0) ? std::numeric_limits<double>::infinity() : opt.alpha / d + opt.beta / ang;
      if (rank > bestRank) {
        bestRank = rank;
        best = static_cast<int>(k);
      }
    }
    if (best < 0) {
      return unexpected("exhausted", "no open point left: the goal cannot be reached");
    }
    OpenPoint& p = open[static_cast<std::size_t>(best)];
    p.alive = false;
    if ((p.at - a).norm() <= r && segmentFree(grid, a, p.at)) {
      res.route.push_back(p.at);
      res.travelled += (p.at - a).norm();
      res.travelledSkeleton += (p.at - a).norm();
      cur = addNode(p.at, cur);
      continue;
    }
    // S3: skeleton = shortest path in G from the robot's node to the node that saw p, then p.
    std::vector<double> dist(nodes.size(), std::numeric_limits<double>::infinity());
    std::vector<int> prev(nodes.size(), -1);
    std::vector<bool> done(nodes.size(), false);
    dist[static_cast<std::size_t>(cur)] = 0.0;
    for (std::size_t it = 0; it < nodes.size(); ++it) {
      int u = -1;
      for (std::size_t k = 0; k < nodes.size(); ++k) {
        if (!done[k] && (u < 0 || dist[k] < dist[static_cast<std::size_t>(u)])) {
          u = static_cast<int>(k);
        }
      }
      if (u < 0 || std::isinf(dist[static_cast<std::size_t>(u)])) {
        break;
      }
      done[static_cast<std::size_t>(u)] = true;
      for (const auto& [v, w] : adj[static_cast<std::size_t>(u)]) {
        if (dist[static_cast<std::size_t>(u)] + w < dist[static_cast<std::size_t>(v)]) {
          dist[static_cast<std::size_t>(v)] = dist[static_cast<std::size_t>(u)] + w;
          prev[static_cast<std::size_t>(v)] = u;
        }
      }
    }
    std::vector<Vec2> skeleton{p.at};
    for (int v = p.node; v >= 0; v = prev[static_cast<std::size_t>(v)]) {
      skeleton.push_back(nodes[static_cast<std::size_t>(v)]);
      if (v == cur) {
        break;
      }
    }
    std::reverse(skeleton.begin(), skeleton.end());
    const auto rp = planReturnPath(grid, skeleton, opt.returnPath);
    if (!rp) {
      return unexpected(rp.error());
    }
    ++res.returns;
    res.skeletonFallbacks += rp->usedSkeleton ? 1 : 0;
    res.route.insert(res.route.end(), rp->points.begin() + 1, rp->points.end());
    res.travelled += rp->length;
    res.travelledSkeleton += rp->skeletonLength;
    cur = addNode(p.at, p.node);
  }
  return res;
}

}  // namespace fleet::planning
