#include "fleet/risk/gaussian.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace fleet::risk {
namespace {

constexpr double kPi = std::numbers::pi;

// Regularized lower incomplete gamma P(s, x) for integer s >= 1 (= P(Poisson(x) >= s)).
double lowerGammaInt(int s, double x) {
  if (x <= 0.0) {
    return 0.0;
  }
  const double sd = static_cast<double>(s);
  if (sd <= x) {
    // Q(s, x) = e^{-x} Σ_{j<s} x^j / j!: a finite sum of positive terms.
    double term = std::exp(-x);
    double q = term;
    for (int j = 1; j < s; ++j) {
      term *= x / static_cast<double>(j);
      q += term;
    }
    return std::clamp(1.0 - q, 0.0, 1.0);
  }
  // P(s, x) = e^{-x} x^s / s! · Σ_n x^n / ((s+1)…(s+n)); converges geometrically since s > x.
  const double lead = std::exp(-x + sd * std::log(x) - std::lgamma(sd + 1.0));
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
  const double logPa0 = -a + kHiD * std::log(a) - std::lgamma(kHiD + 1.0);
  // Poisson(a) weights are carried relative to Pois(kHi; a): with a in the thousands, exp(logPa0) has a
  // relative error of ~1e-12 from lgamma, which normalising by the summed weights removes.
  const double stopWeight = 1e-20 * std::exp(-logPa0);
  double g = lowerGammaInt(kHi + 1, b);                                     // P(k + 1, b)
  double pb = std::exp(-b + kHiD * std::log(b) - std::lgamma(kHiD + 1.0));  // Pois(k; b)
  double w = 1.0;                                                           // Pois(k; a) / Pois(kHi; a)
  double sum = 0.0;
  double weights = 0.0;
  for (int k = kHi; k >= 0; --k) {
    sum += w * g;
    weights += w;
    const double kd = static_cast<double>(k);
    if (kd < a && w < stopWeight) {
      break;  // below the Poisson mode every further term is smaller still
    }
    g += pb;  // P(k, b) = P(k + 1, b) + Pois(k; b)
    w *= kd / a;
    pb *= kd / b;
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
  int n = thetaSteps;
  if (n <= 0) {
    // The angular integrand is peaked with a width of about sigma_min / R radians; 8 points per
    // width make the trapezoid rule (exponentially convergent on periodic integrands) exact to ~1e-12.
    const double perWidth = 8.0 * 2.0 * kPi * R / std::sqrt(lmin);
    n = static_cast<int>(std::clamp(std::ceil(perWidth / 8.0) * 8.0, 64.0, 8192.0));
  }
  const double eg = std::exp(-0.5 * gamma);
  double sum = 0.0;
  const double dth = 2.0 * kPi / static_cast<double>(n);
  for (int i = 0; i < n; ++i) {
    const double th = (static_cast<double>(i) + 0.5) * dth;
    const double ux = std::cos(th);
    const double uy = std::sin(th);
    // Along the ray r·u the exponent is −½(α r² − 2 β r + γ).
    const double alpha = ux * (wxx * ux + wxy * uy) + uy * (wxy * ux + wyy * uy);
    const double beta = ux * (wxx * mean.x + wxy * mean.y) + uy * (wxy * mean.x + wyy * mean.y);
    const double m = beta / alpha;
    const double qR = alpha * R * R - 2.0 * beta * R + gamma;
    // ∫0^R r e^{−q/2} dr = (e^{−γ/2} − e^{−q(R)/2})/α + m √(π/(2α)) e^{−(γ − β²/α)/2} [erf]…
    const double part1 = (eg - std::exp(-0.5 * qR)) / alpha;
    const double s = std::sqrt(0.5 * alpha);
    const double part2 = m * std::sqrt(kPi / (2.0 * alpha)) * std::exp(-0.5 * (gamma - beta * m)) *
                         erfDiff(-m * s, (R - m) * s);
    sum += part1 + part2;
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
