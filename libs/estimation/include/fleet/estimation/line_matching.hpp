#pragma once

// Data association for the laser-line update of seed 003 (eqs. 3.26–3.28): which wall of the map an
// extracted scan line is, if any. docs/algorithms.md (estimation: line matching) gives the gate.

#include <cstddef>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "fleet/core/pose2.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/estimation/line_extraction.hpp"
#include "fleet/estimation/measurement_models.hpp"

namespace fleet::estimation {

/// A wall face of the map: the segment a–b (map frame) seen from the side `normal` points to.
struct MapSegment {
  Vec2 a;
  Vec2 b;
  Vec2 normal;  ///< unit, out of the obstacle
};

/// The infinite line through a segment in the filter's (ρ >= 0, β) form.
MapLine lineOf(const MapSegment& s);

struct LineGate {
  double mahalanobis = 13.82;  ///< χ²(2) 99.9 % on the (r, ψ) innovation against H P Hᵀ + R
  /// T of eq. 3.28 [m]: each observed end point e (in the map frame, by the estimate) must satisfy
  /// |e − a| + |e − b| − |b − a| < T, i.e. lie inside the ellipse with foci at the wall's ends
  /// (2 × how far it may stick out past an end). Widened by 6 σ of the position estimate.
  double endpointTolerance = 0.3;
  double minDistance = 0.05;  ///< the robot must be this far in front of the face (ψ is undefined on it)
  /// Two candidate walls on different lines (|Δρ| or |Δβ| over these) both inside the gate: the line
  /// is ambiguous and skipped rather than risk the wrong one.
  double sameLineRho = 0.05;
  double sameLineBeta = 0.05;
  /// Walls further than this from the robot [m] are not looked at (the scanner's range and a margin):
  /// the matching cost then follows the walls in range, not the site's size. <= 0: every wall.
  double maxRange = 0.0;
};

struct LineMatch {
  std::size_t observation = 0;
  std::size_t segment = 0;
  double d2 = 0.0;  ///< squared Mahalanobis distance at the estimate the match was made at
  MapLine line;
};

/// What became of each observed line; every one that is not matched has exactly one reason.
struct LineMatchResult {
  std::vector<LineMatch> matches;  ///< in observation order
  std::size_t noWallFacing = 0;    ///< no wall in range faces the robot
  std::size_t outsideGate = 0;     ///< no facing wall inside the Mahalanobis gate
  std::size_t noOverlap = 0;       ///< inside the gate only for walls its end points lie off
  std::size_t ambiguous = 0;       ///< walls on two different lines pass every test
};

/// Matches each observed line (robot frame, variances as the filter will use them) against the map
/// at the estimate (pose, P): the candidate walls face the robot and pass the Mahalanobis gate and
/// the end-point test; the nearest in Mahalanobis distance wins. Several observations may match
/// the same wall (a face split by something in front of it gives two independent fits).
LineMatchResult matchLines(const Pose2& pose, const Eigen::Matrix3d& P, std::span<const MapSegment> map,
                           std::span<const ExtractedLine> observed, const LineGate& gate = {});

}  // namespace fleet::estimation
