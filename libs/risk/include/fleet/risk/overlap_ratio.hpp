#pragma once

#include <span>

#include "fleet/risk/disc.hpp"
#include "fleet/risk/risk_model.hpp"

namespace fleet::risk {

/// Area of the intersection of two discs with radii r1, r2 and centre distance d (thesis eq. 3.2,
/// with the lens formula written through atan2 so it stays accurate near tangency and containment).
double discIntersectionArea(double r1, double r2, double d);

/// Thesis eq. (3.3): S(O1 ∩ O2) / S(O1 ∪ O2), with its three cases. Continuous in d.
double discOverlapRatio(double r1, double r2, double d);

/// Volume of the intersection of two spheres (thesis eq. 3.5, spherical caps).
double sphereIntersectionVolume(double r1, double r2, double d);

/// Thesis eq. (3.6): V(O1 ∩ O2) / V(O1 ∪ O2), with its three cases.
double sphereOverlapRatio(double r1, double r2, double d);

/// Thesis eq. (3.7): Σ_{i≠j} S(Ωi ∩ Ωj) / Σ_{i≠j} S(Ωi ∪ Ωj) over m discs; 0 for fewer than two.
double sceneOverlapRatio(std::span<const Disc> discs);

/// Thesis eq. (3.7) for spheres.
double sceneOverlapRatio(std::span<const Sphere> spheres);

/// The thesis pair model: the overlap ratio of the two discs (their sigma is ignored).
class OverlapRatio final : public RiskModel {
 public:
  [[nodiscard]] double pair(const Disc& a, const Disc& b) const override;
  [[nodiscard]] double cullDistance(const Disc& a, const Disc& b) const override;
  [[nodiscard]] double reach(const Disc& a) const override;
  /// 0: discs that do not touch score 0.
  [[nodiscard]] double tail(const Disc& /*a*/) const override { return 0.0; }
  [[nodiscard]] std::string_view name() const override { return "overlap_ratio"; }
  [[nodiscard]] double pairWithIntersection(const Disc& a, const Disc& b, double d,
                                            double intersectionArea) const override;
};

}  // namespace fleet::risk
