#pragma once

// What the bridge's files read off a vehicle's state.

#include <algorithm>
#include <cstddef>
#include <string>

#include "fleet/vda5050/state.hpp"

namespace fleet::vdabridge::bridge_detail {

inline const vda5050::ActionState* findAction(const vda5050::State& s, const std::string& id) {
  for (const auto& a : s.actionStates) {
    if (a.actionId == id) {
      return &a;
    }
  }
  return nullptr;
}

/// Base nodes the vehicle still holds ahead of its last node.
inline std::size_t baseAhead(const vda5050::State& s) {
  return static_cast<std::size_t>(std::count_if(s.nodeStates.begin(), s.nodeStates.end(),
                                                [](const vda5050::NodeState& n) { return n.released; }));
}

}  // namespace fleet::vdabridge::bridge_detail
