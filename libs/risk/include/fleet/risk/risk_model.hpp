#pragma once

#include <string_view>

#include "fleet/risk/disc.hpp"

namespace fleet::risk {

/// Probability-like score that two discs collide at one time step. Implementations are pure and
/// thread-compatible (const methods, no hidden state).
class RiskModel {
 public:
  virtual ~RiskModel() = default;

  /// Score in [0, 1], symmetric in its arguments.
  [[nodiscard]] virtual double pair(const Disc& a, const Disc& b) const = 0;

  /// Centre distance at and beyond which pair(a, b) is exactly 0, so culling beyond it changes nothing.
  [[nodiscard]] virtual double cullDistance(const Disc& a, const Disc& b) const = 0;

  /// Per-disc reach with reach(a) + reach(b) >= cullDistance(a, b) for every pair, so a spatial hash
  /// can find all candidate partners of a disc without knowing them first.
  [[nodiscard]] virtual double reach(const Disc& a) const = 0;

  /// Per-disc part of the cull distance beyond the radii, for a tighter test than reach(a) + reach(b):
  /// pair(a, b) is 0 whenever the centre distance is at least a.r + b.r + √(tail(a)² + tail(b)²). The
  /// default √2·reach(a) follows from the reach contract (√(2·ra² + 2·rb²) >= ra + rb) for any model.
  [[nodiscard]] virtual double tail(const Disc& a) const { return 1.4142135623730951 * reach(a); }

  [[nodiscard]] virtual std::string_view name() const = 0;
  /// pair(a, b) for a caller that already has the centre distance d and the area of intersection of the
  /// two discs (the fusion engine needs it for the scene index); must equal pair(a, b) exactly.
  [[nodiscard]] virtual double pairWithIntersection(const Disc& a, const Disc& b, double /*d*/,
                                                    double /*intersectionArea*/) const {
    return pair(a, b);
  }
  /// For a caller that keeps maxima of scores: pairWithIntersection(a, b, d, area) when that exceeds
  /// `known`, else any value <= known — a model with a cheap upper bound may return 0 for pairs that
  /// cannot raise the maximum. The default scores every pair.
  [[nodiscard]] virtual double pairAbove(const Disc& a, const Disc& b, double d, double intersectionArea,
                                         double /*known*/) const {
    return pairWithIntersection(a, b, d, intersectionArea);
  }
  /// An upper bound on pair(a, b) over every pair whose gap g = d − a.r − b.r is positive with
  /// g² >= x·(tail(a)² + tail(b)²), x in [0, 1): one bound for a whole class of pairs, which lets the
  /// engine pass over pairs that cannot raise a known maximum without asking for each. The default
  /// bounds nothing.
  [[nodiscard]] virtual double tailRatioBound(double /*x*/) const { return 1.0; }
};

}  // namespace fleet::risk
