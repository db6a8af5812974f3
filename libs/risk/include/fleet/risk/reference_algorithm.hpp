#pragma once

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "fleet/risk/disc.hpp"
#include "fleet/risk/grid.hpp"
#include "fleet/risk/risk_model.hpp"

namespace fleet::risk {

enum class SourceKind : std::uint8_t { kRobot = 0, kHuman = 1 };

/// Which pairs of sources count. Two humans near each other are not a robot's collision risk, so by
/// default human–human pairs are skipped; robot–robot and robot–human pairs always count.
struct PairPolicy {
  bool humanHuman = false;
};

inline bool pairAllowed(SourceKind a, SourceKind b, const PairPolicy& policy) {
  return policy.humanHuman || a == SourceKind::kRobot || b == SourceKind::kRobot;
}

/// One source's discs on a common time base: steps[k] is its disc at step k, or nothing when the
/// source has no prediction for that time.
struct AlignedSource {
  SourceKind kind = SourceKind::kRobot;
  std::vector<std::optional<Disc>> steps;
};

/// The thesis grid loop (§3.2.2.2) written plainly and generalised to many sources by superposition
/// (§3.3.3): for every time step, every allowed pair, every grid cell — if the pair's score p > 0 and
/// the cell lies in either disc, P(cell) = max(P(cell), p). O(steps · sources² · cells). It is the
/// oracle the fusion engine is tested against and the baseline it is benchmarked against.
ProbabilityGrid referenceProbabilityGrid(const GridSpec& spec, std::span<const AlignedSource> sources,
                                         const RiskModel& model, const PairPolicy& policy = {});

/// Eq. (3.7) at each step over the discs present, summed over the allowed pairs literally (i ≠ j).
std::vector<double> referenceSceneIndex(std::span<const AlignedSource> sources,
                                        const PairPolicy& policy = {});

/// 3D version of the grid loop for spheres with the overlap ratio (3.6): tracks[s][k] is sphere s at
/// step k (all tracks the same length). Every pair of spheres is considered.
std::vector<double> referenceProbabilityGrid3(const GridSpec3& spec,
                                              std::span<const std::vector<Sphere>> tracks);

}  // namespace fleet::risk
