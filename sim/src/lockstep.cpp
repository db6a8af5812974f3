#include "fleet/sim/lockstep.hpp"

#include <algorithm>

namespace fleet::sim {

bool LockstepBarrier::onStepDone(const std::string& participant, std::int64_t step, Marks marks) {
  if (step == kRegister) {
    acked_.try_emplace(participant, Participant{current_, {}});
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
  if (step >= it->second.acked) {
    it->second.acked = step;
    it->second.marks = std::move(marks);
  }
  return true;
}

bool LockstepBarrier::arrived(const std::pair<std::string, std::uint32_t>& mark) const {
  // Equal, not at least: seqs restart with a restarted agent, and a robot's commands come from one
  // writer, in order, so its newest seq is the mark once the marked command is in.
  const auto it = lastSeq_.find(mark.first);
  return it != lastSeq_.end() && it->second == mark.second;
}

bool LockstepBarrier::complete(std::int64_t step) const {
  return std::all_of(acked_.begin(), acked_.end(), [&](const auto& kv) {
    const Participant& p = kv.second;
    return p.acked >= step &&
           std::all_of(p.marks.begin(), p.marks.end(), [&](const auto& m) { return arrived(m); });
  });
}

std::vector<std::string> LockstepBarrier::missing(std::int64_t step) const {
  std::vector<std::string> out;
  for (const auto& [id, p] : acked_) {
    if (p.acked < step) {
      out.push_back(id);
      continue;
    }
    for (const auto& m : p.marks) {
      if (!arrived(m)) {
        out.push_back(id + " (command " + std::to_string(m.second) + " of " + m.first + ")");
      }
    }
  }
  return out;
}

}  // namespace fleet::sim
