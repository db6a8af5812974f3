#include "fleet/estimation/line_extraction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "fleet/core/angles.hpp"

namespace fleet::estimation {

namespace {

/// Running sums so a growing segment is refitted in O(1) per point.
struct Sums {
  double n = 0.0;
  double sx = 0.0;
  double sy = 0.0;
  double sxx = 0.0;
  double sxy = 0.0;
  double syy = 0.0;

  void add(Vec2 p) {
    n += 1.0;
    sx += p.x;
    sy += p.y;
    sxx += p.x * p.x;
    sxy += p.x * p.y;
    syy += p.y * p.y;
  }
};

struct Fit {
  double r = 0.0;
  double psi = 0.0;
  double c = 1.0;  // cos ψ
  double s = 0.0;  // sin ψ
  double mean_sq_residual = 0.0;
  double spread = 0.0;  // Σ t'² along the line
  Vec2 centroid;
  [[nodiscard]] double distance(Vec2 p) const { return std::abs(p.x * c + p.y * s - r); }
};

Fit fitSums(const Sums& m) {
  Fit f;
  f.centroid = {m.sx / m.n, m.sy / m.n};
  const double cxx = m.sxx / m.n - f.centroid.x * f.centroid.x;
  const double cxy = m.sxy / m.n - f.centroid.x * f.centroid.y;
  const double cyy = m.syy / m.n - f.centroid.y * f.centroid.y;
  // The normal is the scatter matrix's minor eigenvector: 2ψ points against ((cxx − cyy)/2, cxy).
  f.psi = 0.5 * std::atan2(-2.0 * cxy, cyy - cxx);
  f.c = std::cos(f.psi);
  f.s = std::sin(f.psi);
  f.r = f.centroid.x * f.c + f.centroid.y * f.s;
  if (f.r < 0.0) {
    f.r = -f.r;
    f.c = -f.c;
    f.s = -f.s;
    f.psi += kPi;
  }
  f.psi = wrapAngle(f.psi);
  f.mean_sq_residual = std::max(0.0, cxx * f.c * f.c + 2.0 * cxy * f.c * f.s + cyy * f.s * f.s);
  f.spread = m.n * std::max(0.0, cxx * f.s * f.s - 2.0 * cxy * f.c * f.s + cyy * f.c * f.c);
  return f;
}

LineFit toLineFit(const Fit& f, double n, double sigma) {
  // δψ = −Σ t'ε / Σ t'², δr = ε̄ + e δψ with e the centroid's coordinate along the line, so
  // var ψ = σ²/Σt'², var r = σ²/n + e² var ψ, cov = e var ψ (cf. eq. 3.32).
  LineFit out;
  out.r = f.r;
  out.psi = f.psi;
  const double e = -f.centroid.x * f.s + f.centroid.y * f.c;
  const double s2 = sigma * sigma;
  out.varPsi = f.spread > 0.0 ? s2 / f.spread : std::numeric_limits<double>::infinity();
  out.varR = s2 / n + e * e * out.varPsi;
  out.covRPsi = e * out.varPsi;
  out.rmsResidual = std::sqrt(f.mean_sq_residual);
  return out;
}

}  // namespace

Expected<LineFit> fitLine(std::span<const Vec2> points, double pointSigma) {
  if (points.size() < 2) {
    return fleet::unexpected("too_few_points", "a line fit needs at least 2 points");
  }
  if (!std::isfinite(pointSigma) || pointSigma <= 0.0) {
    return fleet::unexpected("invalid_sigma", "point_sigma must be finite and > 0");
  }
  Sums m;
  for (const Vec2 p : points) {
    if (!p.isFinite()) {
      return fleet::unexpected("non_finite_point", "line fit point is NaN/inf");
    }
    m.add(p);
  }
  const Fit f = fitSums(m);
  if (!(f.spread > 0.0)) {
    return fleet::unexpected("degenerate_points", "all points coincide");
  }
  return toLineFit(f, m.n, pointSigma);
}

Expected<void> LineExtractionParams::validate() const {
  if (seedPoints < 3 || minPoints < seedPoints) {
    return fleet::unexpected("invalid_line_params", "need seed_points >= 3 and min_points >= seed_points");
  }
  const bool ok = minThreshold > 0.0 && maxThreshold >= minThreshold && thresholdFactor > 0.0 &&
                  maxPointGap > 0.0 && minLength >= 0.0 && pointSigma > 0.0 && std::isfinite(maxThreshold) &&
                  std::isfinite(maxPointGap) && std::isfinite(pointSigma) && std::isfinite(thresholdFactor);
  if (!ok) {
    return fleet::unexpected("invalid_line_params", "thresholds, gap and sigma must be finite and > 0");
  }
  return {};
}

std::vector<ExtractedLine> extractLines(const LaserScan& scan, const LineExtractionParams& params) {
  std::vector<ExtractedLine> out;
  if (!params.validate() || !std::isfinite(scan.angle_min) || !std::isfinite(scan.angle_increment)) {
    return out;
  }
  // Valid returns only, in beam order (eq. 3.24 with the angle measured from the robot's x axis).
  std::vector<Vec2> pts;
  pts.reserve(scan.ranges.size());
  for (std::size_t i = 0; i < scan.ranges.size(); ++i) {
    const double r = scan.ranges[i];
    if (!std::isfinite(r) || r < scan.rangeMin || r > scan.range_max) {
      continue;
    }
    const double a = scan.angle_min + static_cast<double>(i) * scan.angle_increment;
    pts.push_back({r * std::cos(a), r * std::sin(a)});
  }
  const std::size_t n = pts.size();
  std::size_t start = 0;
  while (start + params.seedPoints <= n) {
    Sums m;
    bool contiguous = true;
    for (std::size_t i = start; i < start + params.seedPoints; ++i) {
      if (i > start && distance(pts[i], pts[i - 1]) > params.maxPointGap) {
        contiguous = false;
      }
      m.add(pts[i]);
    }
    Fit f = fitSums(m);
    double seed_max = 0.0;
    for (std::size_t i = start; i < start + params.seedPoints; ++i) {
      seed_max = std::max(seed_max, f.distance(pts[i]));
    }
    if (!contiguous || seed_max > params.maxThreshold) {
      ++start;
      continue;
    }
    // Each segment gets its own threshold from its seed's residual (the thesis's dynamic threshold).
    const double threshold = std::clamp(params.thresholdFactor * std::sqrt(f.mean_sq_residual),
                                        params.minThreshold, params.maxThreshold);
    std::size_t last = start + params.seedPoints - 1;
    std::size_t misses = 0;
    for (std::size_t i = last + 1; i < n; ++i) {
      if (distance(pts[i], pts[last]) > params.maxPointGap) {
        break;
      }
      if (f.distance(pts[i]) <= threshold) {
        m.add(pts[i]);
        f = fitSums(m);
        last = i;
        misses = 0;
      } else if (++misses > params.maxMisses) {
        break;
      }
    }
    const std::size_t count = static_cast<std::size_t>(m.n);
    const double length = distance(pts[start], pts[last]);
    if (count >= params.minPoints && length >= params.minLength && f.spread > 0.0) {
      const LineFit lf = toLineFit(f, m.n, params.pointSigma);
      ExtractedLine line;
      line.line = {lf.r, lf.psi, lf.varR, lf.varPsi, lf.covRPsi};
      line.first = pts[start];
      line.last = pts[last];
      line.points = count;
      out.push_back(line);
      start = last + 1;
    } else {
      ++start;
    }
  }
  return out;
}

}  // namespace fleet::estimation
