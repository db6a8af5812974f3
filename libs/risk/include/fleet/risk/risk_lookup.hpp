#pragma once

// A fused risk map as a point lookup for planners: the run-length encoded level grid decoded once
// per map and shared read-only by every reader (the agents of a process, their local and global
// planners).

#include <cstdint>
#include <memory>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/risk/rle.hpp"

namespace fleet::risk {

/// The grid of a risk map as it travels: frame, size, number of levels K and its runs.
struct EncodedRiskMap {
  Vec2 origin;
  double resolution = 0.0;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  int levels = 0;
  std::int64_t stampNs = 0;
  std::vector<LevelRun> runs;
};

class RiskLookup {
 public:
  /// Decodes and checks what a remote writer could get wrong (resolution, origin, size at most
  /// 2^26 cells, runs that do not cover the grid exactly or name a level above K); errors name the
  /// field.
  static Expected<std::shared_ptr<const RiskLookup>> decode(const EncodedRiskMap& m);

  /// Collision probability at a map point: the upper bound l/K of the cell's level (level 0 is
  /// p = 0); 0 off the map (no information is no risk: the scan and the safety layer still apply).
  [[nodiscard]] double at(Vec2 p) const;
  [[nodiscard]] std::int64_t stampNs() const { return stamp_; }
  [[nodiscard]] int levels() const { return k_; }

 private:
  Vec2 origin_;
  double res_ = 1.0;
  int w_ = 0;
  int h_ = 0;
  int k_ = 1;
  std::int64_t stamp_ = 0;
  std::vector<std::uint8_t> level_;
};

}  // namespace fleet::risk
