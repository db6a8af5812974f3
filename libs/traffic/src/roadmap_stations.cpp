// The roadmap's stations: docks, approach points, ways out and queues, placed on the lattice
// (docs/algorithms.md, "Stations as servers").

#include <optional>
#include <sstream>

#include "fleet/traffic/traffic_control.hpp"
#include "roadmap_builder.hpp"
#include "roadmap_geometry.hpp"

namespace fleet::traffic::detail {

// Back from `base` along each of `dirs` in turn while the disc fits; the longest line wins.
std::vector<Vec2> RoadmapBuilder::generateQueue(Vec2 base, const std::vector<Vec2>& dirs) {
  const double f = opt.followingDistance;
  std::vector<Vec2> best;
  for (const Vec2 d : dirs) {
    std::vector<Vec2> pts;
    Vec2 prev = base;
    for (int k = 1; k <= opt.queueLength; ++k) {
      const Vec2 p = base + d * (f * k);
      if (!fits(p) || !sweeps(prev, p) || !clearOfStations(p, f)) {
        break;
      }
      pts.push_back(p);
      prev = p;
    }
    if (pts.size() > best.size()) {
      best = pts;
    }
    if (static_cast<int>(best.size()) == opt.queueLength) {
      break;
    }
  }
  return best;
}

// Where robots go after this station: the drop-offs after a pickup, the pickups after a
// drop-off (their centroid); none for chargers and parking places.
std::optional<Vec2> RoadmapBuilder::nextPlaces(site::StationKind k) const {
  const auto want = k == site::StationKind::Pickup    ? site::StationKind::Dropoff
                    : k == site::StationKind::Dropoff ? site::StationKind::Pickup
                                                      : site::StationKind::Parking;
  if (want == site::StationKind::Parking) {
    return std::nullopt;
  }
  Vec2 sum;
  int n = 0;
  for (const auto& st : site.stations) {
    if (st.kind == want) {
      sum = sum + st.pose.position();
      ++n;
    }
  }
  return n > 0 ? std::optional(sum * (1.0 / n)) : std::nullopt;
}

// A pickup's or drop-off's way out, apart from its way in (docs/algorithms.md, "Stations as
// servers"): approached along the row, the dock is left along the row on the side towards where
// robots go next and queued for on the other; approached straight, it is left beside the
// approach point, on the side towards where robots go next. The candidate must fit, be reached
// from the dock in a straight line and keep a following distance from every station node placed.
std::optional<Vec2> RoadmapBuilder::placeExit(const site::Station& st, const StationNodes& sn) const {
  if (st.exit || st.exitByEntry) {
    return st.exit;
  }
  const auto next = nextPlaces(st.kind);
  if (!next) {
    return std::nullopt;
  }
  const Vec2 dockAt = pos[static_cast<std::size_t>(sn.dock)];
  const Vec2 base = sn.approach != kNoNode ? pos[static_cast<std::size_t>(sn.approach)] : dockAt;
  Vec2 side = st.pose.heading().perp();
  if (side.dot(*next - dockAt) < 0.0) {
    side = -side;
  }
  for (const Vec2 d : {side, -side}) {
    const Vec2 e = base + d * opt.followingDistance;
    if (fits(e) && sweeps(dockAt, e) && clearOfStations(e, opt.followingDistance)) {
      return e;
    }
  }
  return std::nullopt;
}

// Docks and approach points first, then the ways out, then the queues, so that no queue is
// generated in front of a station or across its way out.
void RoadmapBuilder::placeStations() {
  constexpr double kCone = kPi / 3.0;
  for (const auto& st : site.stations) {
    StationNodes sn;
    sn.name = st.name;
    sn.kind = st.kind;
    const Vec2 dockAt = st.pose.position();
    if (!fits(dockAt)) {
      std::ostringstream r;
      r << opt.radius;
      problem(RoadmapProblem::Severity::Error, st.name, dockAt,
              keyOf(st, "pose") + "station '" + st.name + "' at " + detail::pointText(dockAt) +
                  ": the robot's disc (radius " + r.str() + " m) does not fit there: no dock node");
      stations.push_back(sn);
      continue;
    }
    const NodeKind k = st.kind == site::StationKind::Parking    ? NodeKind::Parking
                       : st.kind == site::StationKind::Charging ? NodeKind::Charger
                                                                : NodeKind::Station;
    sn.dock = add(dockAt, k);
    if (st.approach) {
      if (fits(*st.approach) && sweeps(*st.approach, dockAt) && distance(*st.approach, dockAt) > 1e-6) {
        sn.approach = add(*st.approach, NodeKind::Approach);
      } else {
        problem(RoadmapProblem::Severity::Error, st.name, *st.approach,
                keyOf(st, "approach") + "station '" + st.name +
                    "': the robot cannot drive straight from its approach point " +
                    detail::pointText(*st.approach) + " to the dock " + detail::pointText(dockAt) +
                    "; joined along the row instead");
      }
    }
    stations.push_back(sn);
  }
  for (std::size_t i = 0; i < site.stations.size(); ++i) {
    const auto& st = site.stations[i];
    auto& sn = stations[i];
    if (sn.dock == kNoNode || st.kind == site::StationKind::Parking) {
      continue;
    }
    const auto e = placeExit(st, sn);
    if (!e && !st.exitByEntry && nextPlaces(st.kind)) {
      // A dead end left by its way in still serves, but the robot leaving meets the next in line
      // on the way in and the dock cycles slower (docs/algorithms.md, "Stations as servers"): the
      // site must say so ("exit": "entry") or give a way out.
      problem(RoadmapProblem::Severity::Error, st.name, st.pose.position(),
              keyOf(st, "exit") + "station '" + st.name + "': no room for a way out apart from its way in: " +
                  "give one in site.json, or \"exit\": \"entry\" to have it left by its way in");
    }
    if (e) {
      const Vec2 dockAt = pos[static_cast<std::size_t>(sn.dock)];
      if (fits(*e) && sweeps(dockAt, *e)) {
        sn.exit = add(*e, NodeKind::Exit);
        links.push_back({sn.dock, sn.exit, true, false});
      } else {
        problem(RoadmapProblem::Severity::Error, st.name, *e,
                keyOf(st, "exit") + "station '" + st.name +
                    "': the robot cannot drive straight from the dock " + detail::pointText(dockAt) +
                    " to its exit " + detail::pointText(*e) + "; left by its way in instead");
      }
    }
  }
  for (std::size_t i = 0; i < site.stations.size(); ++i) {
    const auto& st = site.stations[i];
    auto& sn = stations[i];
    if (sn.dock == kNoNode) {
      continue;
    }
    // With a way out of its own the station is entered only: the approach leg one way in, the
    // approach point (or a dock on a row: from the queue's side) reached from the lanes.
    const Join in = sn.exit != kNoNode ? Join::In : Join::Both;
    const Vec2 dockAt = pos[static_cast<std::size_t>(sn.dock)];
    std::vector<Vec2> inDirs;
    if (sn.approach != kNoNode) {
      links.push_back({sn.approach, sn.dock, true, sn.exit == kNoNode});
      inDirs = {st.pose.heading()};
    } else if (sn.exit != kNoNode) {
      inDirs = {(dockAt - pos[static_cast<std::size_t>(sn.exit)]).normalized()};
    }
    // An approach point is driven to from the free space in front of it (so robots side by side
    // at neighbouring approach points do not drive at each other); a dock without one from any side.
    const NodeId entry = entryOf(sn);
    const Vec2 ep = pos[static_cast<std::size_t>(entry)];
    // Clearance before direction (joinClear): a parking place below a shelf corner was joined up
    // past the corner by an edge that cleared only the disc, and its robot stood there for good.
    const int joined = joinClear(entry, inDirs, kCone, in);
    if (joined == 0) {
      std::ostringstream d;
      d << 3.0 * opt.spacing;
      problem(RoadmapProblem::Severity::Error, st.name, ep,
              keyOf(st, sn.approach != kNoNode ? "approach" : "pose") + "station '" + st.name +
                  "': no lane node within " + d.str() + " m of its " +
                  (sn.approach != kNoNode ? "approach point " : "dock ") + detail::pointText(ep) +
                  " that the robot reaches in a straight line: the station is not on the roadmap");
    }
    if (sn.exit != kNoNode) {
      const Vec2 xp = pos[static_cast<std::size_t>(sn.exit)];
      const Vec2 out = (xp - dockAt).normalized();
      if (joinClear(sn.exit, {out}, kCone, Join::Out) == 0) {
        problem(RoadmapProblem::Severity::Error, st.name, xp,
                keyOf(st, "exit") + "station '" + st.name + "': no lane node near its exit " +
                    detail::pointText(xp) +
                    " that the robot reaches in a straight line: robots could not leave the dock");
      }
    }
  }
  for (std::size_t i = 0; i < site.stations.size(); ++i) {
    placeQueue(site.stations[i], stations[i]);
  }
  for (const auto& sn : stations) {
    joinQueue(sn);
  }
}

// A queue is a line toward the station: entered at its tail from behind, driven one way toward
// the station, left sideways (so a robot joining or leaving never drives at the robots waiting).
void RoadmapBuilder::placeQueue(const site::Station& st, StationNodes& sn) {
  if (sn.dock == kNoNode) {
    return;
  }
  const NodeId entry = entryOf(sn);
  std::vector<Vec2> queue = st.queue;
  if (queue.empty() && st.kind != site::StationKind::Parking && opt.queueLength > 0) {
    // Back from the approach point along the station's axis first; along the row when the axis
    // is blocked or the station has no straight approach: on the side away from its way out.
    const Vec2 h = st.pose.heading();
    std::vector<Vec2> dirs;
    if (sn.approach != kNoNode) {
      dirs.push_back(h);
    }
    Vec2 side = h.perp();
    if (sn.exit != kNoNode &&
        side.dot(pos[static_cast<std::size_t>(sn.exit)] - pos[static_cast<std::size_t>(sn.dock)]) > 0.0) {
      side = -side;
    }
    dirs.push_back(side);
    if (sn.exit == kNoNode || sn.approach != kNoNode) {
      dirs.push_back(-side);
    }
    queue = generateQueue(pos[static_cast<std::size_t>(entry)], dirs);
    sn.queueGenerated = !queue.empty();
  }
  NodeId next = entry;
  for (std::size_t q = 0; q < queue.size(); ++q) {
    if (!fits(queue[q])) {
      problem(RoadmapProblem::Severity::Error, st.name, queue[q],
              keyOf(st, "queue") + "station '" + st.name +
                  "': the robot's disc does not fit on queue point " + std::to_string(q) + " " +
                  detail::pointText(queue[q]));
      continue;
    }
    const Vec2 nextAt = pos[static_cast<std::size_t>(next)];
    const NodeId v = add(queue[q], NodeKind::Queue);
    if (sweeps(queue[q], nextAt)) {
      links.push_back({v, next, true, false});
    } else {
      problem(RoadmapProblem::Severity::Warning, st.name, queue[q],
              keyOf(st, "queue") + "station '" + st.name + "': queue point " + std::to_string(q) + " " +
                  detail::pointText(queue[q]) + " cannot be driven straight to the one before it");
    }
    sn.queue.push_back(v);
    next = v;
  }
}

// A queue is left sideways from any of its places and entered at its tail from behind.
void RoadmapBuilder::joinQueue(const StationNodes& sn) {
  constexpr double kCone = kPi / 3.0;
  NodeId next = sn.dock == kNoNode ? kNoNode : entryOf(sn);
  for (std::size_t q = 0; q < sn.queue.size(); ++q) {
    const NodeId v = sn.queue[q];
    const Vec2 back = (pos[static_cast<std::size_t>(v)] - pos[static_cast<std::size_t>(next)]).normalized();
    joinToLattice(v, {back.perp(), -back.perp()}, kCone, Join::Out);
    if (q + 1 == sn.queue.size()) {
      joinToLattice(v, {back}, kPi / 2.0, Join::Both);
    }
    next = v;
  }
}

}  // namespace fleet::traffic::detail

namespace fleet::traffic {

std::vector<StationLine> stationLines(const Roadmap& roadmap) {
  std::vector<StationLine> lines;
  for (const auto& st : roadmap.stations) {
    if (st.dock != kNoNode &&
        (st.kind == site::StationKind::Pickup || st.kind == site::StationKind::Dropoff ||
         st.kind == site::StationKind::Charging)) {
      lines.push_back({st.dock, st.queue, st.approach});
    }
  }
  return lines;
}

}  // namespace fleet::traffic
