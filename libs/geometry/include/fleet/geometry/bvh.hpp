#pragma once

#include <cstdint>
#include <optional>
#include <vector>

#include "fleet/core/vec2.hpp"
#include "fleet/geometry/aabb.hpp"

namespace fleet::geometry {

/// An obstacle primitive: an axis-aligned box or a disc.
struct Primitive {
  enum class Kind : std::uint8_t { Box, Disc };
  Kind kind = Kind::Box;
  Aabb2 box;          ///< the box itself (Box) or the disc's bounding box (Disc)
  Vec2 center;        ///< Disc only
  double radius = 0;  ///< Disc only

  static Primitive makeBox(const Aabb2& b) { return {Kind::Box, b, b.center(), 0.0}; }
  static Primitive makeDisc(Vec2 c, double r) { return {Kind::Disc, {c - Vec2{r, r}, c + Vec2{r, r}}, c, r}; }
  [[nodiscard]] double distanceTo(Vec2 p) const;                                 ///< 0 inside
  [[nodiscard]] bool overlaps(const Aabb2& q) const;                             ///< closed sets
  [[nodiscard]] bool overlapsDisc(Vec2 c, double r) const;                       ///< closed sets
  [[nodiscard]] std::optional<double> ray(Vec2 o, Vec2 dir, double tmax) const;  ///< dir unit
};

struct NearestResult {
  int index = -1;
  double distance = 0.0;
};
struct RayResult {
  int index = -1;
  double range = 0.0;
};

/// Bounding-volume hierarchy over boxes and discs (thesis §2.1.3): median cut along the longest axis
/// of the centroid bounds, down to leaves of at most `leafSize` primitives. Leaves test their
/// primitives exactly (the printed traversal has no leaf case).
class Bvh2 {
 public:
  explicit Bvh2(std::vector<Primitive> prims, int leafSize = 4);

  [[nodiscard]] std::vector<int> overlapping(const Aabb2& q) const;
  [[nodiscard]] std::vector<int> overlappingDisc(Vec2 c, double r) const;
  [[nodiscard]] bool anyOverlapDisc(Vec2 c, double r) const;
  /// Nearest primitive to p and its distance (0 if p is inside one); index -1 when empty.
  [[nodiscard]] NearestResult nearest(Vec2 p) const;
  /// First primitive hit by the ray origin + t*dir (dir is normalised here), t in [0, maxRange].
  [[nodiscard]] std::optional<RayResult> raycast(Vec2 origin, Vec2 dir, double maxRange) const;
  /// The thesis's BVH-vs-BVH detection, with the leaf case; counts bounding-volume tests.
  [[nodiscard]] bool intersects(const Bvh2& other, std::int64_t* bvTests = nullptr) const;

  [[nodiscard]] const std::vector<Primitive>& primitives() const { return prims_; }
  [[nodiscard]] int nodeCount() const { return static_cast<int>(nodes_.size()); }
  [[nodiscard]] int depth() const;
  /// Structural invariants (each node encloses its children, leaf sizes); for tests.
  [[nodiscard]] bool checkInvariants() const;

 private:
  struct Node {
    Aabb2 box;
    int left = -1;  ///< child node indices; -1 for a leaf
    int right = -1;
    int first = 0;  ///< leaf range in order_
    int count = 0;
  };
  int build(int first, int count);
  [[nodiscard]] bool isLeaf(const Node& n) const { return n.left < 0; }
  bool intersectsRec(int a, const Bvh2& other, int b, std::int64_t* tests) const;

  std::vector<Primitive> prims_;
  std::vector<int> order_;
  std::vector<Node> nodes_;
  int leafSize_;
};

/// Brute-force references (tests and benchmarks compare the BVH against them).
std::vector<int> bruteOverlapping(const std::vector<Primitive>& prims, const Aabb2& q);
NearestResult bruteNearest(const std::vector<Primitive>& prims, Vec2 p);
std::optional<RayResult> bruteRaycast(const std::vector<Primitive>& prims, Vec2 origin, Vec2 dir,
                                      double maxRange);

}  // namespace fleet::geometry
