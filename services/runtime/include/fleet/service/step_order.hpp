// In lockstep a sample made in one step counts from the next one (by its stamp_ns), whatever DDS
// delivered first: a sample of this step that came early waits for the next step. The traffic
// manager orders the robots' progress reports so, the agents the traffic manager's releases, and a
// lockstep run is then the same every time (AgentLockstep.SameSeedAndOrdersGiveByteIdenticalReplays).
#pragma once

#include <cstdint>
#include <iterator>
#include <utility>
#include <vector>

namespace fleet::service {

template <class T>
class StepOrder {
 public:
  explicit StepOrder(bool lockstep) : lockstep_(lockstep) {}

  /// What is due at `nowNs` of `in` and of what waited before, oldest first: samples stamped before
  /// `nowNs` (everything, outside lockstep). The others wait.
  std::vector<T> due(std::vector<T> in, std::int64_t nowNs) {
    if (!lockstep_) {
      return in;
    }
    waiting_.insert(waiting_.end(), std::make_move_iterator(in.begin()), std::make_move_iterator(in.end()));
    std::vector<T> now;
    std::vector<T> later;
    for (auto& m : waiting_) {
      (m.stamp_ns < nowNs ? now : later).push_back(std::move(m));
    }
    waiting_ = std::move(later);
    return now;
  }
  [[nodiscard]] std::size_t waiting() const { return waiting_.size(); }

 private:
  bool lockstep_;
  std::vector<T> waiting_;
};

}  // namespace fleet::service
