#include "fleet/risk/source.hpp"

#include <algorithm>
#include <cmath>
#include <string>

#include "fleet/core/ids.hpp"

namespace fleet::risk {

Expected<void> validateSource(const Source& source, const SourceLimits& limits,
                              std::optional<std::int64_t> nowNs) {
  if (!isValidId(source.id)) {
    return unexpected("invalid_id",
                      "source id '" + source.id + "' is not 1-63 characters of [A-Za-z0-9_.:-]");
  }
  if (source.discs.empty()) {
    return unexpected("empty", "source '" + source.id + "' has no discs");
  }
  if (source.discs.size() > limits.maxSteps) {
    return unexpected("too_many_steps", "source '" + source.id + "' has " +
                                            std::to_string(source.discs.size()) +
                                            " discs, more than the bound " + std::to_string(limits.maxSteps));
  }
  if (!std::isfinite(source.dt) || !(source.dt > 0.0) || source.dt > limits.maxDt) {
    return unexpected("bad_dt", "source '" + source.id + "' has dt " + std::to_string(source.dt) +
                                    " s; expected 0 < dt <= " + std::to_string(limits.maxDt));
  }
  for (std::size_t k = 0; k < source.discs.size(); ++k) {
    const Disc& d = source.discs[k];
    const std::string where = "source '" + source.id + "' disc " + std::to_string(k);
    if (!std::isfinite(d.x) || !std::isfinite(d.y) || !std::isfinite(d.r) || !std::isfinite(d.sigma)) {
      return unexpected("non_finite", where + " has a NaN or infinite field");
    }
    if (!(d.r > 0.0) || d.r > limits.maxRadius) {
      return unexpected("bad_radius", where + " has radius " + std::to_string(d.r) +
                                          " m; expected 0 < r <= " + std::to_string(limits.maxRadius));
    }
    if (d.sigma < 0.0 || d.sigma > limits.maxSigma) {
      return unexpected("bad_sigma", where + " has sigma " + std::to_string(d.sigma) +
                                         " m; expected 0 <= sigma <= " + std::to_string(limits.maxSigma));
    }
    if (!std::isfinite(d.cov.xx) || !std::isfinite(d.cov.xy) || !std::isfinite(d.cov.yy)) {
      return unexpected("non_finite_covariance", where + " has a NaN or infinite covariance entry");
    }
    // Positive semi-definite, with a relative slack for a singular covariance rounded to float on the
    // wire (xy² can then exceed xx·yy by a few ulps).
    if (d.cov.xx < 0.0 || d.cov.yy < 0.0 || d.cov.xy * d.cov.xy > d.cov.xx * d.cov.yy * (1.0 + 1e-5)) {
      return unexpected("bad_covariance", where + " has covariance [[" + std::to_string(d.cov.xx) + ", " +
                                              std::to_string(d.cov.xy) + "], [" + std::to_string(d.cov.xy) +
                                              ", " + std::to_string(d.cov.yy) +
                                              "]] m², which is not positive semi-definite");
    }
    if (d.sigmaMax() > limits.maxSigma) {
      return unexpected("bad_covariance",
                        where + " has a standard deviation of " + std::to_string(d.sigmaMax()) +
                            " m along its major axis; expected <= " + std::to_string(limits.maxSigma));
    }
    if (std::abs(d.x) > limits.maxAbsCoordinate || std::abs(d.y) > limits.maxAbsCoordinate) {
      return unexpected(
          "out_of_range",
          where + " lies farther than " + std::to_string(limits.maxAbsCoordinate) + " m from the map origin");
    }
  }
  if (nowNs.has_value() && source.t0_ns - *nowNs > limits.maxFutureNs) {
    return unexpected("future_timestamp", "source '" + source.id + "' has t0 " +
                                              std::to_string(source.t0_ns - *nowNs) + " ns in the future");
  }
  return {};
}

AlignedSource alignSource(const Source& source, const TimeBase& base) {
  AlignedSource out{source.kind,
                    std::vector<std::optional<Disc>>(static_cast<std::size_t>(std::max(base.steps, 0)))};
  const std::size_t n = source.discs.size();
  if (n == 0) {
    return out;
  }
  const double srcStepNs = source.dt * 1e9;
  for (int k = 0; k < base.steps; ++k) {
    auto& slot = out.steps[static_cast<std::size_t>(k)];
    if (n == 1) {
      slot = source.discs[0];
      continue;
    }
    const std::int64_t t = base.tRefNs + std::llround(static_cast<double>(k) * base.dt * 1e9);
    double s = static_cast<double>(t - source.t0_ns) / srcStepNs;
    const double last = static_cast<double>(n - 1);
    if (!(s >= -0.5 && s <= last + 0.5)) {
      continue;
    }
    s = std::clamp(s, 0.0, last);
    const std::size_t i0 = std::min(static_cast<std::size_t>(s), n - 2);
    const double f = s - static_cast<double>(i0);
    const Disc& a = source.discs[i0];
    const Disc& b = source.discs[i0 + 1];
    slot = Disc{a.x + (b.x - a.x) * f, a.y + (b.y - a.y) * f, a.r + (b.r - a.r) * f,
                a.sigma + (b.sigma - a.sigma) * f};
    if (a.anisotropic() || b.anisotropic()) {
      // A convex combination of two covariances is one (PSD stays PSD); an isotropic end enters as σ²I.
      const Cov2 ca = a.covariance();
      const Cov2 cb = b.covariance();
      slot->cov = Cov2{ca.xx + (cb.xx - ca.xx) * f, ca.xy + (cb.xy - ca.xy) * f, ca.yy + (cb.yy - ca.yy) * f};
      slot->sigma = slot->sigmaMax();
    }
  }
  return out;
}

}  // namespace fleet::risk
