#include "fleet/geometry/bvh.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace fleet::geometry {

double Primitive::distanceTo(Vec2 p) const {
  if (kind == Kind::Box) {
    return box.distanceTo(p);
  }
  return std::max(0.0, (p - center).norm() - radius);
}

bool Primitive::overlaps(const Aabb2& q) const {
  if (kind == Kind::Box) {
    return geometry::overlaps(box, q);
  }
  return q.distanceTo(center) <= radius;
}

bool Primitive::overlapsDisc(Vec2 c, double r) const {
  if (kind == Kind::Box) {
    return box.distanceTo(c) <= r;
  }
  return (c - center).norm() <= r + radius;
}

std::optional<double> Primitive::ray(Vec2 o, Vec2 dir, double tmax) const {
  if (kind == Kind::Box) {
    return box.rayEntry(o, dir, tmax);
  }
  const Vec2 m = o - center;
  const double b = m.dot(dir);
  const double c = m.squaredNorm() - radius * radius;
  if (c <= 0.0) {
    return 0.0;  // origin inside the disc
  }
  const double disc = b * b - c;
  if (b > 0.0 || disc < 0.0) {
    return std::nullopt;
  }
  const double t = -b - std::sqrt(disc);
  if (t > tmax) {
    return std::nullopt;
  }
  return std::max(t, 0.0);
}

Bvh2::Bvh2(std::vector<Primitive> prims, int leafSize)
    : prims_(std::move(prims)), leafSize_(std::max(1, leafSize)) {
  order_.reserve(prims_.size());
  for (std::size_t i = 0; i < prims_.size(); ++i) {
    order_.push_back(static_cast<int>(i));
  }
  if (!prims_.empty()) {
    nodes_.reserve(2 * prims_.size() / static_cast<std::size_t>(leafSize_) + 2);
    build(0, static_cast<int>(prims_.size()));
  }
}

int Bvh2::build(int first, int count) {
  const int idx = static_cast<int>(nodes_.size());
  nodes_.push_back({});
  Aabb2 box = prims_[static_cast<std::size_t>(order_[static_cast<std::size_t>(first)])].box;
  Aabb2 cb{box.center(), box.center()};
  for (int k = first; k < first + count; ++k) {
    const Aabb2& b = prims_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])].box;
    box = box.merged(b);
    cb = cb.merged({b.center(), b.center()});
  }
  nodes_[static_cast<std::size_t>(idx)].box = box;
  if (count <= leafSize_) {
    nodes_[static_cast<std::size_t>(idx)].first = first;
    nodes_[static_cast<std::size_t>(idx)].count = count;
    return idx;
  }
  // Median cut on the longest axis of the centroids: children differ in size by at most one.
  const bool splitX = cb.extent().x >= cb.extent().y;
  const int half = count / 2;
  auto begin = order_.begin() + first;
  std::nth_element(begin, begin + half, begin + count, [&](int a, int b) {
    const Vec2 ca = prims_[static_cast<std::size_t>(a)].box.center();
    const Vec2 cbb = prims_[static_cast<std::size_t>(b)].box.center();
    return splitX ? ca.x < cbb.x : ca.y < cbb.y;
  });
  const int l = build(first, half);
  const int r = build(first + half, count - half);
  nodes_[static_cast<std::size_t>(idx)].left = l;
  nodes_[static_cast<std::size_t>(idx)].right = r;
  return idx;
}

int Bvh2::depth() const {
  if (nodes_.empty()) {
    return 0;
  }
  int best = 0;
  std::vector<std::pair<int, int>> stack{{0, 1}};
  while (!stack.empty()) {
    auto [n, d] = stack.back();
    stack.pop_back();
    best = std::max(best, d);
    const Node& node = nodes_[static_cast<std::size_t>(n)];
    if (!isLeaf(node)) {
      stack.push_back({node.left, d + 1});
      stack.push_back({node.right, d + 1});
    }
  }
  return best;
}

bool Bvh2::checkInvariants() const {
  auto encloses = [](const Aabb2& outer, const Aabb2& inner) {
    return outer.min.x <= inner.min.x && outer.min.y <= inner.min.y && outer.max.x >= inner.max.x &&
           outer.max.y >= inner.max.y;
  };
  std::size_t seen = 0;
  for (const Node& n : nodes_) {
    if (isLeaf(n)) {
      if (n.count < 1 || n.count > leafSize_) {
        return false;
      }
      for (int k = n.first; k < n.first + n.count; ++k) {
        if (!encloses(n.box, prims_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])].box)) {
          return false;
        }
      }
      seen += static_cast<std::size_t>(n.count);
    } else {
      if (!encloses(n.box, nodes_[static_cast<std::size_t>(n.left)].box) ||
          !encloses(n.box, nodes_[static_cast<std::size_t>(n.right)].box)) {
        return false;
      }
    }
  }
  return seen == prims_.size();
}

std::vector<int> Bvh2::overlapping(const Aabb2& q) const {
  std::vector<int> out;
  if (nodes_.empty()) {
    return out;
  }
  int stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--sp])];
    if (!geometry::overlaps(n.box, q)) {
      continue;
    }
    if (isLeaf(n)) {
      for (int k = n.first; k < n.first + n.count; ++k) {
        const int id = order_[static_cast<std::size_t>(k)];
        if (prims_[static_cast<std::size_t>(id)].overlaps(q)) {
          out.push_back(id);
        }
      }
    } else {
      stack[sp++] = n.left;
      stack[sp++] = n.right;
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<int> Bvh2::overlappingDisc(Vec2 c, double r) const {
  std::vector<int> out;
  if (nodes_.empty()) {
    return out;
  }
  int stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--sp])];
    if (n.box.distanceTo(c) > r) {
      continue;
    }
    if (isLeaf(n)) {
      for (int k = n.first; k < n.first + n.count; ++k) {
        const int id = order_[static_cast<std::size_t>(k)];
        if (prims_[static_cast<std::size_t>(id)].overlapsDisc(c, r)) {
          out.push_back(id);
        }
      }
    } else {
      stack[sp++] = n.left;
      stack[sp++] = n.right;
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

bool Bvh2::anyOverlapDisc(Vec2 c, double r) const {
  if (nodes_.empty()) {
    return false;
  }
  int stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--sp])];
    if (n.box.distanceTo(c) > r) {
      continue;
    }
    if (isLeaf(n)) {
      for (int k = n.first; k < n.first + n.count; ++k) {
        if (prims_[static_cast<std::size_t>(order_[static_cast<std::size_t>(k)])].overlapsDisc(c, r)) {
          return true;
        }
      }
    } else {
      stack[sp++] = n.left;
      stack[sp++] = n.right;
    }
  }
  return false;
}

NearestResult Bvh2::nearest(Vec2 p) const {
  NearestResult best{-1, std::numeric_limits<double>::infinity()};
  if (nodes_.empty()) {
    return best;
  }
  int stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--sp])];
    if (n.box.distanceTo(p) >= best.distance && best.index >= 0) {
      continue;
    }
    if (isLeaf(n)) {
      for (int k = n.first; k < n.first + n.count; ++k) {
        const int id = order_[static_cast<std::size_t>(k)];
        const double d = prims_[static_cast<std::size_t>(id)].distanceTo(p);
        if (d < best.distance || (d == best.distance && id < best.index)) {
          best = {id, d};
        }
      }
    } else {
      // Visit the nearer child first so that the bound tightens early.
      const double dl = nodes_[static_cast<std::size_t>(n.left)].box.distanceTo(p);
      const double dr = nodes_[static_cast<std::size_t>(n.right)].box.distanceTo(p);
      if (dl <= dr) {
        stack[sp++] = n.right;
        stack[sp++] = n.left;
      } else {
        stack[sp++] = n.left;
        stack[sp++] = n.right;
      }
    }
  }
  return best;
}

std::optional<RayResult> Bvh2::raycast(Vec2 origin, Vec2 dir, double maxRange) const {
  dir = dir.normalized();
  std::optional<RayResult> best;
  double tmax = maxRange;
  if (nodes_.empty()) {
    return best;
  }
  int stack[128];
  int sp = 0;
  stack[sp++] = 0;
  while (sp > 0) {
    const Node& n = nodes_[static_cast<std::size_t>(stack[--sp])];
    const auto te = n.box.rayEntry(origin, dir, tmax);
    if (!te) {
      continue;
    }
    if (isLeaf(n)) {
      for (int k = n.first; k < n.first + n.count; ++k) {
        const int id = order_[static_cast<std::size_t>(k)];
        const auto t = prims_[static_cast<std::size_t>(id)].ray(origin, dir, tmax);
        if (t && (!best || *t < best->range || (*t == best->range && id < best->index))) {
          best = RayResult{id, *t};
          tmax = *t;
        }
      }
    } else {
      stack[sp++] = n.right;
      stack[sp++] = n.left;
    }
  }
  return best;
}

bool Bvh2::intersects(const Bvh2& other, std::int64_t* bvTests) const {
  if (nodes_.empty() || other.nodes_.empty()) {
    return false;
  }
  return intersectsRec(0, other, 0, bvTests);
}

bool Bvh2::intersectsRec(int a, const Bvh2& other, int b, std::int64_t* tests) const {
  const Node& na = nodes_[static_cast<std::size_t>(a)];
  const Node& nb = other.nodes_[static_cast<std::size_t>(b)];
  if (tests != nullptr) {
    ++*tests;
  }
  if (!geometry::overlaps(na.box, nb.box)) {
    return false;
  }
  const bool leafA = isLeaf(na);
  const bool leafB = other.isLeaf(nb);
  if (leafA && leafB) {
    // The leaf case missing from the printed pseudocode: test the primitives themselves.
    for (int i = na.first; i < na.first + na.count; ++i) {
      const Primitive& pa = prims_[static_cast<std::size_t>(order_[static_cast<std::size_t>(i)])];
      for (int j = nb.first; j < nb.first + nb.count; ++j) {
        const Primitive& pb =
            other.prims_[static_cast<std::size_t>(other.order_[static_cast<std::size_t>(j)])];
        const bool hit =
            pb.kind == Primitive::Kind::Box ? pa.overlaps(pb.box) : pa.overlapsDisc(pb.center, pb.radius);
        if (hit) {
          return true;
        }
      }
    }
    return false;
  }
  // Descend into the bigger volume (by area), as the thesis does after its swap.
  const double areaA = na.box.extent().x * na.box.extent().y;
  const double areaB = nb.box.extent().x * nb.box.extent().y;
  if (leafB || (!leafA && areaA >= areaB)) {
    return intersectsRec(na.left, other, b, tests) || intersectsRec(na.right, other, b, tests);
  }
  return intersectsRec(a, other, nb.left, tests) || intersectsRec(a, other, nb.right, tests);
}

std::vector<int> bruteOverlapping(const std::vector<Primitive>& prims, const Aabb2& q) {
  std::vector<int> out;
  for (std::size_t i = 0; i < prims.size(); ++i) {
    if (prims[i].overlaps(q)) {
      out.push_back(static_cast<int>(i));
    }
  }
  return out;
}

NearestResult bruteNearest(const std::vector<Primitive>& prims, Vec2 p) {
  NearestResult best{-1, std::numeric_limits<double>::infinity()};
  for (std::size_t i = 0; i < prims.size(); ++i) {
    const double d = prims[i].distanceTo(p);
    if (d < best.distance) {
      best = {static_cast<int>(i), d};
    }
  }
  return best;
}

std::optional<RayResult> bruteRaycast(const std::vector<Primitive>& prims, Vec2 origin, Vec2 dir,
                                      double maxRange) {
  dir = dir.normalized();
  std::optional<RayResult> best;
  for (std::size_t i = 0; i < prims.size(); ++i) {
    const auto t = prims[i].ray(origin, dir, maxRange);
    if (t && (!best || *t < best->range)) {
      best = RayResult{static_cast<int>(i), *t};
    }
  }
  return best;
}

}  // namespace fleet::geometry
