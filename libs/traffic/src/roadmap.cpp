#include "fleet/traffic/roadmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "fleet/core/bends.hpp"
#include "fleet/core/config.hpp"
#include "fleet/site/reachability.hpp"
#include "roadmap_builder.hpp"
#include "roadmap_geometry.hpp"

namespace fleet::traffic {

namespace detail {

// One-way zones: a direction is dropped when, anywhere along the edge, it runs more than 90°
// off the zone's direction.
bool RoadmapBuilder::allowed(Vec2 a, Vec2 b) const {
  if (site.layers.oneWay.size() != site.map.size()) {
    return true;
  }
  const Vec2 dir = (b - a).normalized();
  const double len = distance(a, b);
  const int n = std::max(1, static_cast<int>(std::ceil(len / (0.5 * site.map.resolution()))));
  for (int s = 0; s <= n; ++s) {
    const auto c = site.map.cellAt(a + (b - a) * (static_cast<double>(s) / n));
    if (!c) {
      continue;
    }
    const double phi = static_cast<double>(site.layers.oneWay[site.map.index(*c)]);
    if (std::isfinite(phi) && dir.dot({std::cos(phi), std::sin(phi)}) < -1e-9) {
      return false;
    }
  }
  return true;
}

// Drive time at the cruise speed, slower where a speed-limit zone says so.
double RoadmapBuilder::driveTime(Vec2 a, Vec2 b) const {
  const double len = distance(a, b);
  const int n = std::max(1, static_cast<int>(std::ceil(len / (0.5 * site.map.resolution()))));
  double t = 0.0;
  for (int s = 0; s < n; ++s) {
    const Vec2 mid = a + (b - a) * ((s + 0.5) / n);
    const double v = std::max(0.05, std::min(opt.cruiseSpeed, site.speedLimitAt(mid)));
    t += len / n / v;
  }
  return t;
}

}  // namespace detail

const char* toString(NodeKind k) {
  constexpr const char* kNames[] = {"lane", "station", "approach", "queue", "parking", "charger", "exit"};
  return kNames[static_cast<int>(k)];
}

namespace {

std::size_t errorCount(const Roadmap& r) {
  return static_cast<std::size_t>(
      std::count_if(r.problems.begin(), r.problems.end(),
                    [](const RoadmapProblem& p) { return p.severity == RoadmapProblem::Severity::Error; }));
}

// Every pickup to every drop-off and back: the trips a task list between them makes.
void guide(Roadmap& r) {
  std::vector<Trip> trips;
  for (const auto& p : r.stations) {
    if (p.kind != site::StationKind::Pickup || p.dock == kNoNode)
      continue;
    for (const auto& d : r.stations) {
      if (d.kind != site::StationKind::Dropoff || d.dock == kNoNode)
        continue;
      trips.push_back({p.dock, d.dock, 1.0});
      trips.push_back({d.dock, p.dock, 1.0});
    }
  }
  GuidanceOptions o;
  o.weight = r.options.guidance;
  r.guidance = guideByFlow(r.graph, trips, o);
}

// The lattice kept clear of parked robots; where the site leaves no room for that (a parking row
// in a corridor of its own width: stations cut off without the lanes beside it), the lattice as
// the map allows, with a warning that parked robots block lanes there.
Roadmap clearOfParkingWherePossible(const site::Site& s, const RoadmapOptions& options) {
  Roadmap r = detail::buildRoadmapOnce(s, options);
  if (!options.parkingClear || errorCount(r) == 0) {
    return r;
  }
  RoadmapOptions as = options;
  as.parkingClear = false;
  Roadmap plain = detail::buildRoadmapOnce(s, as);
  if (errorCount(plain) >= errorCount(r)) {
    return r;
  }
  const auto parking = s.ofKind(site::StationKind::Parking);
  plain.problems.push_back({RoadmapProblem::Severity::Warning, "",
                            parking.empty() ? Vec2{} : parking.front()->pose.position(),
                            "the parking places stand too close to the lanes for lanes clear of them (the "
                            "lanes beside them are the only way between stations): a robot parked there "
                            "blocks the lanes next to it"});
  return plain;
}

}  // namespace

// Guided once, on the lattice chosen (not on both when the fall-back is tried).
Roadmap buildRoadmap(const site::Site& s, const RoadmapOptions& options) {
  Roadmap r = clearOfParkingWherePossible(s, options);
  guide(r);
  return r;
}

Roadmap detail::buildRoadmapOnce(const site::Site& s, const RoadmapOptions& options) {
  const auto& in = options;
  if (!(in.cruiseSpeed > 0.0) || in.spacing < 0.0 || (in.spacing > 0.0 && in.spacing < 0.05) ||
      !(in.targetSpacing >= 0.05) || in.radius < 0.0 || in.stopGap < 0.0 || in.corridorSlack < 0.0 ||
      in.nodeClearance < 0.0 || in.edgeClearance < 0.0 || in.margin < 0.0 || in.queueLength < 0 ||
      in.queueLength > 50 || in.followingDistance < 0.0 || !(in.guidance >= 0.0 && in.guidance <= 100.0)) {
    throw std::invalid_argument(
        "RoadmapOptions: cruiseSpeed > 0, spacing 0 or >= 0.05 m, targetSpacing >= 0.05 m, radius, stopGap, "
        "corridorSlack, nodeClearance, edgeClearance, margin and followingDistance >= 0, queueLength 0..50, "
        "guidance 0..100");
  }
  detail::RoadmapBuilder b{s, options, s.drivable(), {}, {}, {}, {}, {}, 0, {}, {}, {}, {}};
  auto& o = b.opt;
  const double res = s.map.size() > 0 ? s.map.resolution() : 1.0;
  if (o.radius <= 0.0) {
    o.radius = s.robot.radius;
  }
  if (o.spacing <= 0.0) {
    o.spacing = res * std::max(1.0, std::round(o.targetSpacing / res));
  }
  Separation sep;
  sep.margin = o.margin;
  sep.contact = 2.0 * o.radius + o.margin;
  sep.corridor = 2.0 * o.radius + o.corridorSlack + o.margin;
  sep.ahead = std::max(sep.corridor + 1e-6, 2.0 * o.radius + o.stopGap + o.margin);
  if (o.followingDistance <= 0.0) {
    o.followingDistance = std::ceil(sep.ahead * 20.0 - 1e-9) / 20.0;
  }
  b.sep = sep;

  Roadmap r;
  if (s.map.size() > 0) {
    b.buildLattice();
    b.placeStations();
  }

  // Pockets: components (either direction) without a station node are left out — the robot can
  // never get there. A bare map keeps its largest component.
  const std::size_t n = b.pos.size();
  std::vector<std::size_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  auto find = [&](std::size_t x) {
    while (parent[x] != x) {
      parent[x] = parent[parent[x]];
      x = parent[x];
    }
    return x;
  };
  for (const auto& l : b.links) {
    parent[find(static_cast<std::size_t>(l.a))] = find(static_cast<std::size_t>(l.b));
  }
  std::vector<std::size_t> compSize(n, 0);
  std::vector<std::uint8_t> compHasStation(n, 0);
  for (std::size_t v = 0; v < n; ++v) {
    ++compSize[find(v)];
    compHasStation[find(v)] |= b.kind[v] != NodeKind::Lane ? 1 : 0;
  }
  const bool anyStation =
      std::any_of(b.kind.begin(), b.kind.end(), [](NodeKind k) { return k != NodeKind::Lane; });
  std::size_t largest = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (compSize[v] > compSize[largest]) {
      largest = v;
    }
  }
  std::vector<NodeId> remap(n, kNoNode);
  for (std::size_t v = 0; v < n; ++v) {
    const std::size_t c = find(v);
    if (anyStation ? compHasStation[c] != 0 : c == largest) {
      remap[v] = r.graph.addNode(b.pos[v]);
      r.kinds.push_back(b.kind[v]);
    } else {
      ++r.droppedLatticeNodes;
    }
  }

  for (const auto& l : b.links) {
    const NodeId a = remap[static_cast<std::size_t>(l.a)];
    const NodeId c = remap[static_cast<std::size_t>(l.b)];
    if (a == kNoNode || c == kNoNode) {
      continue;
    }
    auto direct = [&](NodeId from, NodeId to) {
      const Vec2 pf = r.graph.position(from);
      const Vec2 pt = r.graph.position(to);
      if (!b.allowed(pf, pt)) {
        ++r.oneWayDropped;
        return;
      }
      r.graph.addEdge(from, to, b.driveTime(pf, pt));
    };
    if (l.ab) {
      direct(a, c);
    }
    if (l.ba) {
      direct(c, a);
    }
  }
  for (auto& sn : b.stations) {
    auto map = [&](NodeId& v) { v = v == kNoNode ? kNoNode : remap[static_cast<std::size_t>(v)]; };
    map(sn.dock);
    map(sn.approach);
    map(sn.exit);
    for (auto& q : sn.queue) {
      map(q);
    }
  }

  r.turnRate_ = std::max(1e-3, s.robot.limits.omegaMax);
  r.turnAccel_ = std::max(1e-3, s.robot.limits.alphaMax);
  // Turning (bendTime): an edge's duration includes the least turning any way into its start needs
  // (a lower bound without knowing where the robot came from; exact at nodes with one way in).
  const auto nn = static_cast<NodeId>(r.graph.size());
  std::vector<std::vector<NodeId>> into(r.graph.size());
  r.baseDuration_.assign(r.graph.size(), {});
  r.tightBend_.assign(r.graph.size(), 0);
  for (NodeId v = 0; v < nn; ++v) {
    for (const auto& e : r.graph.edges(v)) {
      into[static_cast<std::size_t>(e.to)].push_back(v);
      r.baseDuration_[static_cast<std::size_t>(v)].push_back(e.duration);
    }
    r.tightBend_[static_cast<std::size_t>(v)] =
        b.grid.size() > 0 && !site::discFits(b.grid, r.graph.position(v), o.radius + bends::kTightClearance)
            ? 1
            : 0;
  }
  r.turnIncluded_.assign(r.graph.size(), {});
  for (NodeId v = 0; v < nn; ++v) {
    const auto& ways = into[static_cast<std::size_t>(v)];
    for (std::size_t k = 0; k < r.graph.edges(v).size(); ++k) {
      double least = ways.empty() ? 0.0 : std::numeric_limits<double>::infinity();
      for (const NodeId w : ways) {
        least = std::min(least, r.bendTime(w, v, k));
      }
      r.turnIncluded_[static_cast<std::size_t>(v)].push_back(least);
    }
  }
  for (NodeId v = 0; v < nn; ++v) {
    const std::vector<Edge> out(r.graph.edges(v).begin(), r.graph.edges(v).end());
    for (std::size_t k = 0; k < out.size(); ++k) {
      r.graph.addEdge(
          v, out[k].to,
          r.baseDuration_[static_cast<std::size_t>(v)][k] + r.turnIncluded_[static_cast<std::size_t>(v)][k]);
    }
  }

  r.stations = std::move(b.stations);
  r.options = o;
  r.separation = sep;
  r.latticeOrigin = b.latticeOrigin;
  std::vector<std::uint8_t> waiting(r.kinds.size(), 0);
  for (std::size_t v = 0; v < r.kinds.size(); ++v) {
    waiting[v] = r.kinds[v] == NodeKind::Parking ? 2 : r.kinds[v] != NodeKind::Lane ? 1 : 0;
  }
  addGeometricConflicts(r.graph, sep, waiting);
  // A robot waiting on a station's approach point must not shut the docked robot's way out: where
  // the exit excludes the approach, the dock excludes it too, so the next robot in line waits on
  // the queue until the dock is left (otherwise the docked robot waits for the exit and the next
  // one, which moves only forward in its line, for the dock: a deadlock, seen on the generated
  // sites' pickups).
  for (const auto& st : r.stations) {
    if (st.dock != kNoNode && st.approach != kNoNode && st.exit != kNoNode &&
        r.graph.conflicting(st.exit, st.approach) && !r.graph.conflicting(st.dock, st.approach)) {
      r.graph.addConflict(st.dock, st.approach);
    }
  }

  // Nearest-node lookup.
  if (r.graph.size() > 0) {
    Vec2 lo = r.graph.position(0);
    Vec2 hi = lo;
    for (NodeId v = 0; v < nn; ++v) {
      const Vec2 p = r.graph.position(v);
      lo = {std::min(lo.x, p.x), std::min(lo.y, p.y)};
      hi = {std::max(hi.x, p.x), std::max(hi.y, p.y)};
    }
    // At most kMaxBucketsPerSide buckets a side, however large the site.
    r.bucketSize_ = std::max({o.spacing, 0.25, std::max(hi.x - lo.x, hi.y - lo.y) / kMaxBucketsPerSide});
    r.bucketOrigin_ = lo;
    r.bucketW_ = static_cast<int>((hi.x - lo.x) / r.bucketSize_) + 1;
    r.bucketH_ = static_cast<int>((hi.y - lo.y) / r.bucketSize_) + 1;
    r.buckets_.resize(static_cast<std::size_t>(r.bucketW_) * static_cast<std::size_t>(r.bucketH_));
    for (NodeId v = 0; v < nn; ++v) {
      const Vec2 p = r.graph.position(v) - lo;
      const int x = std::min(r.bucketW_ - 1, static_cast<int>(p.x / r.bucketSize_));
      const int y = std::min(r.bucketH_ - 1, static_cast<int>(p.y / r.bucketSize_));
      r.buckets_[static_cast<std::size_t>(y * r.bucketW_ + x)].push_back(v);
    }
  }
  r.nodeClosures_.assign(r.graph.size(), 0);
  r.edgeClosures_.resize(r.graph.size());
  for (NodeId v = 0; v < nn; ++v) {
    r.edgeClosures_[static_cast<std::size_t>(v)].assign(r.graph.edges(v).size(), 0);
  }

  // Queue nodes are for waiting while the station is busy: one that excludes the dock or another
  // place in the same line (possible with the site's own queue points) cannot serve.
  for (std::size_t i = 0; i < r.stations.size(); ++i) {  // in the site's order
    const auto& sn = r.stations[i];
    for (std::size_t q = 0; q < sn.queue.size(); ++q) {
      const NodeId v = sn.queue[q];
      std::string with;
      if (sn.dock != kNoNode && r.graph.conflicting(v, sn.dock)) {
        with = "the dock";
      }
      for (std::size_t j = 0; j < q && with.empty(); ++j) {
        with = r.graph.conflicting(v, sn.queue[j]) ? "queue point " + std::to_string(j) : "";
      }
      if (!with.empty()) {
        b.problem(RoadmapProblem::Severity::Warning, sn.name, r.graph.position(v),
                  "stations[" + std::to_string(i) + "].queue: station '" + sn.name +
                      "': a robot waiting on queue point " + std::to_string(q) + " " +
                      detail::pointText(r.graph.position(v)) + " is too close to " + with + " (" +
                      (with == "the dock" ? "it blocks the station" : "they cannot both be used") + ")");
      }
    }
  }
  r.problems = std::move(b.problems);
  for (auto& p : checkRoadmap(r)) {
    r.problems.push_back(std::move(p));
  }
  for (auto& p : checkQueues(r)) {
    r.problems.push_back(std::move(p));
  }
  return r;
}

const StationNodes* Roadmap::station(const std::string& name) const {
  for (const auto& s : stations) {
    if (s.name == name) {
      return &s;
    }
  }
  return nullptr;
}

NodeId Roadmap::nearest(Vec2 p, bool openOnly) const {
  if (buckets_.empty()) {
    return kNoNode;
  }
  const int cx = static_cast<int>(std::floor((p.x - bucketOrigin_.x) / bucketSize_));
  const int cy = static_cast<int>(std::floor((p.y - bucketOrigin_.y) / bucketSize_));
  NodeId best = kNoNode;
  double bestD = std::numeric_limits<double>::infinity();
  const int maxRing = std::max(bucketW_, bucketH_) + std::max(std::abs(cx), std::abs(cy)) + 1;
  for (int ring = 0; ring <= maxRing; ++ring) {
    // Every node in ring k or beyond is at least (k - 1) buckets away.
    if (best != kNoNode && (ring - 1) * bucketSize_ > bestD) {
      break;
    }
    for (int y = cy - ring; y <= cy + ring; ++y) {
      for (int x = cx - ring; x <= cx + ring; ++x) {
        if (std::max(std::abs(x - cx), std::abs(y - cy)) != ring || x < 0 || y < 0 || x >= bucketW_ ||
            y >= bucketH_) {
          continue;
        }
        for (const NodeId v : buckets_[static_cast<std::size_t>(y * bucketW_ + x)]) {
          const double d = distance(p, graph.position(v));
          if ((!openOnly || graph.isOpen(v)) && d < bestD) {
            bestD = d;
            best = v;
          }
        }
      }
    }
  }
  return best;
}

double Roadmap::turnTime(double angle) const {
  const double a = std::abs(angle);
  if (a < 1e-9) {
    return 0.0;
  }
  // Accelerate to the turn rate and brake again; a short turn never reaches it.
  const double ramp = turnRate_ * turnRate_ / turnAccel_;
  return a >= ramp ? a / turnRate_ + turnRate_ / turnAccel_ : 2.0 * std::sqrt(a / turnAccel_);
}

double Roadmap::baseDuration(NodeId from, NodeId to) const {
  const auto out = graph.edges(from);
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (out[k].to == to) {
      return baseDuration_[static_cast<std::size_t>(from)][k];
    }
  }
  return 0.0;
}

double Roadmap::bendTime(NodeId prev, NodeId atNode, std::size_t out) const {
  const Edge& e = graph.edges(atNode)[out];
  const Vec2 p = graph.position(atNode);
  const double angle = detail::angleBetween(p - graph.position(prev), graph.position(e.to) - p);
  if (angle < 1e-9) {
    return 0.0;
  }
  // Corners (fleet/core/bends.hpp), and the leg onto a dock, which the agent starts facing the dock:
  // on the spot.
  const bool corner = angle > bends::kDrivenRound ||
                      (tightBend_[static_cast<std::size_t>(atNode)] != 0 && angle > bends::kTight) ||
                      kind(atNode) == NodeKind::Station || kind(e.to) == NodeKind::Station;
  if (corner) {
    return turnTime(angle);
  }
  // Driven round: the robot turns while it drives the second half of the edge in and the first half
  // of the edge out at cruise; what the turn needs beyond that is the bend's cost.
  const double along =
      0.5 * (baseDuration(prev, atNode) + baseDuration_[static_cast<std::size_t>(atNode)][out]);
  return std::max(0.0, turnTime(angle) - along);
}

double Roadmap::extraTurn(NodeId prev, NodeId atNode, NodeId next) const {
  if (!graph.valid(prev) || !graph.valid(atNode) || !graph.valid(next)) {
    return 0.0;
  }
  const auto out = graph.edges(atNode);
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (out[k].to == next) {
      return std::max(0.0, bendTime(prev, atNode, k) - turnIncluded_[static_cast<std::size_t>(atNode)][k]);
    }
  }
  return 0.0;
}

std::size_t Roadmap::edgeCount() const {
  std::size_t n = 0;
  for (NodeId v = 0; v < static_cast<NodeId>(graph.size()); ++v) {
    n += graph.edges(v).size();
  }
  return n;
}

std::size_t Roadmap::queueNodeCount() const {
  return static_cast<std::size_t>(std::count(kinds.begin(), kinds.end(), NodeKind::Queue));
}

}  // namespace fleet::traffic
