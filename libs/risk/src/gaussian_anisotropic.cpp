// Anisotropic Gaussian collision probability by an eigen-axis trapezoid rule (docs/algorithms.md, risk).
#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "fleet/risk/gaussian.hpp"

namespace fleet::risk {
namespace {

constexpr double kInvSqrt2 = 0.70710678118654752440;
constexpr double kInvSqrt2Pi = 0.39894228040143267794;
// Upper bound on the step when both sigmas are large against R (the circle itself is the feature).
constexpr double kMaxStep = std::numbers::pi / 8.0;
// Below this eigenvalue split (relative) the covariance is isotropic to ~1e-12 in P: Marcum-Q series.
constexpr double kIsotropicSplit = 1e-12;

// The exact evaluation. Normal mass beyond 9 sigma is Φ(−9) = 1.1e-19: nodes and terms out there are
// left out. Trapezoid step as a fraction of the narrowest feature (in θ) of the integrand: the trapezoid
// rule on a Gaussian of unit width errs by ~2·exp(−2π²/Δt²), 1e-13 at Δt = 0.8 (see kStepFraction's
// test).
struct ExactNormal {
  static constexpr double kWindow = 9.0;
  static constexpr double kSkipT2 = 8.5 * 8.5;
  static constexpr double kStepFraction = 0.85;
  static double upperTail(double x) { return 0.5 * std::erfc(x * kInvSqrt2); }  // 1 − Φ(x)
  static double isotropic(double d, double R, double sigma) {
    return gaussianCollisionProbability(d, R, sigma);
  }
};

// The fast path: 1 − Φ from a cubic table (step 1/64, error ≤ 2e-9), a window of 7.5 sigma (Φ(−7.5) =
// 3e-14), nodes up to 7 sigma (e^{−24.5} = 2e-11 of the peak) and a step of one feature width (trapezoid
// error ~2·exp(−2π²) = 5e-9 of P): within kGaussianTableTolerance, measured in gaussian_fast_test.
struct TabulatedNormal {
  static constexpr double kWindow = 7.5;
  static constexpr double kSkipT2 = 7.0 * 7.0;
  static constexpr double kStepFraction = 1.0;
  static constexpr double kStep = 1.0 / 64.0;
  static constexpr int kPad = 2;
  static constexpr int kNodes = static_cast<int>(2.0 * kWindow / kStep) + 1 + 2 * kPad;
  struct Table {
    std::array<double, kNodes> q{};
    Table() {
      for (int i = 0; i < kNodes; ++i) {
        q[static_cast<std::size_t>(i)] = ExactNormal::upperTail((i - kPad) * kStep - kWindow);
      }
    }
  };
  static const Table& table() {
    static const Table t;
    return t;
  }
  static double upperTail(double x) {
    if (x >= kWindow) {
      return 0.0;
    }
    if (x <= -kWindow) {
      return 1.0;
    }
    const double f = (x + kWindow) / kStep + kPad;
    const int i = static_cast<int>(f);
    const double t = f - i;
    const double tm1 = t - 1.0;
    const double tm2 = t - 2.0;
    const double tp1 = t + 1.0;
    const double* q = table().q.data() + (i - 1);
    return -t * tm1 * tm2 * (1.0 / 6.0) * q[0] + tp1 * tm1 * tm2 * 0.5 * q[1] - tp1 * t * tm2 * 0.5 * q[2] +
           tp1 * t * tm1 * (1.0 / 6.0) * q[3];
  }
  static double isotropic(double d, double R, double sigma) {
    return gaussianCollisionProbabilityTabulated(d, R, sigma);
  }
};

// P(−w ≤ x2 ≤ w) for x2 ~ N(m2, s2²), m2 ≥ 0, w ≥ 0: the chord's share of the major-axis normal. Each
// tail as an upper tail so that small probabilities keep their relative accuracy.
template <class N>
double chordProbability(double w, double m2, double invS2) {
  const double a = (w - m2) * invS2;
  if (a < -N::kWindow) {
    return 0.0;
  }
  const double nb = (w + m2) * invS2;                               // −b, b = (−w − m2)/s2 ≤ a
  const double lowTail = nb > N::kWindow ? 0.0 : N::upperTail(nb);  // Φ(b)
  if (a <= 0.0) {
    return N::upperTail(-a) - lowTail;  // Φ(a) − Φ(b), both lower tails
  }
  const double highTail = a > N::kWindow ? 0.0 : N::upperTail(a);  // 1 − Φ(a)
  return 1.0 - highTail - lowTail;
}

template <class N>
double anisotropicProbability(Vec2 mean, const Cov2& cov, double R, double floor) {
  constexpr double kWindow = N::kWindow;
  constexpr double kSkipT2 = N::kSkipT2;
  constexpr double kStepFraction = N::kStepFraction;
  if (!(R > 0.0)) {
    return 0.0;
  }
  const double half = 0.5 * (cov.xx - cov.yy);
  const double split = std::sqrt(half * half + cov.xy * cov.xy);
  const double lmax = 0.5 * (cov.xx + cov.yy) + split;
  const double dist = mean.norm();
  if (!(lmax > 0.0)) {
    return dist < R ? 1.0 : 0.0;  // no uncertainty: the indicator, as the isotropic formula
  }
  const double s2 = std::sqrt(lmax);
  // Tail bound with the largest sigma: P(‖x − mean‖ ≥ t) ≤ exp(−t²/(2 s2²)).
  const double gap = (dist - R) / s2;
  if (gap > kWindow || (gap > 0.0 && std::exp(-0.5 * gap * gap) < floor)) {
    return 0.0;
  }
  if (-gap > kWindow) {
    return 1.0;
  }
  if (split <= kIsotropicSplit * lmax) {
    return N::isotropic(dist, R, std::sqrt(0.5 * (cov.xx + cov.yy)));
  }
  // Major axis (eigenvector of lmax) from the row of (cov − lmax I) that does not cancel.
  double ex = 0.0;
  double ey = 0.0;
  if (cov.xx >= cov.yy) {
    ex = lmax - cov.yy;
    ey = cov.xy;
  } else {
    ex = cov.xy;
    ey = lmax - cov.xx;
  }
  const double en = 1.0 / std::sqrt(ex * ex + ey * ey);
  ex *= en;
  ey *= en;
  // The disc is symmetric under x2 → −x2, so the major-axis mean can be taken ≥ 0.
  const double m2 = std::abs(ex * mean.x + ey * mean.y);
  const double m1 = ex * mean.y - ey * mean.x;
  const double invS2 = 1.0 / s2;
  const double lmin = (cov.xx * cov.yy - cov.xy * cov.xy) / lmax;
  if (!(lmin > 0.0)) {
    // Singular covariance: the mass lies on the line x1 = m1 (the exact one-dimensional answer).
    if (!(std::abs(m1) < R)) {
      return 0.0;
    }
    return std::clamp(chordProbability<N>(std::sqrt((R - m1) * (R + m1)), m2, invS2), 0.0, 1.0);
  }
  const double s1 = std::sqrt(lmin);
  const double lo = m1 - kWindow * s1;
  const double hi = m1 + kWindow * s1;
  if (lo >= R || hi <= -R) {
    return 0.0;
  }
  // P = ∫ φ((x1 − m1)/s1)/s1 · chord(√(R² − x1²)) dx1 over |x1| ≤ R; with x1 = R sin θ the integrand
  // f(θ) = R cos θ · φ(·)/s1 · chord(R cos θ) is analytic and f(π − θ) = f(θ), so it is even about ±π/2:
  // a trapezoid rule whose nodes are symmetric about an end of [−π/2, π/2] inside the window, or any
  // nodes when neither end is, converges geometrically. Its narrowest feature is the normal in x1
  // (width s1/(R cos θ), widest cos in the window) or the chord's edge (width s2/(R |sin θ|) ≥ s2/R).
  const bool top = hi >= R;
  const bool bottom = lo <= -R;
  double cmax = 1.0;
  if (lo > 0.0) {
    cmax = std::sqrt((R - lo) * (R + lo)) / R;
  } else if (hi < 0.0) {
    cmax = std::sqrt((R - hi) * (R + hi)) / R;
  }
  const double k1 = R * cmax / s1;
  const double k2 = R / s2;
  double h = kStepFraction / std::sqrt(k1 * k1 + k2 * k2 + 1.0 / (kMaxStep * kMaxStep));
  // Nodes θ = θref + d·δ, δ = (j + off)·h; sin and cos of θ by the addition formulas from
  // (sθ, cθ) = (sin θref, cos θref) and (sin δ, 1 − cos δ), which keeps x1 − m1 accurate to the scale of
  // s1 however small s1 is. e0 = R sθ − m1.
  double sth = 0.0;
  double cth = 0.0;
  double e0 = 0.0;
  double off = 0.5;
  int passes = 1;
  int dir = 1;
  long maxNodes = 1L << 40;
  if (top && bottom) {
    const double m = std::ceil(std::numbers::pi / h);  // periodic case: h divides π
    h = std::numbers::pi / m;
    maxNodes = static_cast<long>(m);
    sth = -1.0;
    e0 = -R - m1;
  } else if (top) {
    sth = 1.0;
    e0 = R - m1;
    dir = -1;
  } else if (bottom) {
    sth = -1.0;
    e0 = -R - m1;
  } else {
    sth = m1 / R;
    cth = std::sqrt((1.0 - sth) * (1.0 + sth));
    off = 0.0;
    passes = 2;
  }
  const double sh = std::sin(h);
  const double sh2 = std::sin(0.5 * h);
  const double vh = 2.0 * sh2 * sh2;  // 1 − cos h
  const double invS1 = 1.0 / s1;
  double sum = 0.0;
  for (int pass = 0; pass < passes; ++pass) {
    const double d = pass == 0 ? static_cast<double>(dir) : -static_cast<double>(dir);
    // The centre case's second pass starts one step out (δ = 0 was the first pass's node).
    const double d0 = pass == 0 ? off * h : h;
    double s = std::sin(d0);
    const double sd0 = std::sin(0.5 * d0);
    double vc = 2.0 * sd0 * sd0;
    for (long j = 0; j < maxNodes; ++j) {
      const double t = (e0 - R * sth * vc + d * R * cth * s) * invS1;
      const double w = R * cth * (1.0 - vc) - d * R * sth * s;
      // Leaving the window (x1 is monotone in δ) or passing an end of [−π/2, π/2]: done.
      if (w < 0.0 || d * t > kWindow) {
        break;
      }
      // Nodes beyond 8.5 s1 from the mean weigh < 2e-16 of the peak: no chord (erfc) for them.
      if (t * t < kSkipT2) {
        sum += w * std::exp(-0.5 * t * t) * chordProbability<N>(w, m2, invS2);
      }
      const double ns = s - s * vh + sh - vc * sh;
      vc = vc + vh - vc * vh + s * sh;
      s = ns;
    }
  }
  return std::clamp(sum * h * invS1 * kInvSqrt2Pi, 0.0, 1.0);
}

}  // namespace

double gaussianCollisionProbability(Vec2 mean, const Cov2& cov, double R, double floor) {
  return anisotropicProbability<ExactNormal>(mean, cov, R, floor);
}

double gaussianCollisionProbabilityFast(Vec2 mean, const Cov2& cov, double R, double floor) {
  return anisotropicProbability<TabulatedNormal>(mean, cov, R, floor);
}

}  // namespace fleet::risk
