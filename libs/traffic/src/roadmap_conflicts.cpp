#include "fleet/traffic/roadmap_conflicts.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "roadmap_geometry.hpp"

namespace fleet::traffic {

namespace {

using detail::fastDistance;
using detail::pointSegmentDistance;
using detail::segmentDistance;

// Distances equal to a separation up to rounding count as kept (a queue one following distance
// long is computed as 1.0999999999999999 m).
constexpr double kSlack = 1e-9;

// Does any point of segment q0→q1 lie in the corridor ahead of a robot driving a0→a1? In the
// driver's frame (x along its heading from a0, y to its left) the set of such points is
// {x > 0, |y| <= corridor, x <= L or |(x - L, y)| < ahead}: a point beside the driven stretch is
// passed at its lateral distance (< ahead), one beyond it is closest when the driver stops at a1.
// That set is convex, so clip the segment to the slab and the half-plane, then test the rest.
bool corridorHit(Vec2 a0, Vec2 a1, Vec2 q0, Vec2 q1, const Separation& s) {
  const double len = fastDistance(a0, a1);
  if (len <= 0.0) {
    return false;
  }
  const Vec2 dir = (a1 - a0) / len;
  const Vec2 left = dir.perp();
  const Vec2 p0{(q0 - a0).dot(dir), (q0 - a0).dot(left)};
  const Vec2 p1{(q1 - a0).dot(dir), (q1 - a0).dot(left)};
  double t0 = 0.0;
  double t1 = 1.0;
  // f(t) = f0 + t (f1 - f0) >= 0 for each constraint.
  auto clip = [&](double f0, double f1) {
    if (f0 < 0.0 && f1 < 0.0) {
      t1 = -1.0;
      return;
    }
    if (f0 < 0.0) {
      t0 = std::max(t0, f0 / (f0 - f1));
    } else if (f1 < 0.0) {
      t1 = std::min(t1, f0 / (f0 - f1));
    }
  };
  constexpr double kAhead = 1e-9;  // strictly ahead: a point level with the driver falls behind
  clip(p0.x - kAhead, p1.x - kAhead);
  const double w = s.corridor + kSlack;
  clip(w - p0.y, w - p1.y);
  clip(w + p0.y, w + p1.y);
  if (t0 > t1) {
    return false;
  }
  const Vec2 c0 = p0 + (p1 - p0) * t0;
  const Vec2 c1 = p0 + (p1 - p0) * t1;
  if (std::min(c0.x, c1.x) <= len) {
    return true;
  }
  return pointSegmentDistance({len, 0.0}, c0, c1) < s.ahead - kSlack;
}

// Nodes bucketed by position for neighbourhood queries.
class Buckets {
 public:
  Buckets(const std::vector<Vec2>& points, double cell) : cell_(cell) {
    if (points.empty()) {
      return;
    }
    lo_ = hi_ = points.front();
    for (const Vec2 p : points) {
      lo_.x = std::min(lo_.x, p.x);
      lo_.y = std::min(lo_.y, p.y);
      hi_.x = std::max(hi_.x, p.x);
      hi_.y = std::max(hi_.y, p.y);
    }
    // Coarser buckets on a large site: at most kMaxBucketsPerSide a side.
    cell_ = std::max(cell_, std::max(hi_.x - lo_.x, hi_.y - lo_.y) / kMaxBucketsPerSide);
    w_ = static_cast<int>((hi_.x - lo_.x) / cell_) + 1;
    h_ = static_cast<int>((hi_.y - lo_.y) / cell_) + 1;
    cells_.resize(static_cast<std::size_t>(w_) * static_cast<std::size_t>(h_));
    for (std::size_t i = 0; i < points.size(); ++i) {
      cells_[index(points[i])].push_back(static_cast<std::int32_t>(i));
    }
  }
  /// Calls f(i) for every point within the box [lo, hi] grown to whole cells.
  template <class F>
  void forBox(Vec2 lo, Vec2 hi, F&& f) const {
    if (cells_.empty()) {
      return;
    }
    const int x0 = std::max(0, static_cast<int>(std::floor((lo.x - lo_.x) / cell_)));
    const int y0 = std::max(0, static_cast<int>(std::floor((lo.y - lo_.y) / cell_)));
    const int x1 = std::min(w_ - 1, static_cast<int>(std::floor((hi.x - lo_.x) / cell_)));
    const int y1 = std::min(h_ - 1, static_cast<int>(std::floor((hi.y - lo_.y) / cell_)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        for (const std::int32_t v : cells_[static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) +
                                           static_cast<std::size_t>(x)]) {
          f(v);
        }
      }
    }
  }

 private:
  std::size_t index(Vec2 p) const {
    const int x = std::clamp(static_cast<int>((p.x - lo_.x) / cell_), 0, w_ - 1);
    const int y = std::clamp(static_cast<int>((p.y - lo_.y) / cell_), 0, h_ - 1);
    return static_cast<std::size_t>(y) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(x);
  }
  double cell_;
  Vec2 lo_;
  Vec2 hi_;
  int w_ = 0;
  int h_ = 0;
  std::vector<std::vector<std::int32_t>> cells_;
};

struct DirectedEdge {
  NodeId from;
  NodeId to;
};

}  // namespace

bool unsafe(const Motion& a, const Motion& b, const Separation& s) {
  const Vec2 a1 = a.moving ? a.to : a.from;
  const Vec2 b1 = b.moving ? b.to : b.from;
  const double d = segmentDistance(a.from, a1, b.from, b1);
  if (d < s.contact - kSlack) {
    return true;
  }
  if (d >= s.ahead) {
    return false;  // every point of a corridor region lies within `ahead` of its driver's segment
  }
  return (a.moving && corridorHit(a.from, a1, b.from, b1, s)) ||
         (b.moving && corridorHit(b.from, b1, a.from, a1, s));
}

std::size_t conflictPairs(const Graph& g) {
  std::size_t n = 0;
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    n += g.conflicts(v).size();
  }
  return n / 2;
}

std::size_t addGeometricConflicts(Graph& g, const Separation& s, const std::vector<std::uint8_t>& waiting) {
  const std::size_t before = conflictPairs(g);
  const auto n = static_cast<NodeId>(g.size());
  // Which of the held pairs to make conflict: one with the least weight of nodes robots wait on
  // (a place robots rest at weighs most), the closest of those.
  auto waits = [&](NodeId v) {
    return static_cast<std::size_t>(v) < waiting.size()
               ? static_cast<int>(waiting[static_cast<std::size_t>(v)])
               : 0;
  };
  std::vector<DirectedEdge> edges;
  double longest = 0.0;
  for (NodeId v = 0; v < n; ++v) {
    for (const auto& e : g.edges(v)) {
      edges.push_back({v, e.to});
      longest = std::max(longest, fastDistance(g.position(v), g.position(e.to)));
    }
  }
  // No motion reaches further than `ahead` beyond its own segment.
  std::vector<Vec2> positions;
  for (NodeId v = 0; v < n; ++v) {
    positions.push_back(g.position(v));
  }
  const Buckets nodes(positions, std::max(s.ahead, 0.25));
  auto box = [&](Vec2 a, Vec2 b, double grow) {
    return std::pair{Vec2{std::min(a.x, b.x) - grow, std::min(a.y, b.y) - grow},
                     Vec2{std::max(a.x, b.x) + grow, std::max(a.y, b.y) + grow}};
  };

  // Robots standing: only contact matters (the gate does not hold a robot that stands or turns).
  for (NodeId v = 0; v < n; ++v) {
    const auto [lo, hi] = box(g.position(v), g.position(v), s.contact);
    nodes.forBox(lo, hi, [&](NodeId w) {
      if (w > v && fastDistance(g.position(v), g.position(w)) < s.contact - kSlack) {
        g.addConflict(v, w);
      }
    });
  }

  // The nodes that conflict with the held ones of the motion at hand carry its stamp, so "already
  // covered" costs nothing.
  std::vector<std::size_t> stamp(static_cast<std::size_t>(n), std::numeric_limits<std::size_t>::max());
  auto stampHeld = [&](const DirectedEdge& e, std::size_t mark) {
    for (const NodeId v : {e.from, e.to}) {
      stamp[static_cast<std::size_t>(v)] = mark;
      for (const NodeId c : g.conflicts(v)) {
        stamp[static_cast<std::size_t>(c)] = mark;
      }
    }
  };

  // A robot driving u→v against one standing on w.
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& e = edges[i];
    const Vec2 pu = g.position(e.from);
    const Vec2 pv = g.position(e.to);
    stampHeld(e, i);
    const auto [lo, hi] = box(pu, pv, s.ahead);
    nodes.forBox(lo, hi, [&](NodeId w) {
      if (stamp[static_cast<std::size_t>(w)] == i) {
        return;
      }
      const Vec2 pw = g.position(w);
      if (unsafe({pu, pv, true}, {pw, pw, false}, s)) {
        const auto cu = std::pair{waits(e.from), fastDistance(pu, pw)};
        const auto cv = std::pair{waits(e.to), fastDistance(pv, pw)};
        g.addConflict(cu <= cv ? e.from : e.to, w);
        stamp[static_cast<std::size_t>(w)] = i;
      }
    });
  }

  // Two robots driving: edges bucketed by their midpoints; two edges can only come within `ahead`
  // of each other when their midpoints are closer than `ahead` plus half of each length.
  std::vector<Vec2> mids;
  std::vector<double> half;
  for (const auto& e : edges) {
    mids.push_back((g.position(e.from) + g.position(e.to)) * 0.5);
    half.push_back(0.5 * fastDistance(g.position(e.from), g.position(e.to)));
  }
  const Buckets byMid(mids, 0.5);
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const auto& e = edges[i];
    const Vec2 pu = g.position(e.from);
    const Vec2 pv = g.position(e.to);
    const double halfE = half[i];
    const std::size_t mark = edges.size() + i;
    stampHeld(e, mark);
    const Vec2 me = mids[i];
    const double reach = s.ahead + halfE + 0.5 * longest;
    byMid.forBox(me - Vec2{reach, reach}, me + Vec2{reach, reach}, [&](std::int32_t jj) {
      const auto j = static_cast<std::size_t>(jj);
      if (j <= i) {
        return;
      }
      const auto& f = edges[j];
      if (stamp[static_cast<std::size_t>(f.from)] == mark || stamp[static_cast<std::size_t>(f.to)] == mark) {
        return;  // they share a node (both robots hold it) or already hold conflicting ones
      }
      const Vec2 pw = g.position(f.from);
      const Vec2 px = g.position(f.to);
      const double within = s.ahead + halfE + half[j];
      if ((me - mids[j]).squaredNorm() >= within * within || !unsafe({pu, pv, true}, {pw, px, true}, s)) {
        return;
      }
      const std::array<std::pair<NodeId, NodeId>, 4> cross{
          {{e.from, f.from}, {e.from, f.to}, {e.to, f.from}, {e.to, f.to}}};
      auto best = std::pair{3, std::numeric_limits<double>::infinity()};
      std::pair<NodeId, NodeId> pick = cross[0];
      for (const auto& [a, b] : cross) {
        const auto cost = std::pair{waits(a) + waits(b), fastDistance(g.position(a), g.position(b))};
        if (cost < best) {
          best = cost;
          pick = {a, b};
        }
      }
      g.addConflict(pick.first, pick.second);
      stamp[static_cast<std::size_t>(pick.second)] = mark;
    });
  }
  return conflictPairs(g) - before;
}

}  // namespace fleet::traffic
