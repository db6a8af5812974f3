#pragma once

// Which roadmap nodes exclude each other, from the robot's disc and the robot agent's motion gate.
//
// The execution contract (execution.hpp): a robot *holds* the node it stands on, and while it drives
// u→v it holds both u and v until it has reached v. Two robots never hold conflicting nodes (a node
// conflicts with itself). addGeometricConflicts() chooses the conflicts so that, under that contract,
// two robots each within `Separation::margin`/2 of their planned positions — standing on a node,
// or anywhere on the straight segment of the edge they drive, facing along it —
//   - keep their centres at least `contact` apart (2·radius + margin): no contact, and
//   - a driving robot never has the other in its gate's corridor ahead (centre within `corridor`
//     of its heading line and ahead of it) closer than `ahead` (2·radius + stop gap + margin):
//     the gate never holds it (it may slow it: cruising at v needs headway·v more).
// Side by side only the contact distance is kept: the gate does not look sideways, so parking
// places 1 m apart are not made to exclude each other.
//
// How: every pair of motions (standing on a node, or driving an edge) whose held nodes are disjoint
// and which could come too close (unsafe()) must have a conflicting pair of held nodes. Standing
// robots too close make their nodes conflict; for the rest, when no held pair conflicts yet, one
// held pair is made to conflict (greedy, deterministic): of those with the least weight of nodes
// robots wait on (docks, approach and queue nodes; parking places, where robots rest, weigh most),
// the closest — so that neighbouring parking places or queue nodes are not made to exclude each
// other when a lane node next to them can carry the conflict, and a robot leaving its parking place
// is given the conflict on its way out (the approach) rather than where it rests.
// Edges sharing a node never need a conflict: their robots hold that node.

#include <cstddef>
#include <cstdint>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

/// The nearest-node and conflict lookups bucket nodes on a square grid of at most this many buckets
/// a side (larger buckets on a larger site).
inline constexpr double kMaxBucketsPerSide = 1024.0;

/// Centre-to-centre distances two robots keep (m). contact < corridor < ahead.
struct Separation {
  double contact = 0.7;    ///< any direction: 2·radius + margin
  double ahead = 1.1;      ///< to a robot in the corridor ahead of a driving one: 2·radius + gap + margin
  double corridor = 0.75;  ///< half-width of that corridor: 2·radius + the gate's slack + margin
  double margin = 0.1;     ///< included above: how far the two robots together may stray from the plan
};

/// What a robot does: stands at `from` (moving false, `to` ignored) or drives forward from `from`
/// to `to` and may be anywhere on that segment, facing `to`.
struct Motion {
  Vec2 from;
  Vec2 to;
  bool moving = false;
};

/// Some placement of the two robots within their motions breaks the separation (exact: distance
/// between segments, and the corridor ahead as a convex region intersected with the other segment).
bool unsafe(const Motion& a, const Motion& b, const Separation& s);

/// Adds the conflicts described above to `g` for every node and every edge (open or not: closures
/// are temporary, conflicts are not). `waiting[v]`: 0 a lane node, 1 a node robots wait on, 2 a
/// place robots rest at (may be empty: all lanes). Returns the number of conflicting pairs added.
std::size_t addGeometricConflicts(Graph& g, const Separation& s,
                                  const std::vector<std::uint8_t>& waiting = {});

/// Number of conflicting pairs (each counted once).
std::size_t conflictPairs(const Graph& g);

}  // namespace fleet::traffic
