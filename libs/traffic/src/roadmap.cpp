#include "fleet/traffic/roadmap.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <optional>
#include <sstream>
#include <stdexcept>

#include "fleet/core/config.hpp"
#include "fleet/site/reachability.hpp"
#include "roadmap_geometry.hpp"

namespace fleet::traffic {

namespace {

constexpr double kPi = 3.14159265358979323846;

double angleBetween(Vec2 a, Vec2 b) {
  const double c = a.normalized().dot(b.normalized());
  return std::acos(std::clamp(c, -1.0, 1.0));
}

// Approximate clearance (m) of every cell centre: distance to the nearest blocked cell centre or
// the map's edge, less half a cell; a two-pass chamfer transform (1, √2), within ~8 % of Euclidean.
// Only used to choose where the lattice lies, so approximate is enough.
std::vector<float> cellClearance(const planning::OccupancyGrid& g) {
  const int w = g.width();
  const int h = g.height();
  std::vector<float> d(g.size());
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      d[g.index({x, y})] =
          g.blocked({x, y}) ? 0.0F : static_cast<float>(std::min({x + 1, y + 1, w - x, h - y}));
    }
  }
  const auto diag = static_cast<float>(std::sqrt(2.0));
  auto relax = [&](int x, int y, int dx, int dy, float c) {
    if (x + dx >= 0 && y + dy >= 0 && x + dx < w && y + dy < h) {
      float& v = d[g.index({x, y})];
      v = std::min(v, d[g.index({x + dx, y + dy})] + c);
    }
  };
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < w; ++x) {
      relax(x, y, -1, 0, 1.0F);
      relax(x, y, 0, -1, 1.0F);
      relax(x, y, -1, -1, diag);
      relax(x, y, 1, -1, diag);
    }
  }
  for (int y = h - 1; y >= 0; --y) {
    for (int x = w - 1; x >= 0; --x) {
      relax(x, y, 1, 0, 1.0F);
      relax(x, y, 0, 1, 1.0F);
      relax(x, y, 1, 1, diag);
      relax(x, y, -1, 1, diag);
    }
  }
  const auto res = static_cast<float>(g.resolution());
  for (auto& v : d) {
    v = std::max(0.0F, (v - 0.5F) * res);
  }
  return d;
}

// Undirected pair of nodes with the directions a robot may drive it.
struct Link {
  NodeId a = kNoNode;
  NodeId b = kNoNode;
  bool ab = true;
  bool ba = true;
};

struct Builder {
  const site::Site& site;
  RoadmapOptions opt;
  planning::OccupancyGrid grid;  // the drivable map: no-go cells blocked
  std::vector<Vec2> pos;
  std::vector<NodeKind> kind;
  std::vector<Link> links;
  std::vector<RoadmapProblem> problems;
  std::vector<StationNodes> stations;
  std::size_t latticeCount = 0;  // nodes [0, latticeCount) are the lattice
  Vec2 latticeOrigin;

  NodeId add(Vec2 p, NodeKind k) {
    pos.push_back(p);
    kind.push_back(k);
    return static_cast<NodeId>(pos.size() - 1);
  }
  [[nodiscard]] bool fits(Vec2 p) const { return site::discFits(grid, p, opt.radius); }
  [[nodiscard]] bool latticeFits(Vec2 p) const {
    return site::discFits(grid, p, opt.radius + opt.nodeClearance);
  }
  [[nodiscard]] bool sweeps(Vec2 a, Vec2 b) const { return site::segmentFits(grid, a, b, opt.radius); }
  [[nodiscard]] bool passes(Vec2 a, Vec2 b) const {
    return site::segmentFits(grid, a, b, opt.radius + opt.edgeClearance);
  }
  void problem(RoadmapProblem::Severity sev, const std::string& station, Vec2 p, const std::string& what) {
    problems.push_back({sev, station, p, what});
  }

  // Lattice points are cell centres `k` cells apart. Of the k ways to lay the node rows, the one
  // through most cells on a ridge of the clearance across y (the middle of an aisle running along
  // x), and likewise for the columns: node lines run down the middle of aisles rather than two
  // lines off their middle. (A sum of clearances does not tell them apart: the open floor swamps it.)
  Vec2 chooseLatticeOrigin(int k) {
    const double res = grid.resolution();
    const Vec2 first = grid.origin() + Vec2{0.5 * res, 0.5 * res};
    if (k <= 1) {
      return first;
    }
    const auto c = cellClearance(grid);
    const int w = grid.width();
    const int h = grid.height();
    auto at = [&](int x, int y) { return c[grid.index({x, y})]; };
    auto ridge = [](float v, float a, float b) { return v >= a && v >= b && v > std::min(a, b); };
    std::vector<std::size_t> rows(static_cast<std::size_t>(k), 0);
    std::vector<std::size_t> cols(static_cast<std::size_t>(k), 0);
    for (int y = 1; y + 1 < h; ++y) {
      for (int x = 1; x + 1 < w; ++x) {
        const float v = at(x, y);
        if (static_cast<double>(v) < opt.radius) {
          continue;
        }
        rows[static_cast<std::size_t>(y % k)] += ridge(v, at(x, y - 1), at(x, y + 1)) ? 1 : 0;
        cols[static_cast<std::size_t>(x % k)] += ridge(v, at(x - 1, y), at(x + 1, y)) ? 1 : 0;
      }
    }
    const auto px = std::max_element(cols.begin(), cols.end()) - cols.begin();
    const auto py = std::max_element(rows.begin(), rows.end()) - rows.begin();
    return first + Vec2{static_cast<double>(px) * res, static_cast<double>(py) * res};
  }

  // The lattice, and where it misses a passage (its disc-fit band narrower than the spacing falls
  // between two node lines, e.g. a 1 m corridor centred on a cell edge of a 0.5 m map) nodes half a
  // spacing off it: a point midway between two lattice points neither of which fits. Those join
  // every node within a diagonal step.
  void buildLattice() {
    const double res = grid.resolution();
    const double cells = opt.spacing / res;
    const int k = std::abs(cells - std::round(cells)) < 1e-6 ? static_cast<int>(std::round(cells)) : 1;
    latticeOrigin = chooseLatticeOrigin(k);
    const Vec2 hi = grid.origin() + Vec2{grid.width() * res, grid.height() * res};
    const double lwd = std::max(0.0, std::floor((hi.x - latticeOrigin.x) / opt.spacing) + 1.0);
    const double lhd = std::max(0.0, std::floor((hi.y - latticeOrigin.y) / opt.spacing) + 1.0);
    if (!(lwd * lhd <= static_cast<double>(kMaxLatticePoints))) {
      std::ostringstream os;
      os << "roadmap: a lattice " << opt.spacing << " m apart over the map's " << grid.width() * res << " x "
         << grid.height() * res << " m has " << lwd * lhd << " points, more than the limit of "
         << static_cast<long long>(kMaxLatticePoints) << "; give the roadmap a larger spacing";
      throw ConfigError({os.str()});
    }
    const int lw = static_cast<int>(lwd);
    const int lh = static_cast<int>(lhd);
    // Half-spacing grid: lattice points at even (a, b), the half-offset ones at one odd coordinate.
    const int hw = 2 * lw;
    const int hh = 2 * lh;
    std::vector<NodeId> id(static_cast<std::size_t>(hw) * static_cast<std::size_t>(hh), kNoNode);
    auto at = [&](int a, int b) -> NodeId {
      return a < 0 || b < 0 || a >= hw || b >= hh ? kNoNode : id[static_cast<std::size_t>(b * hw + a)];
    };
    auto point = [&](int a, int b) {
      return latticeOrigin + Vec2{a * 0.5 * opt.spacing, b * 0.5 * opt.spacing};
    };
    for (int b = 0; b < hh; b += 2) {
      for (int a = 0; a < hw; a += 2) {
        if (latticeFits(point(a, b))) {
          id[static_cast<std::size_t>(b * hw + a)] = add(point(a, b), NodeKind::Lane);
        }
      }
    }
    std::vector<std::pair<int, int>> filled;
    for (int b = 0; b < hh; b += 2) {
      for (int a = 0; a < hw; a += 2) {
        const bool right = a + 2 < hw && at(a, b) == kNoNode && at(a + 2, b) == kNoNode;
        const bool up = b + 2 < hh && at(a, b) == kNoNode && at(a, b + 2) == kNoNode;
        if (right && latticeFits(point(a + 1, b))) {
          filled.emplace_back(a + 1, b);
        }
        if (up && latticeFits(point(a, b + 1))) {
          filled.emplace_back(a, b + 1);
        }
      }
    }
    for (const auto& [a, b] : filled) {
      id[static_cast<std::size_t>(b * hw + a)] = add(point(a, b), NodeKind::Lane);
    }
    latticeCount = pos.size();
    std::vector<std::pair<int, int>> steps{{2, 0}, {0, 2}};
    if (opt.diagonals) {
      steps.insert(steps.end(), {{2, 2}, {-2, 2}});
    }
    auto link = [&](NodeId u, NodeId v) {
      if (passes(pos[static_cast<std::size_t>(u)], pos[static_cast<std::size_t>(v)])) {
        links.push_back({u, v, true, true});
      }
    };
    for (int b = 0; b < hh; b += 2) {
      for (int a = 0; a < hw; a += 2) {
        const NodeId u = at(a, b);
        for (const auto& [da, db] : steps) {
          if (u != kNoNode && at(a + da, b + db) != kNoNode) {
            link(u, at(a + da, b + db));
          }
        }
      }
    }
    for (const auto& [a, b] : filled) {
      const NodeId u = at(a, b);
      for (int db = -2; db <= 2; ++db) {
        for (int da = -2; da <= 2; ++da) {
          const NodeId v = at(a + da, b + db);
          const bool lattice = (a + da) % 2 == 0 && (b + db) % 2 == 0;
          if (v == kNoNode || v == u || (!lattice && v < u) || (!opt.diagonals && da != 0 && db != 0)) {
            continue;
          }
          link(u, v);
        }
      }
    }
  }

  enum class Join { Both, Out, In };

  // Joins `v` to the lattice nodes within one spacing that the disc reaches in a straight line
  // keeping the edge clearance and that lie within `cone` rad of one of `dirs` (any direction when
  // `dirs` is empty); failing that, to the nearest two such within three spacings; failing both,
  // the same with edges that clear the disc only. The number of nodes joined.
  int joinToLattice(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how) {
    const int joined = joinToLattice(v, dirs, cone, how, true);
    return joined > 0 ? joined : joinToLattice(v, dirs, cone, how, false);
  }
  int joinToLattice(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how, bool wide) {
    const Vec2 p = pos[static_cast<std::size_t>(v)];
    std::vector<std::pair<double, NodeId>> near;
    const double reach2 = std::pow(3.0 * opt.spacing + 1e-9, 2);
    for (NodeId w = 0; w < static_cast<NodeId>(latticeCount); ++w) {
      const Vec2 d = pos[static_cast<std::size_t>(w)] - p;
      if (d.squaredNorm() > reach2) {
        continue;
      }
      const bool inCone = dirs.empty() || std::any_of(dirs.begin(), dirs.end(), [&](Vec2 u) {
                            return angleBetween(u, d) <= cone + 1e-9;
                          });
      if (d.norm() > 1e-9 && d.norm() <= 3.0 * opt.spacing + 1e-9 && inCone) {
        near.emplace_back(d.norm(), w);
      }
    }
    std::sort(near.begin(), near.end());
    int joined = 0;
    for (const auto& [d, w] : near) {
      if (d > opt.spacing + 1e-9 && joined >= 2) {
        break;
      }
      if (wide ? passes(p, pos[static_cast<std::size_t>(w)]) : sweeps(p, pos[static_cast<std::size_t>(w)])) {
        links.push_back({v, w, how != Join::In, how != Join::Out});
        ++joined;
      }
    }
    return joined;
  }

  // Queues keep a following distance from every station node placed so far.
  [[nodiscard]] bool clearOfStations(Vec2 p, double keep) const {
    for (std::size_t v = latticeCount; v < pos.size(); ++v) {
      if (distance(p, pos[v]) < keep - 1e-9) {
        return false;
      }
    }
    return true;
  }

  // Back from `base` along each of `dirs` in turn while the disc fits; the longest line wins.
  std::vector<Vec2> generateQueue(Vec2 base, const std::vector<Vec2>& dirs) {
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

  [[nodiscard]] NodeId entryOf(const StationNodes& sn) const {
    return sn.approach != kNoNode ? sn.approach : sn.dock;
  }

  // Where robots go after this station: the drop-offs after a pickup, the pickups after a
  // drop-off (their centroid); none for chargers and parking places.
  [[nodiscard]] std::optional<Vec2> nextPlaces(site::StationKind k) const {
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
  [[nodiscard]] std::optional<Vec2> placeExit(const site::Station& st, const StationNodes& sn) const {
    if (st.exit) {
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
  void placeStations() {
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
                "station '" + st.name + "' at " + detail::pointText(dockAt) + ": the robot's disc (radius " +
                    r.str() + " m) does not fit there: no dock node");
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
                  "station '" + st.name + "': the robot cannot drive straight from its approach point " +
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
      if (const auto e = placeExit(st, sn)) {
        const Vec2 dockAt = pos[static_cast<std::size_t>(sn.dock)];
        if (fits(*e) && sweeps(dockAt, *e)) {
          sn.exit = add(*e, NodeKind::Exit);
          links.push_back({sn.dock, sn.exit, true, false});
        } else {
          problem(RoadmapProblem::Severity::Error, st.name, *e,
                  "station '" + st.name + "': the robot cannot drive straight from the dock " +
                      detail::pointText(dockAt) + " to its exit " + detail::pointText(*e) +
                      "; left by its way in instead");
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
      int joined = inDirs.empty() ? 0 : joinToLattice(entry, inDirs, kCone, in);
      if (joined == 0) {
        joined = joinToLattice(entry, {}, 0.0, in);
      }
      if (joined == 0) {
        std::ostringstream d;
        d << 3.0 * opt.spacing;
        problem(RoadmapProblem::Severity::Error, st.name, ep,
                "station '" + st.name + "': no lane node within " + d.str() + " m of its " +
                    (sn.approach != kNoNode ? "approach point " : "dock ") + detail::pointText(ep) +
                    " that the robot reaches in a straight line: the station is not on the roadmap");
      }
      if (sn.exit != kNoNode) {
        const Vec2 xp = pos[static_cast<std::size_t>(sn.exit)];
        const Vec2 out = (xp - dockAt).normalized();
        if (joinToLattice(sn.exit, {out}, kCone, Join::Out) == 0 &&
            joinToLattice(sn.exit, {}, 0.0, Join::Out) == 0) {
          problem(RoadmapProblem::Severity::Error, st.name, xp,
                  "station '" + st.name + "': no lane node near its exit " + detail::pointText(xp) +
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
  void placeQueue(const site::Station& st, StationNodes& sn) {
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
                "station '" + st.name + "': the robot's disc does not fit on queue point " +
                    std::to_string(q) + " " + detail::pointText(queue[q]));
        continue;
      }
      const Vec2 nextAt = pos[static_cast<std::size_t>(next)];
      const NodeId v = add(queue[q], NodeKind::Queue);
      if (sweeps(queue[q], nextAt)) {
        links.push_back({v, next, true, false});
      } else {
        problem(RoadmapProblem::Severity::Warning, st.name, queue[q],
                "station '" + st.name + "': queue point " + std::to_string(q) + " " +
                    detail::pointText(queue[q]) + " cannot be driven straight to the one before it");
      }
      sn.queue.push_back(v);
      next = v;
    }
  }

  // A queue is left sideways from any of its places and entered at its tail from behind.
  void joinQueue(const StationNodes& sn) {
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

  // One-way zones: a direction is dropped when, anywhere along the edge, it runs more than 90°
  // off the zone's direction.
  bool allowed(Vec2 a, Vec2 b) const {
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
  double driveTime(Vec2 a, Vec2 b) const {
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
};

}  // namespace

const char* toString(NodeKind k) {
  constexpr const char* kNames[] = {"lane", "station", "approach", "queue", "parking", "charger", "exit"};
  return kNames[static_cast<int>(k)];
}

Roadmap buildRoadmap(const site::Site& s, const RoadmapOptions& options) {
  const auto& in = options;
  if (!(in.cruiseSpeed > 0.0) || in.spacing < 0.0 || (in.spacing > 0.0 && in.spacing < 0.05) ||
      !(in.targetSpacing >= 0.05) || in.radius < 0.0 || in.stopGap < 0.0 || in.corridorSlack < 0.0 ||
      in.nodeClearance < 0.0 || in.edgeClearance < 0.0 || in.margin < 0.0 || in.queueLength < 0 ||
      in.queueLength > 50 || in.followingDistance < 0.0) {
    throw std::invalid_argument(
        "RoadmapOptions: cruiseSpeed > 0, spacing 0 or >= 0.05 m, targetSpacing >= 0.05 m, radius, stopGap, "
        "corridorSlack, nodeClearance, edgeClearance, margin and followingDistance >= 0, queueLength 0..50");
  }
  Builder b{s, options, s.drivable(), {}, {}, {}, {}, {}, 0, {}};
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
  // Turning: an edge's duration includes the smallest turn any way into its start needs (a lower
  // bound without knowing where the robot came from; exact at nodes with one way in).
  const auto nn = static_cast<NodeId>(r.graph.size());
  std::vector<std::vector<NodeId>> into(r.graph.size());
  for (NodeId v = 0; v < nn; ++v) {
    for (const auto& e : r.graph.edges(v)) {
      into[static_cast<std::size_t>(e.to)].push_back(v);
    }
  }
  r.turnIncluded_.assign(r.graph.size(), {});
  for (NodeId v = 0; v < nn; ++v) {
    const Vec2 pv = r.graph.position(v);
    const std::vector<Edge> out(r.graph.edges(v).begin(), r.graph.edges(v).end());
    for (const auto& e : out) {
      double turn = into[static_cast<std::size_t>(v)].empty() ? 0.0 : kPi;
      for (const NodeId w : into[static_cast<std::size_t>(v)]) {
        turn = std::min(turn, angleBetween(pv - r.graph.position(w), r.graph.position(e.to) - pv));
      }
      const double t = r.turnTime(turn);
      r.turnIncluded_[static_cast<std::size_t>(v)].push_back(t);
      r.graph.addEdge(v, e.to, e.duration + t);
    }
  }

  r.stations = std::move(b.stations);
  r.options = o;
  r.separation = sep;
  r.latticeOrigin = b.latticeOrigin;
  std::vector<std::uint8_t> waiting(r.kinds.size(), 0);
  for (std::size_t v = 0; v < r.kinds.size(); ++v) {
    waiting[v] = r.kinds[v] != NodeKind::Lane ? 1 : 0;
  }
  addGeometricConflicts(r.graph, sep, waiting);

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
  for (const auto& sn : r.stations) {
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
                  "station '" + sn.name + "': a robot waiting on queue point " + std::to_string(q) + " " +
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

double Roadmap::extraTurn(NodeId prev, NodeId atNode, NodeId next) const {
  if (!graph.valid(prev) || !graph.valid(atNode) || !graph.valid(next)) {
    return 0.0;
  }
  const auto out = graph.edges(atNode);
  for (std::size_t k = 0; k < out.size(); ++k) {
    if (out[k].to == next) {
      const Vec2 p = graph.position(atNode);
      const double exact = turnTime(angleBetween(p - graph.position(prev), graph.position(next) - p));
      return std::max(0.0, exact - turnIncluded_[static_cast<std::size_t>(atNode)][k]);
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
