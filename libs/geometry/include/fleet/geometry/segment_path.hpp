#pragma once

#include <vector>

#include "fleet/core/vec2.hpp"

namespace fleet::geometry {

/// A segment the path must touch. `a` is the skeleton-side endpoint (the bundle vertex in seed 001),
/// so the skeleton path runs through the `a` points.
struct Segment2 {
  Vec2 a;
  Vec2 b;
};

/// Shortest path from p to q that touches the segments in order (seed 001 problem (P)).
struct SegmentPath {
  std::vector<Vec2> points;    ///< p, one touch point per segment, q (coincident points kept)
  std::vector<double> params;  ///< touch parameter in [0,1] along a->b, one per segment
  double length = 0.0;
  int iterations = 0;  ///< MMS outer iterations, or Newton steps of the convex solver
  bool converged = false;
  int merges = 0;  ///< MMS: times a stall made it merge sub-sequences; rubber band: joint moves
  std::vector<double> lengthHistory;  ///< MMS: path length before each iteration and at the end
};

double polylineLength(const std::vector<Vec2>& pts);
/// Length of the skeleton path p -> a_1 -> ... -> a_n -> q.
double skeletonLength(Vec2 p, Vec2 q, const std::vector<Segment2>& segs);

/// Cross-check solver: the problem is convex (Polishchuk-Mitchell), so minimise the smoothed length
/// sum sqrt(|x_{j+1}-x_j|^2 + mu^2) over the touch parameters in [0,1] by projected Newton steps
/// (the Hessian is tridiagonal), driving mu from 1e-2 to 1e-13 of the problem scale.
struct ConvexOptions {
  double muStart = 1e-2;
  double muEnd = 1e-13;
  int maxNewtonPerStage = 60;
};
SegmentPath shortestPathConvex(Vec2 p, Vec2 q, const std::vector<Segment2>& segs,
                               const ConvexOptions& opt = {});
/// Same solver from a given start (touch parameters); used for sub-problems.
SegmentPath shortestPathConvex(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, std::vector<double> t0,
                               const ConvexOptions& opt);

/// Seed 001 method of multiple shooting: cutting segments every `subsequence` segments, shooting
/// points start at the bundle vertices (`a`), sub-paths between shooting points are solved exactly,
/// and shooting points that fail the collinear condition move to where SP(t_{i-1}, t_i) crosses
/// their cutting segment (Jacobi update). Stops when every shooting point satisfies the collinear
/// condition (first-order test with tolerance `angleTol`). When an update no longer shortens the path
/// by more than `lengthTol` relative while a condition still fails (coincident shooting points at a
/// shared bundle vertex), neighbouring sub-sequences are merged (c doubles) and the iteration goes on.
struct MmsOptions {
  int subsequence = 5;
  /// Explicit cutting segments (increasing indices), e.g. the last segment of each bundle; when
  /// empty, every `subsequence`-th segment is one.
  std::vector<int> cuts{};
  double angleTol = 1e-11;
  double lengthTol = 1e-13;
  int maxIterations = 20000;
};
SegmentPath shortestPathMms(Vec2 p, Vec2 q, const std::vector<Segment2>& segs, const MmsOptions& opt = {});

/// Independent cross-check ("rubber band", libs/geometry/src/segment_path_rubber_band.cpp): starting
/// from the segment midpoints, sweeps move one touch point at a time to the exact minimiser of its
/// two adjacent pieces (reflection across the segment's line, clamped), optionally over-relaxed by
/// `overRelaxation` when that does not lengthen the path (measured: 1.0 needs the fewest sweeps on
/// random sequences; 1.5 and 1.8 need 1.5-3.5x more, see docs/algorithms.md). When a sweep moves no point by
/// more than `tolerance` of the problem scale, runs of 2-3 coincident consecutive points (crossing
/// segments, bundle vertices: where single-point moves stall) are moved jointly by exact nested
/// 1-D searches; it stops when that no longer helps. `iterations` counts sweeps, `merges` joint
/// moves that shortened the path.
struct RubberBandOptions {
  double overRelaxation = 1.0;
  double tolerance = 1e-15;
  int maxSweeps = 200000;
  /// Start parameters, one per segment; empty (default): the segment midpoints.
  std::vector<double> start{};
};
SegmentPath shortestPathRubberBand(Vec2 p, Vec2 q, const std::vector<Segment2>& segs,
                                   const RubberBandOptions& opt = {});

}  // namespace fleet::geometry
