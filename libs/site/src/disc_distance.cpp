#include "fleet/site/disc_distance.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>
#include <queue>
#include <stdexcept>
#include <string>
#include <vector>

#include "fleet/planning/segment_free.hpp"
#include "fleet/planning/wavefront.hpp"
#include "fleet/site/reachability.hpp"

namespace fleet::site {

namespace {

using planning::Cell;
using planning::OccupancyGrid;

constexpr double kFinestCellM = 0.1;

std::string where(Vec2 p) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "(%.2f, %.2f)", p.x, p.y);
  return buf;
}

/// The refined grid of disc centres: a cell is free when the disc on its centre overlaps no
/// blocked cell of `map` and the centre itself is not in one (which matters only for radius 0).
std::shared_ptr<const OccupancyGrid> configurationGrid(const OccupancyGrid& map, double radius) {
  if (map.size() == 0 || !std::isfinite(radius) || radius < 0.0) {
    throw std::invalid_argument("DiscDistance: needs a non-empty map and a finite radius >= 0 (got " +
                                std::to_string(radius) + ")");
  }
  const double res = map.resolution();
  const int k = std::max(1, static_cast<int>(std::ceil(res / kFinestCellM - 1e-9)));
  auto g = std::make_shared<OccupancyGrid>(map.width() * k, map.height() * k, res / k, map.origin());
  for (int y = 0; y < g->height(); ++y) {
    for (int x = 0; x < g->width(); ++x) {
      const Vec2 c = g->cellCenter({x, y});
      if (map.blocked({x / k, y / k}) || !discFits(map, c, radius)) {
        g->setBlocked({x, y});
      }
    }
  }
  return g;
}

}  // namespace

DiscDistance::DiscDistance(const OccupancyGrid& map, double radius, std::size_t cachedFields)
    : radius_(radius),
      grid_(configurationGrid(map, radius)),
      capacity_(std::max<std::size_t>(1, cachedFields)) {}

Expected<DiscDistance::Snapped> DiscDistance::snap(Vec2 p, const char* what) const {
  const auto cell = p.isFinite() ? grid_->cellAt(p) : std::nullopt;
  if (!cell) {
    return unexpected("off_map", std::string(what) + " " + where(p) + " is outside the map");
  }
  if (grid_->freeCell(*cell)) {
    return Snapped{*cell, 0.0};
  }
  const int reach = static_cast<int>(std::ceil(kSnapM / grid_->resolution()));
  std::optional<Snapped> best;
  for (int dy = -reach; dy <= reach; ++dy) {
    for (int dx = -reach; dx <= reach; ++dx) {
      const Cell c{cell->x + dx, cell->y + dy};
      if (grid_->blocked(c)) {
        continue;
      }
      const double d = (grid_->cellCenter(c) - p).norm();
      if (d <= kSnapM && (!best || d < best->leg)) {
        best = Snapped{c, d};
      }
    }
  }
  if (!best) {
    char buf[96];
    std::snprintf(buf, sizeof buf, "a disc of radius %.2f m fits nowhere within %.1f m of the ", radius_,
                  kSnapM);
    return unexpected("no_room", buf + std::string(what) + " " + where(p));
  }
  return *best;
}

Vec2 DiscDistance::parentPoint(const Field& f, std::int32_t parent) const {
  return parent == kRoot ? f.root : grid_->cellCenter(grid_->cellOf(static_cast<std::size_t>(parent)));
}

const DiscDistance::Field& DiscDistance::field(Vec2 goal, const Snapped& at) {
  for (auto it = fields_.begin(); it != fields_.end(); ++it) {
    if ((*it)->goal.x == goal.x && (*it)->goal.y == goal.y) {
      std::rotate(it, it + 1, fields_.end());
      return *fields_.back();
    }
  }
  if (fields_.size() >= capacity_) {
    fields_.erase(fields_.begin());
  }
  auto f = std::make_unique<Field>();
  f->goal = goal;
  f->root = at.leg == 0.0 ? goal : grid_->cellCenter(at.cell);
  const std::size_t n = grid_->size();
  const double inf = std::numeric_limits<double>::infinity();
  f->g.assign(n, inf);
  f->parent.assign(n, kRoot);
  std::vector<std::uint8_t> settled(n, 0);
  using Item = std::pair<double, std::size_t>;
  std::priority_queue<Item, std::vector<Item>, std::greater<>> open;
  const std::size_t first = grid_->index(at.cell);
  f->g[first] = (f->root - grid_->cellCenter(at.cell)).norm();
  open.push({f->g[first], first});
  const auto& offsets = planning::neighbourOffsets(planning::Connectivity::Eight);
  while (!open.empty()) {
    const auto [gu, u] = open.top();
    open.pop();
    if (settled[u] != 0 || gu > f->g[u]) {
      continue;  // settled already, or queued before a shorter way was found
    }
    const Cell cu = grid_->cellOf(u);
    const Vec2 pu = grid_->cellCenter(cu);
    // The parent was taken from a neighbour on trust; when it is out of sight, the way goes through
    // the settled neighbour it is shortest through.
    if (u != first && !planning::segmentFree(*grid_, pu, parentPoint(*f, f->parent[u]))) {
      f->g[u] = inf;
      for (const Cell& o : offsets) {
        const Cell cn{cu.x + o.x, cu.y + o.y};
        if (!planning::moveAllowed(*grid_, cu, o)) {
          continue;
        }
        const std::size_t m = grid_->index(cn);
        const double via = f->g[m] + (grid_->cellCenter(cn) - pu).norm();
        if (settled[m] != 0 && via < f->g[u]) {
          f->g[u] = via;
          f->parent[u] = static_cast<std::int32_t>(m);
        }
      }
    }
    settled[u] = 1;
    // Its neighbours head for its parent too (in sight or not: seen to when they are settled).
    const std::int32_t parent = f->parent[u];
    const Vec2 pp = parentPoint(*f, parent);
    const double gp = parent == kRoot ? 0.0 : f->g[static_cast<std::size_t>(parent)];
    for (const Cell& o : offsets) {
      if (!planning::moveAllowed(*grid_, cu, o)) {
        continue;
      }
      const Cell cv{cu.x + o.x, cu.y + o.y};
      const std::size_t v = grid_->index(cv);
      const double via = gp + (grid_->cellCenter(cv) - pp).norm();
      if (settled[v] == 0 && via < f->g[v]) {
        f->g[v] = via;
        f->parent[v] = parent;
        open.push({via, v});
      }
    }
  }
  fields_.push_back(std::move(f));
  return *fields_.back();
}

Expected<double> DiscDistance::length(Vec2 from, Vec2 to) {
  const auto a = snap(from, "start");
  if (!a) {
    return unexpected(a.error());
  }
  const auto b = snap(to, "goal");
  if (!b) {
    return unexpected(b.error());
  }
  const Field& f = field(to, *b);
  const std::size_t at = grid_->index(a->cell);
  if (!std::isfinite(f.g[at])) {
    char r[32];
    std::snprintf(r, sizeof r, "%.2f", radius_);
    return unexpected("unreachable", std::string("no way for a disc of radius ") + r + " m from " +
                                         where(from) + " to " + where(to));
  }
  if (a->leg > 0.0) {
    return a->leg + f.g[at] + b->leg;
  }
  // From the point itself: straight to where its cell's way heads when that is in sight.
  const Vec2 pp = parentPoint(f, f.parent[at]);
  const double gp = f.parent[at] == kRoot ? 0.0 : f.g[static_cast<std::size_t>(f.parent[at])];
  const double direct = planning::segmentFree(*grid_, from, pp)
                            ? gp + (pp - from).norm()
                            : f.g[at] + (grid_->cellCenter(a->cell) - from).norm();
  return direct + b->leg;
}

}  // namespace fleet::site
