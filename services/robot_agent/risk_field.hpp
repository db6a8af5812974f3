#pragma once

// The latest RiskMap as a lookup for the local and global planners: the run-length encoded level
// grid decoded once per map, shared read-only by every agent of the process.

#include <cstdint>
#include <memory>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/core/vec2.hpp"
#include "fleet/transport/messages.hpp"

namespace fleet::agent {

class RiskField {
 public:
  /// Checks what a remote writer could get wrong (sizes, resolution, runs); errors name the field.
  static Expected<std::shared_ptr<const RiskField>> fromMessage(const msg::RiskMap& m);

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

}  // namespace fleet::agent
