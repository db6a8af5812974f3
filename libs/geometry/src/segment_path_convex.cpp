#include <algorithm>
#include <cmath>
#include <vector>

#include "fleet/geometry/segment_path.hpp"

namespace fleet::geometry {

double polylineLength(const std::vector<Vec2>& pts) {
  double len = 0.0;
  for (std::size_t k = 1; k < pts.size(); ++k) {
    len += (pts[k] - pts[k - 1]).norm();
  }
  return len;
}

double skeletonLength(Vec2 p, Vec2 q, const std::vector<Segment2>& segs) {
  std::vector<Vec2> pts{p};
  for (const auto& s : segs) {
    pts.push_back(s.a);
  }
  pts.push_back(q);
  return polylineLength(pts);
}

namespace {

struct Sym2 {
  double xx = 0, xy = 0, yy = 0;
  [[nodiscard]] double quad(Vec2 u, Vec2 v) const {
    return u.x * (xx * v.x + xy * v.y) + u.y * (xy * v.x + yy * v.y);
  }
};

class ConvexChain {
 public:
  ConvexChain(Vec2 p, Vec2 q, const std::vector<Segment2>& segs)
      : p_(p), q_(q), segs_(segs), n_(segs.size()) {
    // Problem scale: the skeleton length plus the segment lengths (grows linearly with n).
    scale_ = 0.0;
    Vec2 prev = p;
    for (const auto& s : segs) {
      scale_ += (s.b - s.a).norm() + (s.a - prev).norm();
      prev = s.a;
    }
    scale_ += (q - prev).norm();
    scale_ = std::max(scale_, 1e-300);
  }

  [[nodiscard]] Vec2 point(std::size_t k, const std::vector<double>& t) const {
    if (k == 0) {
      return p_;
    }
    if (k == n_ + 1) {
      return q_;
    }
    const Segment2& s = segs_[k - 1];
    return s.a + (s.b - s.a) * t[k - 1];
  }

  [[nodiscard]] double smoothed(const std::vector<double>& t, double mu) const {
    double f = 0.0;
    Vec2 prev = p_;
    for (std::size_t k = 1; k <= n_ + 1; ++k) {
      const Vec2 cur = point(k, t);
      f += std::sqrt((cur - prev).squaredNorm() + mu * mu);
      prev = cur;
    }
    return f;
  }

  int solve(std::vector<double>& t, const ConvexOptions& opt) const {
    int steps = 0;
    if (n_ == 0) {
      return 0;
    }
    const std::size_t n = std::min<std::size_t>(n_, std::size_t{1} << 40);
    std::vector<Vec2> u(n + 1);
    std::vector<Sym2> h(n + 1);
    std::vector<double> g(n), diag(n), off(n), delta(n), trial(n);
    std::vector<int> freeIdx;
    std::vector<double> cd, cs, cr;
    for (double muRel = opt.muStart; muRel >= opt.muEnd * 0.999; muRel *= 0.1) {
      const double mu = muRel * scale_;
      for (int it = 0; it < opt.maxNewtonPerStage; ++it) {
        // Edge k joins point k and k+1; its smoothed length sqrt(|d|^2+mu^2) has gradient d/phi and
        // Hessian (I - d d^T / phi^2) / phi.
        Vec2 prev = p_;
        for (std::size_t k = 0; k <= n_; ++k) {
          const Vec2 cur = point(k + 1, t);
          const Vec2 d = cur - prev;
          const double phi = std::sqrt(d.squaredNorm() + mu * mu);
          u[k] = d / phi;
          const double inv = 1.0 / phi;
          h[k] = {(1.0 - u[k].x * u[k].x) * inv, -u[k].x * u[k].y * inv, (1.0 - u[k].y * u[k].y) * inv};
          prev = cur;
        }
        double maxDiag = 0.0;
        for (std::size_t j = 0; j < n_; ++j) {
          const Vec2 e = segs_[j].b - segs_[j].a;
          g[j] = e.dot(u[j] - u[j + 1]);
          diag[j] = h[j].quad(e, e) + h[j + 1].quad(e, e);
          off[j] = j + 1 < n_ ? -h[j + 1].quad(e, segs_[j + 1].b - segs_[j + 1].a) : 0.0;
          maxDiag = std::max(maxDiag, diag[j]);
        }
        const double lambda = 1e-13 * maxDiag + 1e-300;
        // Variables held at a bound with the gradient pushing outwards stay there (projected Newton).
        freeIdx.clear();
        double pg = 0.0;
        for (std::size_t j = 0; j < n_; ++j) {
          pg = std::max(pg, std::abs(t[j] - std::clamp(t[j] - g[j], 0.0, 1.0)));
          const bool atLo = t[j] <= 0.0 && g[j] > 0.0;
          const bool atHi = t[j] >= 1.0 && g[j] < 0.0;
          delta[j] = 0.0;
          if (!atLo && !atHi) {
            freeIdx.push_back(static_cast<int>(j));
          }
        }
        if (pg < 1e-16 || freeIdx.empty()) {
          break;
        }
        // Thomas algorithm on the free block (still tridiagonal: couplings only between neighbours).
        const std::size_t m = freeIdx.size();
        cd.assign(m, 0.0);
        cs.assign(m, 0.0);
        cr.assign(m, 0.0);
        for (std::size_t k = 0; k < m; ++k) {
          const auto j = static_cast<std::size_t>(freeIdx[k]);
          cd[k] = diag[j] + lambda;
          cr[k] = -g[j];
          cs[k] = (k + 1 < m && freeIdx[k + 1] == freeIdx[k] + 1) ? off[j] : 0.0;
        }
        for (std::size_t k = 1; k < m; ++k) {
          const double w = cs[k - 1] / cd[k - 1];
          cd[k] -= w * cs[k - 1];
          cr[k] -= w * cr[k - 1];
        }
        for (std::size_t k = m; k-- > 0;) {
          const double nextX = k + 1 < m ? cr[k + 1] : 0.0;
          cr[k] = (cr[k] - cs[k] * nextX) / cd[k];
        }
        for (std::size_t k = 0; k < m; ++k) {
          delta[static_cast<std::size_t>(freeIdx[k])] = cr[k];
        }
        const double f0 = smoothed(t, mu);
        double alpha = 1.0;
        bool improved = false;
        double moved = 0.0;
        for (int ls = 0; ls < 60; ++ls) {
          moved = 0.0;
          for (std::size_t j = 0; j < n_; ++j) {
            trial[j] = std::clamp(t[j] + alpha * delta[j], 0.0, 1.0);
            moved = std::max(moved, std::abs(trial[j] - t[j]));
          }
          if (smoothed(trial, mu) < f0) {
            improved = true;
            break;
          }
          alpha *= 0.5;
        }
        ++steps;
        if (!improved) {
          break;
        }
        t.swap(trial);
        if (moved < 1e-15) {
          break;
        }
      }
    }
    return steps;
  }

  [[nodiscard]] SegmentPath result(const std::vector<double>& t, int steps) const {
    SegmentPath r;
    r.params = t;
    for (std::size_t k = 0; k <= n_ + 1; ++k) {
      r.points.push_back(point(k, t));
    }
    r.length = polylineLength(r.points);
    r.iterations = steps;
    r.converged = true;
    return r;
  }

 private:
  Vec2 p_, q_;
  const std::vector<Segment2>& segs_;
  std::size_t n_;
  double scale_ = 1.0;
};

}  // namespace

SegmentPath shortestPathConvex(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, std::vector<double> t0,
                               const ConvexOptions& opt) {
  ConvexChain chain(p, q, segs);
  t0.resize(segs.size(), 0.0);
  const int steps = chain.solve(t0, opt);
  return chain.result(t0, steps);
}

SegmentPath shortestPathConvex(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, const ConvexOptions& opt) {
  return shortestPathConvex(p, q, segs, std::vector<double>(segs.size(), 0.0), opt);
}

}  // namespace fleet::geometry
