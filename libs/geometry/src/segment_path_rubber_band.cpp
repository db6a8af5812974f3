// Independent cross-check for the shortest path through ordered segments: a "rubber band" pulled
// tight one touch point at a time. It shares no code with the convex (smoothed Newton) solver or
// MMS: each point is moved to the exact minimiser of its two adjacent path pieces (a reflection
// construction), with over-relaxation, and coincident neighbours are moved together by an exact
// nested one-dimensional search.
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
    // Start in the middle of every segment: neither the skeleton (MMS's start) nor anything the
    // other solvers compute.
    t_.assign(segs.size(), 0.5);
    x_.resize(segs.size() + 2);
    x_[0] = p;
    x_[segs.size() + 1] = q;
    for (int k = 0; k < n_; ++k) {
      x_[static_cast<std::size_t>(k) + 1] = pointOn(k, 0.5);
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
      for (int k = 0; k + 1 < n_; ++k) {
        if (dist(x(k), x(k + 1)) <= tol && relaxPair(k) > tol) {
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

  // Exact joint move of points k and k+1: the length as a function of t_k with t_{k+1} minimised
  // exactly is convex (partial minimisation of a jointly convex function), so a golden-section
  // search on t_k with the inner reflection minimiser finds the joint optimum. Kept only when it
  // shortens the path. Returns how far the pair moved.
  double relaxPair(int k) {
    const Vec2 prev = x(k - 1), next = x(k + 2);
    auto inner = [&](double tk, double* tk1) {
      const Vec2 xk = pointOn(k, tk);
      *tk1 = exactMin(k + 1, xk, next, t_[static_cast<std::size_t>(k) + 1]);
      const Vec2 xk1 = pointOn(k + 1, *tk1);
      return dist(prev, xk) + dist(xk, xk1) + dist(xk1, next);
    };
    double lo = 0.0, hi = 1.0, tmp = 0.0;
    constexpr double g = 0.6180339887498949;
    double c = hi - g * (hi - lo), d = lo + g * (hi - lo);
    double fc = inner(c, &tmp), fd = inner(d, &tmp);
    for (int it = 0; it < 90 && hi - lo > 1e-16; ++it) {
      if (fc <= fd) {
        hi = d, d = c, fd = fc;
        c = hi - g * (hi - lo);
        fc = inner(c, &tmp);
      } else {
        lo = c, c = d, fc = fd;
        d = lo + g * (hi - lo);
        fd = inner(d, &tmp);
      }
    }
    const double tk = 0.5 * (lo + hi);
    double tk1 = 0.0;
    const double fNew = inner(tk, &tk1);
    const double fOld = dist(prev, x(k)) + dist(x(k), x(k + 1)) + dist(x(k + 1), next);
    if (!(fNew < fOld)) {
      return 0.0;
    }
    const Vec2 b0 = x(k), b1 = x(k + 1);
    set(k, tk);
    set(k + 1, tk1);
    return std::max(dist(b0, x(k)), dist(b1, x(k + 1)));
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
