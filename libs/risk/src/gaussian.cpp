#include "fleet/risk/gaussian.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace fleet::risk {
namespace {

constexpr double kPi = std::numbers::pi;
// Up to this b = R²/(2σ²) the isotropic series is summed upwards from j = 0 (at most ~270 terms).
constexpr double kUpwardMaxB = 150.0;

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

// 1/j for the Poisson recurrences (a table lookup instead of a division per term).
constexpr int kInvTable = 512;
constexpr std::array<double, kInvTable> kInv = [] {
  std::array<double, kInvTable> t{};
  for (int j = 1; j < kInvTable; ++j) {
    t[static_cast<std::size_t>(j)] = 1.0 / static_cast<double>(j);
  }
  return t;
}();

// Σ_{k≥0} Pois(k; a) P(k + 1, b) rearranged as Σ_{j≥1} Pois(j; b) · P(Poisson(a) ≤ j − 1): both Poisson
// weights by upward recurrence from e^{−a}, e^{−b} (normal doubles for a, b < 700) and the Poisson(a) CDF
// by upward summation, so every operation adds or multiplies positive terms (no lgamma, no cancellation).
// Beyond jMax the remaining Poisson(b) mass, an upper bound on what is left out, is below 1e-17.
double marcumSeriesUpward(double a, double b, int jMax) {
  double pb = std::exp(-b);  // Pois(j; b)
  double w = std::exp(-a);   // Pois(j; a)
  double cdf = 0.0;          // P(Poisson(a) ≤ j − 1)
  double sum = 0.0;
  for (int j = 1; j <= jMax; ++j) {
    cdf += w;
    const double inv = kInv[static_cast<std::size_t>(j)];
    pb *= b * inv;
    w *= a * inv;
    sum += pb * cdf;
  }
  return std::clamp(sum, 0.0, 1.0);
}

// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre recurrence), computed once.
struct GaussLegendre {
  static constexpr int kN = 8;
  double x[kN];
  double w[kN];
  GaussLegendre() : x{}, w{} {
    for (int i = 0; i < kN; ++i) {
      double z = std::cos(kPi * (i + 0.75) / (kN + 0.5));
      double dp = 1.0;
      for (int it = 0; it < 100; ++it) {
        double p0 = 1.0;
        double p1 = z;
        for (int k = 2; k <= kN; ++k) {
          const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
          p0 = p1;
          p1 = p2;
        }
        dp = kN * (z * p1 - p0) / (z * z - 1.0);
        const double dz = p1 / dp;
        z -= dz;
        if (std::abs(dz) < 1e-16) {
          break;
        }
      }
      x[i] = z;
      w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
  }
};

const GaussLegendre& gaussLegendre() {
  static const GaussLegendre gl;
  return gl;
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
  // Small and moderate arguments (the usual case: a few sigma between the centres): the upward series
  // over j ≤ b + 9 sqrt(b) + 10 costs a few multiplications per term and two exp.
  if (b <= kUpwardMaxB && a < 600.0) {
    return marcumSeriesUpward(a, b, static_cast<int>(std::ceil(b + 9.0 * std::sqrt(b) + 10.0)));
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

double gaussianCollisionProbabilityPolar(Vec2 mean, const Cov2& cov, double R, int thetaSteps) {
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

double gaussianCollisionProbabilityWhitened(Vec2 mean, const Cov2& cov, double R) {
  if (!(R > 0.0)) {
    return 0.0;
  }
  const double tr = cov.xx + cov.yy;
  const double disc =
      std::sqrt(std::max(0.0, 0.25 * (cov.xx - cov.yy) * (cov.xx - cov.yy) + cov.xy * cov.xy));
  const double lmax = 0.5 * tr + disc;
  const double lmin = 0.5 * tr - disc;
  if (!(cov.xx > 0.0) || !(lmin > 1e-12 * std::max(lmax, 1e-300))) {
    return gaussianCollisionProbability(mean.norm(), R, std::sqrt(std::max(lmax, 0.0)));
  }
  const double dist = mean.norm();
  const double smax = std::sqrt(lmax);
  if (dist - R > 9.0 * smax) {
    return 0.0;  // Rayleigh tail bound with the largest sigma: below exp(−40.5)
  }
  if (R - dist > 9.0 * smax) {
    return 1.0;
  }
  // cov = L Lᵀ, L lower triangular; x = mean + L z. ‖x‖² ≤ R² along z = ρ v is A ρ² + 2 B ρ + C ≤ 0 with
  // A = vᵀ M v (M = LᵀL), B = bᵀ v (b = Lᵀ mean), C = ‖mean‖² − R².
  const double l11 = std::sqrt(cov.xx);
  const double l21 = cov.xy / l11;
  const double l22 = std::sqrt(std::max(cov.yy - l21 * l21, 1e-300));
  const double m11 = l11 * l11 + l21 * l21;
  const double m12 = l21 * l22;
  const double m22 = l22 * l22;
  const double b1 = l11 * mean.x + l21 * mean.y;
  const double b2 = l22 * mean.y;
  const double C = (dist - R) * (dist + R);
  // Angular detail scales with how far (in whitened units) the ellipse reaches and how curved it is.
  const double smin = std::sqrt(lmin);
  const double scale = 1.0 + (dist + R) / smin;
  const double elong = smax / smin;
  auto rayAB = [&](double c, double s, double& A, double& B) {
    A = m11 * c * c + 2.0 * m12 * c * s + m22 * s * s;
    B = b1 * c + b2 * s;
  };
  if (C < 0.0) {
    // Mean inside the disc: every ray leaves the ellipse once, at ρ+; integrand 1 − e^{−ρ+²/2}, smooth
    // and periodic, so the trapezoid rule converges geometrically (faster the rounder the ellipse).
    const int n =
        static_cast<int>(std::clamp(std::ceil(8.0 * (scale + 2.0 * elong) / 8.0) * 8.0, 32.0, 8192.0));
    const double dth = 2.0 * kPi / n;
    const double cr = std::cos(dth);
    const double sr = std::sin(dth);
    double c = std::cos(0.5 * dth);
    double s = std::sin(0.5 * dth);
    double sum = 0.0;
    for (int i = 0; i < n; ++i) {
      double A = 0.0, B = 0.0;
      rayAB(c, s, A, B);
      const double sq = std::sqrt(B * B - A * C);
      const double rho = B >= 0.0 ? -C / (B + sq) : (sq - B) / A;
      sum += -std::expm1(-0.5 * rho * rho);
      const double nc = c * cr - s * sr;  // next direction by rotation (n <= 8192: drift ~1e-12)
      s = c * sr + s * cr;
      c = nc;
    }
    return std::clamp(sum / n, 0.0, 1.0);
  }
  // Mean outside: rays hit the ellipse for vᵀ(b bᵀ − C M)v ≥ 0 with bᵀv < 0, an arc |θ − θm| ≤ h.
  // vᵀQv = α0 + α1 cos 2θ + α2 sin 2θ.
  const double q11 = b1 * b1 - C * m11;
  const double q12 = b1 * b2 - C * m12;
  const double q22 = b2 * b2 - C * m22;
  const double a0 = 0.5 * (q11 + q22);
  const double a1 = 0.5 * (q11 - q22);
  const double a2 = q12;
  const double rq = std::hypot(a1, a2);
  if (!(rq > 0.0) || a0 + rq <= 0.0) {
    return 0.0;
  }
  const double phi = std::atan2(a2, a1);
  const double h = 0.5 * std::acos(std::clamp(-a0 / rq, -1.0, 1.0));
  double thm = 0.5 * phi;
  if (b1 * std::cos(thm) + b2 * std::sin(thm) > 0.0) {
    thm += kPi;
  }
  const auto& gl = gaussLegendre();
  // 8-point panels per unit of h·(scale + 2·elong) / 1.5: two thirds of the first sizing, which moved
  // no result by more than 2e-11 on 3 400 random cases (halving it moved some by 9e-10).
  const int panels = static_cast<int>(std::clamp(std::ceil(h * (scale + 2.0 * elong) / 1.5), 2.0, 1024.0));
  const double du = kPi / panels;
  double sum = 0.0;
  for (int p = 0; p < panels; ++p) {
    const double uc = -0.5 * kPi + (p + 0.5) * du;
    for (int k = 0; k < GaussLegendre::kN; ++k) {
      const double u = uc + 0.5 * du * gl.x[k];
      const double th = thm + h * std::sin(u);
      double A = 0.0, B = 0.0;
      rayAB(std::cos(th), std::sin(th), A, B);
      const double sq = std::sqrt(std::max(B * B - A * C, 0.0));
      const double rhoPlus = (sq - B) / A;
      const double rhoMinus = C / (sq - B);
      // e^{−ρ−²/2} − e^{−ρ+²/2} without cancellation near the tangent rays (ρ+ − ρ− = 2 sq / A).
      const double f = std::exp(-0.5 * rhoMinus * rhoMinus) * -std::expm1(-(sq / A) * (rhoPlus + rhoMinus));
      sum += 0.5 * du * gl.w[k] * std::cos(u) * f;
    }
  }
  return std::clamp(sum * h / (2.0 * kPi), 0.0, 1.0);
}

Gaussian::Gaussian(double floor, GaussianEvaluation evaluation)
    : floor_(std::clamp(floor, 1e-300, 1.0)),
      tailSigmas_(std::sqrt(2.0 * std::log(1.0 / floor_)) * 1.001 + 1e-9),
      evaluation_(evaluation) {
  if (evaluation_ == GaussianEvaluation::kFast) {
    warmGaussianTable();
  }
}

double Gaussian::pair(const Disc& a, const Disc& b) const {
  return pairAt(a, b, centreDistance(a, b));
}

double Gaussian::pairAbove(const Disc& a, const Disc& b, double d, double /*intersectionArea*/,
                           double known) const {
  // The cull first (a square root): many of the engine's candidates within reach(a) + reach(b) lie
  // beyond it, and for them the exp of the bound below would be wasted.
  if (d >= cullDistance(a, b)) {
    return 0.0;
  }
  const double gap = d - (a.r + b.r);
  if (known > 0.0 && gap > 0.0) {
    // The disc ‖x‖ <= R lies in the half-plane u·x <= R (u the unit vector of the mean), and u·x is
    // normal with mean d and variance s² = uᵀ(Ca + Cb)u, so P <= Φ(−t) with t = gap/s, and Φ(−t) <=
    // min(1/2, 1/(t√(2π)))·e^{−t²/2}. Tighter than the Rayleigh bound e^{−gap²/2(λa + λb)} of the cull,
    // by 2× and more for isotropic discs and by far across an anisotropic disc's narrow axis.
    double s2 = 0.0;
    if (!a.anisotropic() && !b.anisotropic()) {
      s2 = a.sigma * a.sigma + b.sigma * b.sigma;
    } else {
      const Cov2 ca = a.covariance();
      const Cov2 cb = b.covariance();
      const double ux = (b.x - a.x) / d;
      const double uy = (b.y - a.y) / d;
      s2 = ux * ux * (ca.xx + cb.xx) + 2.0 * ux * uy * (ca.xy + cb.xy) + uy * uy * (ca.yy + cb.yy);
    }
    const double t2 = gap * gap / std::max(s2, 0.0);
    const double bound = std::exp(-0.5 * t2) * std::min(0.5, 1.0 / std::sqrt(2.0 * kPi * t2));
    if (bound * (1.0 + 1e-9) < known) {
      return 0.0;  // P <= the bound < known: this pair cannot raise the maximum
    }
  }
  return pairWithin(a, b, d);
}

double Gaussian::pairAt(const Disc& a, const Disc& b, double d) const {
  if (d >= cullDistance(a, b)) {
    return 0.0;
  }
  return pairWithin(a, b, d);
}

double Gaussian::pairWithin(const Disc& a, const Disc& b, double d) const {
  if (a.anisotropic() || b.anisotropic()) {
    // Independent errors: the relative position's covariance is the sum of the two. The quadrature is
    // not bitwise even in the mean, so the pair is put in one order to keep pair(a, b) == pair(b, a).
    if (a.x > b.x || (a.x == b.x && a.y > b.y)) {
      return pairWithin(b, a, d);
    }
    const Cov2 ca = a.covariance();
    const Cov2 cb = b.covariance();
    const Vec2 mean{b.x - a.x, b.y - a.y};
    const Cov2 sum{ca.xx + cb.xx, ca.xy + cb.xy, ca.yy + cb.yy};
    const double p = evaluation_ == GaussianEvaluation::kFast
                         ? gaussianCollisionProbabilityFast(mean, sum, a.r + b.r, floor_)
                         : gaussianCollisionProbability(mean, sum, a.r + b.r, floor_);
    return p < floor_ ? 0.0 : p;
  }
  const double sigma = std::sqrt(a.sigma * a.sigma + b.sigma * b.sigma);
  const double p = evaluation_ == GaussianEvaluation::kFast
                       ? gaussianCollisionProbabilityTabulated(d, a.r + b.r, sigma)
                       : gaussianCollisionProbability(d, a.r + b.r, sigma);
  return p < floor_ ? 0.0 : p;
}

double Gaussian::cullDistance(const Disc& a, const Disc& b) const {
  // P(‖x − μ‖ ≥ t) = exp(−t²/(2σ²)) for a 2D isotropic Gaussian, and collision needs ‖x − μ‖ ≥ d − R,
  // so beyond R + σ·sqrt(2 ln(1/floor)) the probability is below the floor. For anisotropic errors the
  // same bound holds with σ² = λmax(Ca + Cb) <= λmax(Ca) + λmax(Cb).
  const double sa = a.sigmaMax();
  const double sb = b.sigmaMax();
  return a.r + b.r + std::sqrt(sa * sa + sb * sb) * tailSigmas_;
}

double Gaussian::tail(const Disc& a) const {
  return a.sigmaMax() * tailSigmas_;
}

double Gaussian::tailRatioBound(double x) const {
  // g² >= x·(tail(a)² + tail(b)²) = x·T²·(σmax(a)² + σmax(b)²) >= x·T²·s², s² <= λmax(Ca) + λmax(Cb)
  // the variance along the centre line, so t = g/s has t² >= x·T² and pairAbove's bound applies there
  // (it falls with t). The 1e-6 covers the rounding of the tails, of s² and of the caller's ratio.
  const double t2 = x * tailSigmas_ * tailSigmas_ * (1.0 - 1e-6);
  if (!(t2 > 0.0)) {
    return 1.0;
  }
  return std::exp(-0.5 * t2) * std::min(0.5, 1.0 / std::sqrt(2.0 * kPi * t2));
}

double Gaussian::reach(const Disc& a) const {
  return a.r + a.sigmaMax() * tailSigmas_;
}

}  // namespace fleet::risk
