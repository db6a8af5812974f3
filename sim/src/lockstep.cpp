#include "fleet/sim/lockstep.hpp"

#include <algorithm>

namespace fleet::sim {

bool LockstepBarrier::onStepDone(const std::string& participant, std::int64_t step) {
  if (step == kRegister) {
    acked_.try_emplace(participant, current_);
    return true;
  }
  if (step == kLeave) {
    acked_.erase(participant);
    return true;
  }
  auto it = acked_.find(participant);
  if (it == acked_.end() || step < 0) {
    return false;
  }
  it->second = std::max(it->second, step);
  return true;
}

bool LockstepBarrier::complete(std::int64_t step) const {
  return std::all_of(acked_.begin(), acked_.end(), [&](const auto& kv) { return kv.second >= step; });
}

std::vector<std::string> LockstepBarrier::missing(std::int64_t step) const {
  std::vector<std::string> out;
  for (const auto& [id, s] : acked_) {
    if (s < step) {
      out.push_back(id);
    }
  }
  return out;
}

}  // namespace fleet::sim
