#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace fleet::sim {

/// Bookkeeping of the lockstep protocol (no I/O): who is registered and who acknowledged which step.
/// StepDone(step = -1) registers, (-2) leaves, (k >= 0) acknowledges step k.
class LockstepBarrier {
 public:
  static constexpr std::int64_t kRegister = -1;
  static constexpr std::int64_t kLeave = -2;

  /// Step k is about to be published. Participants registering from now on are waited for from step
  /// k + 1 on: they may have missed Clock(k).
  void begin(std::int64_t step) { current_ = step; }
  /// Applies one StepDone; returns false for ids never registered acknowledging a step (ignored).
  bool onStepDone(const std::string& participant, std::int64_t step);
  /// Everyone registered has acknowledged `step` (or a later one).
  [[nodiscard]] bool complete(std::int64_t step) const;
  /// Registered participants that have not yet acknowledged `step`.
  [[nodiscard]] std::vector<std::string> missing(std::int64_t step) const;
  [[nodiscard]] std::size_t registered() const { return acked_.size(); }

 private:
  std::map<std::string, std::int64_t> acked_;  // last acknowledged step, -1 = none yet
  std::int64_t current_ = -1;
};

}  // namespace fleet::sim
