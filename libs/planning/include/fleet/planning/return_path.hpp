#pragma once

#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/geometry/segment_path.hpp"
#include "fleet/planning/occupancy_grid.hpp"

namespace fleet::planning {

/// Seed 001 S3: given the skeleton path q = v_0 -> v_1 -> ... -> v_m = p (scan centres the robot
/// has visited, joined by collision-free segments), build one bundle of segments at every interior
/// vertex and return along the MMS shortest path through them instead of the skeleton.
///
/// Bundle at v_k: the seed builds bundles from the collision-warning ("dark") parts of the scans.
/// Here: rays from v_k inside the turn (the sector of angle < pi between the edges to v_{k-1} and
/// v_{k+1}, the seed's "arc not exceeding 180 degrees"), every `rayStep` radians, that hit an
/// obstacle within min(vision radius, `spacingFraction` x the shorter adjacent edge); each becomes
/// the segment from v_k to just short of the hit. Touching every such segment keeps the path on the
/// robot's side of every obstacle point it saw. Segments are ordered from the incoming edge's side
/// to the outgoing edge's side. If the MMS path still clips an obstacle between two rays, the
/// skeleton path is returned instead (`usedSkeleton`).
struct ReturnPathOptions {
  double visionRadius = 8.0;
  double rayStep = 0.02;  ///< radians between bundle segments
  double spacingFraction = 1.0;
  geometry::MmsOptions mms{};
};

struct ReturnPath {
  std::vector<Vec2> points;  ///< q ... p, duplicate points removed
  double length = 0.0;
  double skeletonLength = 0.0;
  int mmsIterations = 0;
  bool usedSkeleton = false;  ///< MMS path crossed an obstacle (ray discretisation); skeleton kept
  std::vector<geometry::Segment2> segments;  ///< the bundle sequence F
};

/// Error "bad_skeleton" when fewer than two vertices are given or a skeleton edge is blocked.
Expected<ReturnPath> planReturnPath(const OccupancyGrid& grid, const std::vector<Vec2>& skeleton,
                                    const ReturnPathOptions& opt = {});

/// Seed 001 S1-S4: explore toward `goal` with a vision disc of radius r. Each scan splits the
/// collision-free directions into sectors of at most 120 degrees with one open point each (at
/// `openPointFraction` * r on the sector bisector, skipped if an earlier scan already saw it);
/// the open point with the highest rank alpha/d(t) + beta/a(t) is visited next (a(t) in radians,
/// rank +inf when d or a is 0), straight if visible, else by planReturnPath along the skeleton.
struct ExploreOptions {
  double visionRadius = 8.0;
  int rays = 360;
  double maxSectorDeg = 120.0;
  double alpha = 1.0;
  double beta = 1.0;
  double openPointFraction = 0.9;
  int maxScans = 2000;
  ReturnPathOptions returnPath{};
};

struct ExploreResult {
  std::vector<Vec2> route;         ///< every point the robot passed through, start to goal
  double travelled = 0.0;          ///< length of route
  double travelledSkeleton = 0.0;  ///< the same exploration with returns along skeleton paths
  int scans = 0;
  int returns = 0;  ///< returns planned by MMS
  int skeletonFallbacks = 0;
};

/// Errors: "out_of_map"/"start_blocked" for bad inputs, "exhausted" when no open point is left
/// (goal unreachable), "step_limit" after maxScans scans.
Expected<ExploreResult> explore(const OccupancyGrid& grid, Vec2 start, Vec2 goal,
                                const ExploreOptions& opt = {});

}  // namespace fleet::planning
