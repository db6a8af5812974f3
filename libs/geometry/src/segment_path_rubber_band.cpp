// Independent cross-check for the shortest path through ordered segments: a "rubber band" pulled
// tight one touch point at a time. It shares no code with the convex (smoothed Newton) solver or
// MMS: each point is moved to the exact minimiser of its two adjacent path pieces (a reflection
// construction), optionally over-relaxed, and runs of coincident points are moved together by
// exact nested one-dimensional searches.
#include <algorithm>
#include <cmath>
#include <vector>

#include "fleet/geometry/segment_path.hpp"

namespace fleet::geometry {

namespace {

double dist(Vec2 u, Vec2 v) {
  const Vec2 d = u - v;
  return std::sqrt(d.dot(d));
}

class RubberBand {
 public:
  RubberBand(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, const RubberBandOptions& opt)
      : p_(p), q_(q), segs_(segs), opt_(opt), n_(static_cast<int>(segs.size())) {
    scale_ = dist(p, q);
    for (const auto& s : segs) {
      scale_ += dist(s.a, s.b) + dist(s.a, p);
    }
    scale_ = std::max(scale_, 1e-300);
    // Start in the middle of every segment (unless told otherwise): neither the skeleton (MMS's
    // start) nor anything the other solvers compute.
    t_.assign(segs.size(), 0.5);
    if (opt.start.size() == segs.size()) {
      for (std::size_t k = 0; k < segs.size(); ++k) {
        t_[k] = std::clamp(opt.start[k], 0.0, 1.0);
      }
    }
    x_.resize(segs.size() + 2);
    x_[0] = p;
    x_[segs.size() + 1] = q;
    for (int k = 0; k < n_; ++k) {
      x_[static_cast<std::size_t>(k) + 1] = pointOn(k, t_[static_cast<std::size_t>(k)]);
    }
  }

  SegmentPath run() {
    SegmentPath out;
    int sweeps = 0;
    bool converged = false;
    const double tol = opt_.tolerance * scale_;
    while (sweeps < opt_.maxSweeps) {
      double moved = 0.0;
      // Symmetric sweeps (forward then backward) carry a change through a long straight run in
      // both directions within one iteration.
      const bool forward = sweeps % 2 == 0;
      for (int j = 0; j < n_; ++j) {
        const int k = forward ? j : n_ - 1 - j;
        moved = std::max(moved, relaxPoint(k));
      }
      ++sweeps;
      if (moved > tol) {
        continue;
      }
      // Single-point moves are exhausted. Where two touch points coincide (segments crossing or
      // sharing an end) the length is not differentiable and only a joint move may shorten it.
      bool improved = false;
      // Runs of coincident points (up to kMaxRun at a time; bundles put several segments' touch
      // points on one shared vertex) are moved jointly.
      for (int k = 0; k + 1 < n_; ++k) {
        int r = 1;
        while (k + r < n_ && r < kMaxRun && dist(x(k), x(k + r)) <= tol) {
          ++r;
        }
        if (r >= 2 && relaxRun(k, r) > tol) {
          improved = true;
          ++out.merges;
        }
      }
      if (!improved) {
        converged = true;
        break;
      }
    }
    out.params = t_;
    out.points = x_;
    out.length = polylineLength(x_);
    out.iterations = sweeps;
    out.converged = converged;
    return out;
  }

 private:
  [[nodiscard]] Vec2 pointOn(int k, double t) const {
    const Segment2& s = segs_[static_cast<std::size_t>(k)];
    return s.a + (s.b - s.a) * t;
  }
  // Path point of segment k; k = -1 is p and k = n is q.
  [[nodiscard]] Vec2 x(int k) const { return x_[static_cast<std::size_t>(k + 1)]; }

  // argmin over t in [0,1] of |s(t) - u| + |s(t) - v|. Reflect v across the segment's line when u
  // and v lie on the same side; the straight line from u to the (reflected) v then crosses the line
  // at the unconstrained minimiser, and since the function is convex in t clamping it is exact.
  // When u and v both lie on the line every point between them is optimal: keep `current` if it is
  // one of them.
  [[nodiscard]] double exactMin(int k, Vec2 u, Vec2 v, double current) const {
    const Segment2& s = segs_[static_cast<std::size_t>(k)];
    const Vec2 e = s.b - s.a;
    const double l2 = e.dot(e);
    if (l2 == 0.0) {
      return current;
    }
    const double l = std::sqrt(l2);
    const Vec2 du = u - s.a, dv = v - s.a;
    const double uu = du.dot(e) / l, vu = dv.dot(e) / l;                          // along the line
    const double un = std::abs(e.cross(du)) / l, vn = std::abs(e.cross(dv)) / l;  // distances to it
    double m;
    if (un + vn <= 1e-15 * scale_) {
      m = std::clamp(current * l, std::min(uu, vu), std::max(uu, vu));
    } else {
      m = uu + (vu - uu) * (un / (un + vn));
    }
    return std::clamp(m / l, 0.0, 1.0);
  }

  [[nodiscard]] double local(int k, double t) const {
    const Vec2 xk = pointOn(k, t);
    return dist(x(k - 1), xk) + dist(xk, x(k + 1));
  }

  void set(int k, double t) {
    t_[static_cast<std::size_t>(k)] = t;
    x_[static_cast<std::size_t>(k) + 1] = pointOn(k, t);
  }

  // Moves point k to its exact minimiser, or past it by the over-relaxation factor when that still
  // does not lengthen the path (so the length never increases). Returns how far the point moved.
  double relaxPoint(int k) {
    const double t0 = t_[static_cast<std::size_t>(k)];
    const double ts = exactMin(k, x(k - 1), x(k + 1), t0);
    double t = ts;
    if (opt_.overRelaxation != 1.0) {
      const double to = std::clamp(t0 + opt_.overRelaxation * (ts - t0), 0.0, 1.0);
      if (local(k, to) <= local(k, t0)) {
        t = to;
      }
    }
    const Vec2 before = x(k);
    set(k, t);
    return dist(before, x(k));
  }

  // Exact joint move of the r consecutive points k .. k+r-1. The length as a function of t_k with
  // the later points minimised exactly is convex (partial minimisation of a jointly convex
  // function), so nested golden-section searches, with the reflection minimiser for the last
  // point, find the joint optimum. Kept only when it shortens the path. Returns how far the points
  // moved.
  static constexpr int kMaxRun = 3;

  // min over the points j .. last of |from - x_j| + ... + |x_last - next|; writes the minimisers.
  double nested(int j, int last, Vec2 from, Vec2 next, double* t) const {
    if (j == last) {
      t[0] = exactMin(j, from, next, t_[static_cast<std::size_t>(j)]);
      const Vec2 xj = pointOn(j, t[0]);
      return dist(from, xj) + dist(xj, next);
    }
    auto value = [&](double tj, double* rest) {
      const Vec2 xj = pointOn(j, tj);
      return dist(from, xj) + nested(j + 1, last, xj, next, rest);
    };
    double scratch[kMaxRun];
    double lo = 0.0, hi = 1.0;
    constexpr double g = 0.6180339887498949;
    double c = hi - g * (hi - lo), d = lo + g * (hi - lo);
    double fc = value(c, scratch), fd = value(d, scratch);
    for (int it = 0; it < 80 && hi - lo > 1e-15; ++it) {
      if (fc <= fd) {
        hi = d, d = c, fd = fc;
        c = hi - g * (hi - lo);
        fc = value(c, scratch);
      } else {
        lo = c, c = d, fc = fd;
        d = lo + g * (hi - lo);
        fd = value(d, scratch);
      }
    }
    t[0] = 0.5 * (lo + hi);
    return value(t[0], t + 1);
  }

  double relaxRun(int k, int r) {
    const int last = k + r - 1;
    const Vec2 prev = x(k - 1), next = x(last + 1);
    double t[kMaxRun];
    const double fNew = nested(k, last, prev, next, t);
    double fOld = dist(prev, x(k)) + dist(x(last), next);
    for (int j = k; j < last; ++j) {
      fOld += dist(x(j), x(j + 1));
    }
    if (!(fNew < fOld)) {
      return 0.0;
    }
    double moved = 0.0;
    for (int j = 0; j < r; ++j) {
      const Vec2 before = x(k + j);
      set(k + j, t[j]);
      moved = std::max(moved, dist(before, x(k + j)));
    }
    return moved;
  }

  Vec2 p_, q_;
  const std::vector<Segment2>& segs_;
  RubberBandOptions opt_;
  int n_;
  double scale_ = 1.0;
  std::vector<double> t_;
  std::vector<Vec2> x_;  // p, one point per segment, q
};

}  // namespace

SegmentPath shortestPathRubberBand(Vec2 p, Vec2 q, const std::vector<Segment2>& segs,
                                   const RubberBandOptions& opt) {
  return RubberBand(p, q, segs, opt).run();
}

}  // namespace fleet::geometry
