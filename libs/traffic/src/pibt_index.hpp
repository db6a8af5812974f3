#pragma once

#include <cstddef>
#include <cstdint>

namespace fleet::traffic::pibt_detail {

/// Agents and nodes are both 32-bit indices into Pibt's vectors.
inline std::size_t idx(std::int32_t i) {
  return static_cast<std::size_t>(i);
}

}  // namespace fleet::traffic::pibt_detail
