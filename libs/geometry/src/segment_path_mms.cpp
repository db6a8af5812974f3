#include <algorithm>
#include <cmath>
#include <vector>

#include "fleet/geometry/segment_path.hpp"

namespace fleet::geometry {

namespace {

// A point of the current path together with its place in the segment order: the segments up to
// `lastDone` are already touched before it, the next one to touch is `lastDone + 1`.
struct PathPoint {
  Vec2 at;
  int lastDone = -1;
};

class Mms {
 public:
  Mms(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, const MmsOptions& opt)
      : p_(p), q_(q), segs_(segs), opt_(opt), n_(static_cast<int>(segs.size())) {
    buildCuts(std::max(1, opt.subsequence));
    if (!opt.cuts.empty()) {
      cuts_.clear();
      for (int k : opt.cuts) {
        if (k >= 0 && k < n_ && (cuts_.empty() || k > cuts_.back())) {
          cuts_.push_back(k);
        }
      }
    }
    t_.assign(segs.size(), 0.0);  // shooting points start at the bundle vertices (skeleton side)
  }

  SegmentPath run() {
    SegmentPath out;
    solveSubPaths();
    double len = length();
    out.lengthHistory.push_back(len);
    int iter = 0;
    bool converged = false;
    while (iter < opt_.maxIterations) {
      std::vector<PathPoint> tp(cuts_.size() + 1);
      for (std::size_t i = 0; i <= cuts_.size(); ++i) {
        tp[i] = midPoint(i);
      }
      std::vector<double> next = t_;
      bool flag = true;
      for (std::size_t i = 1; i <= cuts_.size(); ++i) {
        const int cut = cuts_[i - 1];
        if (collinear(cut)) {
          continue;
        }
        flag = false;
        // SP(t_{i-1}, t_i) through the segments between them (the cutting segment among them); the new
        // shooting point is where it touches the cutting segment.
        const int first = tp[i - 1].lastDone + 1;
        const int last = tp[i].lastDone;
        std::vector<Segment2> sub(segs_.begin() + first, segs_.begin() + last + 1);
        std::vector<double> warm(t_.begin() + first, t_.begin() + last + 1);
        const SegmentPath sp = shortestPathConvex(tp[i - 1].at, tp[i].at, sub, warm, inner_);
        next[static_cast<std::size_t>(cut)] = sp.params[static_cast<std::size_t>(cut - first)];
      }
      if (flag) {
        converged = true;
        break;
      }
      ++iter;
      // Once the first sub-paths are solved, warm starts are close: skip the coarse smoothing stages.
      inner_.muStart = 1e-6;
      t_ = next;
      solveSubPaths();
      const double newLen = length();
      out.lengthHistory.push_back(newLen);
      if (len - newLen <= opt_.lengthTol * len) {
        // Stalled although some collinear condition fails: this happens when neighbouring shooting
        // points coincide (cutting segments sharing a bundle vertex), where moving one point at a
        // time cannot shorten the path. Merge neighbouring sub-sequences; with a single sub-sequence
        // the inner solver is exact.
        if (cuts_.empty()) {
          converged = true;
          len = std::min(len, newLen);
          break;
        }
        buildCuts(2 * sub_);
        ++out.merges;
        solveSubPaths();
      }
      len = newLen;
    }
    out.params = t_;
    out.points = points();
    out.length = polylineLength(out.points);
    out.iterations = iter;
    out.converged = converged;
    return out;
  }

 private:
  void buildCuts(int c) {
    sub_ = c;
    cuts_.clear();
    for (int k = c - 1; k < n_; k += c) {
      cuts_.push_back(k);  // the last segment of each sub-sequence is a cutting segment
    }
  }

  [[nodiscard]] Vec2 at(int k) const {
    if (k < 0) {
      return p_;
    }
    if (k >= n_) {
      return q_;
    }
    const Segment2& s = segs_[static_cast<std::size_t>(k)];
    return s.a + (s.b - s.a) * t_[static_cast<std::size_t>(k)];
  }
  [[nodiscard]] std::vector<Vec2> points() const {
    std::vector<Vec2> pts;
    for (int k = -1; k <= n_; ++k) {
      pts.push_back(at(k));
    }
    return pts;
  }
  [[nodiscard]] double length() const { return polylineLength(points()); }

  // Boundaries of sub-path i: the shooting points on cuts i-1 and i (p and q at the ends).
  [[nodiscard]] int lo(std::size_t i) const { return i == 0 ? -1 : cuts_[i - 1]; }
  [[nodiscard]] int hi(std::size_t i) const { return i == cuts_.size() ? n_ : cuts_[i]; }

  void solveSubPaths() {
    for (std::size_t i = 0; i <= cuts_.size(); ++i) {
      const int a = lo(i);
      const int b = hi(i);
      if (b - a <= 1) {
        continue;
      }
      std::vector<Segment2> sub(segs_.begin() + a + 1, segs_.begin() + b);
      std::vector<double> warm(t_.begin() + a + 1, t_.begin() + b);
      const SegmentPath sp = shortestPathConvex(at(a), at(b), sub, warm, inner_);
      std::copy(sp.params.begin(), sp.params.end(), t_.begin() + a + 1);
    }
  }

  // t_i of the seed: a point of SP(s_i, s_{i+1}) strictly between them. We take the touch point of
  // the middle interior segment (a bend point when the sub-path bends there), or the midpoint when
  // the sub-path has no interior segment.
  [[nodiscard]] PathPoint midPoint(std::size_t i) const {
    const int a = lo(i);
    const int b = hi(i);
    if (b - a <= 1) {
      return {(at(a) + at(b)) * 0.5, a};
    }
    const int mid = a + 1 + (b - a - 2) / 2;
    return {at(mid), mid};
  }

  // Collinear condition at the shooting point on segment k, as a first-order optimality test of
  // f(x) = |x - prev| + |x - next| along the segment (the seed's angle test, with a tolerance).
  [[nodiscard]] bool collinear(int k) const {
    const Segment2& s = segs_[static_cast<std::size_t>(k)];
    const Vec2 e = s.b - s.a;
    const double el = e.norm();
    if (el == 0.0) {
      return true;
    }
    const Vec2 x = at(k);
    const double eps = 1e-14 * (el + (q_ - p_).norm());
    Vec2 prev = x;
    for (int j = k - 1; j >= -1 && (prev - x).norm() <= eps; --j) {
      prev = at(j);
    }
    Vec2 next = x;
    for (int j = k + 1; j <= n_ && (next - x).norm() <= eps; ++j) {
      next = at(j);
    }
    Vec2 grad{};
    if ((x - prev).norm() > eps) {
      grad += (x - prev).normalized();
    }
    if ((x - next).norm() > eps) {
      grad += (x - next).normalized();
    }
    const double slope = grad.dot(e / el);
    const double tk = t_[static_cast<std::size_t>(k)];
    if (tk <= 0.0) {
      return slope >= -opt_.angleTol;
    }
    if (tk >= 1.0) {
      return slope <= opt_.angleTol;
    }
    return std::abs(slope) <= opt_.angleTol;
  }

  Vec2 p_, q_;
  const std::vector<Segment2>& segs_;
  MmsOptions opt_;
  int n_;
  std::vector<int> cuts_;
  int sub_ = 1;
  ConvexOptions inner_{};
  std::vector<double> t_;
};

}  // namespace

SegmentPath shortestPathMms(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, const MmsOptions& opt) {
  return Mms(p, q, segs, opt).run();
}

}  // namespace fleet::geometry
