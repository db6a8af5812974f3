#pragma once

// Flow guidance: edge costs that make routes keep to one direction of travel where the site's
// flows would otherwise meet head-on (a one-lane aisle used both ways, the two halves of an open
// floor crossed by loaded and empty robots). Learnt from traffic-flow-aware guide paths (Chen et
// al., AAAI 2024) and guidance graphs (Zhang et al., IJCAI 2024); written anew.
//
// The flows are the site's own: every pickup to every drop-off and back (the trips a task list
// makes). A trip driving into node v in direction d adds its share to v's flow in d, and to the
// flow of every node a robot at v excludes. An edge into v costs its duration times 1 + `weight`
// × the share of v's flow that heads against it (more than 90° off) among the flow along or
// against it. Trips are routed goal by goal on those costs, each goal's trips against the flow of
// those routed before (so the first ones set the directions, and two equal flows meeting head-on
// part instead of swapping sides together), then `rounds` − 1 more times each taken out and
// routed again against all the others (rip-up and re-route). The guide is then set from the whole
// flow into Edge::guide; durations (timing) are untouched.

#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "fleet/traffic/graph.hpp"

namespace fleet::traffic {

struct GuidanceOptions {
  /// Driving wholly against the flow costs 1 + weight times its duration; 0: no guidance.
  double weight = 0.0;
  int rounds = 4;  ///< routing rounds (each routes every trip once)
};

/// A trip the site's tasks make, with its share of them.
struct Trip {
  NodeId from = kNoNode;
  NodeId to = kNoNode;
  double share = 1.0;
};

struct GuidanceStats {
  double contraflowBefore = 0.0;  ///< flow-weighted share of travel against the flow, unguided routes
  double contraflowAfter = 0.0;   ///< the same on the guided routes
  double lengthRatio = 1.0;       ///< guided routes' duration over the unguided ones', flow-weighted
};

/// Sets every edge's guide in `graph` from `trips` (guide 1 everywhere when weight is 0 or there
/// are no trips; trips with a share that is not finite and > 0, or unreachable, add nothing).
/// Deterministic. Throws std::invalid_argument for a weight that is not finite and >= 0, or fewer
/// than one round.
/// Computed once, on the graph as built: closures made later do not re-guide it.
GuidanceStats guideByFlow(Graph& graph, std::span<const Trip> trips, const GuidanceOptions& options);

}  // namespace fleet::traffic
