#pragma once

#include "fleet/core/vec2.hpp"
#include "fleet/risk/disc.hpp"
#include "fleet/risk/risk_model.hpp"

namespace fleet::risk {

/// P(‖x‖ ≤ R) for x ~ N(μ, σ² I) with ‖μ‖ = d: the noncentral χ² (k = 2) CDF at R²/σ² with
/// λ = d²/σ², i.e. 1 − Q₁(d/σ, R/σ), as a Poisson-mixture series in which every addition is of
/// positive terms: for b = R²/(2σ²) <= 150 summed upwards from e^{−a}, e^{−b} (a few multiplications
/// per term; ~1e-14 absolute, checked against 60-digit sums), above that downwards from the truncation
/// point with lgamma (~1e-12 absolute at a, b in the thousands). sigma = 0 gives the indicator d < R.
double gaussianCollisionProbability(double d, double R, double sigma);

/// Largest R/σ the table of gaussianCollisionProbabilityTabulated covers; beyond it the exact series.
inline constexpr double kGaussianTableMaxRatio = 32.0;
/// Tolerance of the tabulated isotropic probability against the exact series (tested).
inline constexpr double kGaussianTableTolerance = 1e-6;

/// gaussianCollisionProbability(d, R, sigma) by bicubic interpolation in a table over v = R/σ ∈ [0, 32]
/// and w = (d − R)/σ ∈ [−9, 9] (steps 1/32, floats, 2.4 MB, built on first use from the exact series):
/// within kGaussianTableTolerance of it, ~5× faster. Outside the table: the exact series, or 0/1 beyond
/// 9 σ of the rim as there.
double gaussianCollisionProbabilityTabulated(double d, double R, double sigma);
/// Builds the table now (a service calls it at start-up rather than in its first fusion).
void warmGaussianTable();

/// P(‖x‖ ≤ R) for x ~ N(mean, cov) (anisotropic), the production path. In the covariance's eigenbasis
/// (x1 along the minor axis, sigma s1 <= s2) the x2 integral over the chord |x2| ≤ √(R² − x1²) is a
/// difference of two normal CDFs; the remaining x1 integral, substituted x1 = R sin θ (no square-root
/// ends), is smooth and even about θ = ±π/2, so the trapezoid rule converges like Gauss–Hermite. Only the
/// nodes where x1 is within 9 s1 of the mean are visited (~20–30), with a step chosen from s1/R, s2/R
/// and where the window sits on the circle; cost is independent of the anisotropy. Nearly isotropic
/// covariances take the Marcum-Q series; a singular one (s1 = 0) the one-dimensional closed form.
/// Returns 0 when the tail bound exp(−((|mean| − R)/s2)²/2) is below `floor` (default: only beyond 9 s2).
double gaussianCollisionProbability(Vec2 mean, const Cov2& cov, double R, double floor = 0.0);

/// The same quadrature on the fast path: 1 − Φ from a table, a 7.5 σ window and a coarser step (see
/// gaussian_anisotropic.cpp); within kGaussianTableTolerance of gaussianCollisionProbability.
double gaussianCollisionProbabilityFast(Vec2 mean, const Cov2& cov, double R, double floor = 0.0);

/// The previous anisotropic implementation, kept as the reference for tests and benchmarks: whitened
/// coordinates z = L⁻¹(x − mean) (cov = L Lᵀ), where each ray from the mean crosses the transformed disc
/// in one interval [ρ1, ρ2] with radial integral e^{−ρ1²/2} − e^{−ρ2²/2}; the angle by the periodic
/// trapezoid rule when the mean is inside the disc, else over the arc of hitting rays (θ = θm + h·sin u)
/// by composite Gauss–Legendre. A covariance with λmin ≤ 1e-12 λmax falls back to the isotropic formula
/// with the largest standard deviation (an approximation).
double gaussianCollisionProbabilityWhitened(Vec2 mean, const Cov2& cov, double R);

/// The same probability by Foster-style polar quadrature centred on the disc (the radial integral of
/// each ray in closed form with exp/erf, trapezoid over the angle; thetaSteps = 0 picks a step count
/// from the angular width of the Gaussian). Slower; kept as the independent cross-check.
double gaussianCollisionProbabilityPolar(Vec2 mean, const Cov2& cov, double R, int thetaSteps = 0);

/// How the Gaussian model evaluates a pair: the exact series and quadrature, or the fast path (the
/// isotropic table and the anisotropic quadrature with tabulated normal functions), within
/// kGaussianTableTolerance of the exact value (tested; docs/algorithms.md).
enum class GaussianEvaluation { kExact, kFast };

/// Probability that two discs with independent Gaussian centre errors overlap: relative position
/// ~ N(μa − μb, Ca + Cb) (C = σ² I for an isotropic disc), collision iff ‖x‖ ≤ ra + rb; the isotropic
/// formula when both discs are isotropic, else the anisotropic one. Values below `floor` are reported
/// as 0 so that culling pairs farther than cullDistance (where the tail bound exp(−(d−R)²/(2σ²)) <
/// floor, σ² = λmax(Ca) + λmax(Cb)) changes nothing.
class Gaussian final : public RiskModel {
 public:
  explicit Gaussian(double floor = 1e-4, GaussianEvaluation evaluation = GaussianEvaluation::kExact);

  [[nodiscard]] double pair(const Disc& a, const Disc& b) const override;
  /// pair(a, b) with the centre distance the engine has already computed (the same expression).
  [[nodiscard]] double pairWithIntersection(const Disc& a, const Disc& b, double d,
                                            double /*intersectionArea*/) const override {
    return pairAt(a, b, d);
  }
  /// 0 without evaluating P when its tail bound exp(−(d − R)²/2σ²) (σ² = λmax(Ca) + λmax(Cb)) is
  /// already below `known`.
  [[nodiscard]] double pairAbove(const Disc& a, const Disc& b, double d, double intersectionArea,
                                 double known) const override;
  [[nodiscard]] double cullDistance(const Disc& a, const Disc& b) const override;
  [[nodiscard]] double reach(const Disc& a) const override;
  /// σmax(a)·√(2 ln(1/floor)) (padded): a.r + b.r + √(tail(a)² + tail(b)²) is cullDistance(a, b) up to
  /// rounding, and the padding puts the probability there below the floor, so a pair at or beyond it
  /// is 0 either way.
  [[nodiscard]] double tail(const Disc& a) const override;
  /// The half-plane bound of pairAbove at the smallest t the class allows (t² >= x·2 ln(1/floor)).
  [[nodiscard]] double tailRatioBound(double x) const override;
  [[nodiscard]] std::string_view name() const override { return "gaussian"; }
  [[nodiscard]] double floor() const { return floor_; }

 private:
  [[nodiscard]] double pairAt(const Disc& a, const Disc& b, double d) const;
  [[nodiscard]] double pairWithin(const Disc& a, const Disc& b, double d) const;  // d below the cull
  double floor_;
  double tailSigmas_;  // sqrt(2 ln(1/floor)), slightly padded
  GaussianEvaluation evaluation_;
};

}  // namespace fleet::risk
