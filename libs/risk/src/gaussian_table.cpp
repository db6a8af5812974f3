// Isotropic Gaussian collision probability from a precomputed table (docs/algorithms.md, risk: the
// fast path). P depends on d, R, σ only through v = R/σ and w = (d − R)/σ.
#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

#include "fleet/risk/gaussian.hpp"

namespace fleet::risk {
namespace {

// 1/32: interpolation error ≤ 2e-7 (at 1/16 it reached 3e-6 near d = 0, R ≈ σ, where the skewed
// coordinates make the fourth derivatives large); floats keep the 2.4 MB table in cache and add ≤ 6e-8.
constexpr double kStep = 1.0 / 32.0;
constexpr double kInvStep = 32.0;
constexpr double kWMax = 9.0;  // |w| beyond this: 0 or 1 as in the exact formula
constexpr int kPad = 2;        // nodes beyond each end, for the cubic stencil
constexpr int kNv = static_cast<int>(kGaussianTableMaxRatio * kInvStep) + 1 + 2 * kPad;
constexpr int kNw = static_cast<int>(2.0 * kWMax * kInvStep) + 1 + 2 * kPad;

// Node (i, j) holds P at v = (i − kPad)·h, w = (j − kPad)·h − kWMax. P(u, v) = 1 − Q1(u, v) is an
// analytic function of u² and v², so G(v, w) = P(|v + w|, |v|) is smooth across u = 0 and v = 0, and
// the padding nodes there are its values rather than a reflection.
struct Table {
  std::vector<float> p;
  Table() : p(static_cast<std::size_t>(kNv) * static_cast<std::size_t>(kNw)) {
    for (int i = 0; i < kNv; ++i) {
      const double v = (i - kPad) * kStep;
      for (int j = 0; j < kNw; ++j) {
        const double w = (j - kPad) * kStep - kWMax;
        p[static_cast<std::size_t>(i) * kNw + static_cast<std::size_t>(j)] = static_cast<float>(
            v == 0.0 ? 0.0 : gaussianCollisionProbability(std::abs(v + w), std::abs(v), 1.0));
      }
    }
  }
};

const Table& table() {
  static const Table t;
  return t;
}

// Cubic Lagrange weights on the nodes −1, 0, 1, 2 at t ∈ [0, 1).
std::array<double, 4> cubicWeights(double t) {
  const double tm1 = t - 1.0;
  const double tm2 = t - 2.0;
  const double tp1 = t + 1.0;
  return {-t * tm1 * tm2 * (1.0 / 6.0), tp1 * tm1 * tm2 * 0.5, -tp1 * t * tm2 * 0.5,
          tp1 * t * tm1 * (1.0 / 6.0)};
}

}  // namespace

void warmGaussianTable() {
  (void)table();
}

double gaussianCollisionProbabilityTabulated(double d, double R, double sigma) {
  if (!(R > 0.0) || !(sigma > 0.0)) {
    return gaussianCollisionProbability(d, R, sigma);
  }
  const double inv = 1.0 / sigma;
  const double v = R * inv;
  const double w = (std::abs(d) - R) * inv;
  if (w > kWMax) {
    return 0.0;
  }
  if (w < -kWMax) {
    return 1.0;
  }
  if (!(v <= kGaussianTableMaxRatio)) {
    return gaussianCollisionProbability(d, R, sigma);
  }
  const double fi = v * kInvStep + kPad;
  const double fj = (w + kWMax) * kInvStep + kPad;
  const int i = static_cast<int>(fi);
  const int j = static_cast<int>(fj);
  const auto wi = cubicWeights(fi - i);
  const auto wj = cubicWeights(fj - j);
  const float* row = table().p.data() + static_cast<std::ptrdiff_t>(i - 1) * kNw + (j - 1);
  double sum = 0.0;
  for (int a = 0; a < 4; ++a) {
    const float* r = row + static_cast<std::ptrdiff_t>(a) * kNw;
    sum += wi[static_cast<std::size_t>(a)] *
           (wj[0] * static_cast<double>(r[0]) + wj[1] * static_cast<double>(r[1]) +
            wj[2] * static_cast<double>(r[2]) + wj[3] * static_cast<double>(r[3]));
  }
  return std::clamp(sum, 0.0, 1.0);
}

}  // namespace fleet::risk
