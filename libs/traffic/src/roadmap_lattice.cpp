// The roadmap's lattice: where its rows and columns lie, its nodes and edges, and how other nodes
// join it.

#include <algorithm>
#include <cmath>
#include <sstream>

#include "fleet/core/config.hpp"
#include "roadmap_builder.hpp"

namespace fleet::traffic::detail {

namespace {

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

}  // namespace

bool RoadmapBuilder::clearOfResting(Vec2 a, Vec2 b) const {
  const bool moving = distance(a, b) > 1e-9;
  // No motion reaches further than `ahead` beyond its own segment (roadmap_conflicts.hpp): only the
  // parking places in that box can be too close. `resting` is sorted by x.
  const double lo = std::min(a.x, b.x) - sep.ahead;
  const double hi = std::max(a.x, b.x) + sep.ahead;
  const double ylo = std::min(a.y, b.y) - sep.ahead;
  const double yhi = std::max(a.y, b.y) + sep.ahead;
  auto it = std::lower_bound(resting.begin(), resting.end(), lo, [](Vec2 r, double x) { return r.x < x; });
  for (; it != resting.end() && it->x <= hi; ++it) {
    if (it->y < ylo || it->y > yhi) {
      continue;
    }
    const Motion rests{*it, *it, false};
    if (unsafe({a, b, moving}, rests, sep) || (moving && unsafe({b, a, true}, rests, sep))) {
      return false;
    }
  }
  return true;
}

// Lattice points are cell centres `k` cells apart. Of the k ways to lay the node rows, the one
// through most cells on a ridge of the clearance across y (the middle of an aisle running along
// x), and likewise for the columns: node lines run down the middle of aisles rather than two
// lines off their middle. (A sum of clearances does not tell them apart: the open floor swamps it.)
Vec2 RoadmapBuilder::chooseLatticeOrigin(int k) {
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
void RoadmapBuilder::buildLattice() {
  const double res = grid.resolution();
  const double cells = opt.spacing / res;
  const int k = std::abs(cells - std::round(cells)) < 1e-6 ? static_cast<int>(std::round(cells)) : 1;
  latticeOrigin = chooseLatticeOrigin(k);
  resting.clear();
  for (const auto& st : site.stations) {
    if (opt.parkingClear && st.kind == site::StationKind::Parking) {
      resting.push_back(st.pose.position());
    }
  }
  std::sort(resting.begin(), resting.end(), [](Vec2 p, Vec2 q) { return p.x < q.x; });
  const auto open = [&](Vec2 p) { return latticeFits(p) && clearOfResting(p, p); };
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
      if (open(point(a, b))) {
        id[static_cast<std::size_t>(b * hw + a)] = add(point(a, b), NodeKind::Lane);
      }
    }
  }
  std::vector<std::pair<int, int>> filled;
  for (int b = 0; b < hh; b += 2) {
    for (int a = 0; a < hw; a += 2) {
      const bool right = a + 2 < hw && at(a, b) == kNoNode && at(a + 2, b) == kNoNode;
      const bool up = b + 2 < hh && at(a, b) == kNoNode && at(a, b + 2) == kNoNode;
      if (right && open(point(a + 1, b))) {
        filled.emplace_back(a + 1, b);
      }
      if (up && open(point(a, b + 1))) {
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
    const Vec2 pu = pos[static_cast<std::size_t>(u)];
    const Vec2 pv = pos[static_cast<std::size_t>(v)];
    if (passes(pu, pv) && clearOfResting(pu, pv)) {
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
  // A lattice node left without an edge (all of them too close to a parked robot) leads nowhere:
  // a station joined to it would be cut off.
  latticeLinked.assign(latticeCount, 0);
  for (const auto& l : links) {
    latticeLinked[static_cast<std::size_t>(l.a)] = 1;
    latticeLinked[static_cast<std::size_t>(l.b)] = 1;
  }
}

// Joins `v` to the lattice nodes within one spacing that the disc reaches in a straight line
// keeping the edge clearance and that lie within `cone` rad of one of `dirs` (any direction when
// `dirs` is empty); failing that, to the nearest two such within three spacings; failing both,
// the same with edges that clear the disc only. The number of nodes joined.
int RoadmapBuilder::joinToLattice(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how) {
  const int joined = joinToLattice(v, dirs, cone, how, true);
  return joined > 0 ? joined : joinToLattice(v, dirs, cone, how, false);
}

int RoadmapBuilder::joinClear(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how) {
  for (const bool wide : {true, false}) {
    if (!dirs.empty()) {
      if (const int joined = joinToLattice(v, dirs, cone, how, wide); joined > 0) {
        return joined;
      }
    }
    if (const int joined = joinToLattice(v, {}, 0.0, how, wide); joined > 0) {
      return joined;
    }
  }
  return 0;
}

int RoadmapBuilder::joinToLattice(NodeId v, const std::vector<Vec2>& dirs, double cone, Join how, bool wide) {
  const Vec2 p = pos[static_cast<std::size_t>(v)];
  std::vector<std::pair<double, NodeId>> near;
  const double reach2 = std::pow(3.0 * opt.spacing + 1e-9, 2);
  for (NodeId w = 0; w < static_cast<NodeId>(latticeCount); ++w) {
    if (latticeLinked[static_cast<std::size_t>(w)] == 0) {
      continue;
    }
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

}  // namespace fleet::traffic::detail
