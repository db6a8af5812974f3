#include "fleet/risk/gaussian.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fleet::risk {
namespace {

constexpr double kPi = std::numbers::pi;

// Regularized lower incomplete gamma P(s, x) for integer s >= 1 (= P(Poisson(x) >= s)), given
// lgs = lgamma(s) and logX = log(x), which the caller has at hand.
double lowerGammaInt(int s, double x, double lgs, double logX) {
  if (x <= 0.0) {
    return 0.0;
  }
  const double sd = static_cast<double>(s);
  if (sd <= x) {
    // Q(s, x) = Σ_{j<s} Pois(j; x), summed from j = s − 1 downwards: below the mode x the terms shrink
    // at least geometrically, so the sum stops after O(sqrt(x)) terms.
    double term = std::exp(-x + (sd - 1.0) * logX - lgs);
    double q = 0.0;
    const double invX = 1.0 / x;
    for (int j = s - 1; j >= 0; --j) {
      q += term;
      if (term < 1e-18 * q) {
        break;
      }
      term *= static_cast<double>(j) * invX;
    }
    return std::clamp(1.0 - q, 0.0, 1.0);
  }
  // P(s, x) = e^{-x} x^s / s! · Σ_n x^n / ((s+1)…(s+n)); converges geometrically since s > x.
  const double lead = std::exp(-x + sd * logX - lgs - std::log(sd));
  double term = 1.0;
  double sum = 1.0;
  for (int n = 1; n < 100000; ++n) {
    term *= x / (sd + static_cast<double>(n));
    sum += term;
    if (term < 1e-17 * sum) {
      break;
    }
  }
  return std::clamp(lead * sum, 0.0, 1.0);
}

// erf(hi) − erf(lo) for lo <= hi without cancellation in the tails.
double erfDiff(double lo, double hi) {
  if (lo >= 0.0) {
    return std::erfc(lo) - std::erfc(hi);
  }
  if (hi <= 0.0) {
    return std::erfc(-hi) - std::erfc(-lo);
  }
  return std::erf(hi) - std::erf(lo);
}

}  // namespace

double gaussianCollisionProbability(double d, double R, double sigma) {
  if (!(R > 0.0)) {
    return 0.0;
  }
  d = std::abs(d);
  if (!(sigma > 0.0)) {
    return d < R ? 1.0 : 0.0;
  }
  // Outside 9 sigma of the rim the answer is 0 or 1 to within exp(−40.5) < 3e-18 (Rayleigh tail bound
  // on ‖x − μ‖), which also keeps the series below short.
  if (d - R > 9.0 * sigma) {
    return 0.0;
  }
  if (R - d > 9.0 * sigma) {
    return 1.0;
  }
  const double s2 = 2.0 * sigma * sigma;
  const double a = d * d / s2;  // half the noncentrality λ/2
  const double b = R * R / s2;  // half the χ² argument x/2
  if (a == 0.0) {
    return -std::expm1(-b);
  }
  // P = Σ_k Pois(k; a) · P(k + 1, b). Terms above kHi are below 1e-20 because either the Poisson(a)
  // tail or P(k + 1, b) is; summing downwards keeps every recurrence an addition of positive terms.
  const double ka = a + 9.0 * std::sqrt(a) + 10.0;
  const double kb = b + 9.0 * std::sqrt(b) + 10.0;
  const bool fullUpperTail = ka <= kb;
  const int kHi = static_cast<int>(std::ceil(std::min(ka, kb)));
  const double kHiD = static_cast<double>(kHi);
  const double lgk = std::lgamma(kHiD + 1.0);
  const double logB = std::log(b);
  const double logPa0 = -a + kHiD * std::log(a) - lgk;
  // Poisson(a) weights are carried relative to Pois(kHi; a): with a in the thousands, exp(logPa0) has a
  // relative error of ~1e-12 from lgamma, which normalising by the summed weights removes.
  const double stopWeight = 1e-20 * std::exp(-logPa0);
  double g = lowerGammaInt(kHi + 1, b, lgk, logB);  // P(k + 1, b)
  double pb = std::exp(-b + kHiD * logB - lgk);     // Pois(k; b)
  double w = 1.0;                                   // Pois(k; a) / Pois(kHi; a)
  double sum = 0.0;
  double weights = 0.0;
  const double invA = 1.0 / a;
  const double invB = 1.0 / b;
  for (int k = kHi; k >= 0; --k) {
    sum += w * g;
    weights += w;
    const double kd = static_cast<double>(k);
    if (kd < a && w < stopWeight) {
      break;  // below the Poisson mode every further term is smaller still
    }
    g += pb;  // P(k, b) = P(k + 1, b) + Pois(k; b)
    w *= kd * invA;
    pb *= kd * invB;
  }
  if (fullUpperTail && weights > 0.0) {  // the loop covered all but 1e-20 of the Poisson(a) mass
    return std::clamp(sum / weights, 0.0, 1.0);
  }
  sum *= std::exp(logPa0);
  return std::clamp(sum, 0.0, 1.0);
}

double gaussianCollisionProbability(Vec2 mean, const Cov2& cov, double R, int thetaSteps) {
  if (!(R > 0.0)) {
    return 0.0;
  }
  const double det = cov.xx * cov.yy - cov.xy * cov.xy;
  const double tr = cov.xx + cov.yy;
  const double disc =
      std::sqrt(std::max(0.0, 0.25 * (cov.xx - cov.yy) * (cov.xx - cov.yy) + cov.xy * cov.xy));
  const double lmax = 0.5 * tr + disc;
  const double lmin = 0.5 * tr - disc;
  if (!(lmin > 1e-12 * std::max(lmax, 1e-300)) || !(det > 0.0)) {
    return gaussianCollisionProbability(mean.norm(), R, std::sqrt(std::max(lmax, 0.0)));
  }
  // Inverse covariance W.
  const double wxx = cov.yy / det;
  const double wxy = -cov.xy / det;
  const double wyy = cov.xx / det;
  const double gamma = mean.x * (wxx * mean.x + wxy * mean.y) + mean.y * (wxy * mean.x + wyy * mean.y);
  const double smin = std::sqrt(lmin);
  const double dist = mean.norm();
  // Far outside the disc the whole integral is below exp(−40.5) (tail bound with the largest sigma).
  if (dist - R > 9.0 * std::sqrt(lmax)) {
    return 0.0;
  }
  int n = thetaSteps;
  if (n <= 0) {
    // Seen from the disc centre the Gaussian spans an angle of about sigma_min / max(|μ|, sigma_min);
    // the trapezoid rule on a periodic peak of that width is accurate to ~1e-12 with 8 points per width.
    const double width = smin / std::max(dist, smin);
    n = static_cast<int>(std::clamp(std::ceil(8.0 * 2.0 * kPi / width / 4.0) * 4.0, 32.0, 4096.0));
  }
  const double eg = std::exp(-0.5 * gamma);
  double sum = 0.0;
  const double dth = 2.0 * kPi / static_cast<double>(n);
  // Unit vectors by rotation (re-seeded every 64 steps against drift) instead of cos/sin per point.
  const double cr = std::cos(dth);
  const double sr = std::sin(dth);
  double ux = std::cos(0.5 * dth);
  double uy = std::sin(0.5 * dth);
  for (int i = 0; i < n; ++i) {
    if ((i & 63) == 0 && i > 0) {
      const double th = (static_cast<double>(i) + 0.5) * dth;
      ux = std::cos(th);
      uy = std::sin(th);
    }
    // Along the ray r·u the exponent is −½(α r² − 2 β r + γ).
    const double alpha = ux * (wxx * ux + wxy * uy) + uy * (wxy * ux + wyy * uy);
    const double beta = ux * (wxx * mean.x + wxy * mean.y) + uy * (wxy * mean.x + wyy * mean.y);
    const double m = beta / alpha;
    const double rc = std::clamp(m, 0.0, R);
    const double qMin = alpha * rc * rc - 2.0 * beta * rc + gamma;
    if (qMin < 92.0) {  // rays whose density stays below exp(−46) everywhere on [0, R] add nothing
      const double qR = alpha * R * R - 2.0 * beta * R + gamma;
      // ∫0^R r e^{−q/2} dr = (e^{−γ/2} − e^{−q(R)/2})/α + m √(π/(2α)) e^{−(γ − β m)/2} [erf(..) − erf(..)]
      const double part1 = (eg - std::exp(-0.5 * qR)) / alpha;
      const double sq = std::sqrt(0.5 * alpha);
      const double part2 = m * std::sqrt(kPi / (2.0 * alpha)) * std::exp(-0.5 * (gamma - beta * m)) *
                           erfDiff(-m * sq, (R - m) * sq);
      sum += part1 + part2;
    }
    const double nx = ux * cr - uy * sr;
    uy = ux * sr + uy * cr;
    ux = nx;
  }
  const double p = sum * dth / (2.0 * kPi * std::sqrt(det));
  return std::clamp(p, 0.0, 1.0);
}

Gaussian::Gaussian(double floor)
    : floor_(std::clamp(floor, 1e-300, 1.0)),
      tailSigmas_(std::sqrt(2.0 * std::log(1.0 / floor_)) * 1.001 + 1e-9) {}

double Gaussian::pair(const Disc& a, const Disc& b) const {
  const double sigma = std::sqrt(a.sigma * a.sigma + b.sigma * b.sigma);
  const double d = centreDistance(a, b);
  if (d >= cullDistance(a, b)) {
    return 0.0;
  }
  const double p = gaussianCollisionProbability(d, a.r + b.r, sigma);
  return p < floor_ ? 0.0 : p;
}

double Gaussian::cullDistance(const Disc& a, const Disc& b) const {
  // P(‖x − μ‖ ≥ t) = exp(−t²/(2σ²)) for a 2D isotropic Gaussian, and collision needs ‖x − μ‖ ≥ d − R,
  // so beyond R + σ·sqrt(2 ln(1/floor)) the probability is below the floor.
  return a.r + b.r + std::sqrt(a.sigma * a.sigma + b.sigma * b.sigma) * tailSigmas_;
}

double Gaussian::reach(const Disc& a) const {
  return a.r + a.sigma * tailSigmas_;
}

}  // namespace fleet::risk
