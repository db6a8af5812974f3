#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <utility>
#include <vector>

namespace fleet::sim {

/// Bookkeeping of the lockstep protocol (no I/O): who is registered, who acknowledged which step,
/// and whether the commands they say they wrote for it have arrived.
/// StepDone(step = -1) registers, (-2) leaves, (k >= 0) acknowledges step k.
///
/// DDS orders samples per writer only, and a robot's commands travel through its own writer (in
/// its partition), not the participant's StepDone writer: a StepDone can arrive before the commands
/// written ahead of it. So StepDone(k) names, for each robot it commanded, the seq of the last
/// command written, and step k is complete only once those commands are in.
class LockstepBarrier {
 public:
  static constexpr std::int64_t kRegister = -1;
  static constexpr std::int64_t kLeave = -2;
  /// Robot id and the seq of the last command a StepDone covers for it.
  using Marks = std::vector<std::pair<std::string, std::uint32_t>>;

  /// Step k is about to be published. Participants registering from now on are waited for from step
  /// k + 1 on: they may have missed Clock(k).
  void begin(std::int64_t step) { current_ = step; }
  /// Applies one StepDone; returns false for ids never registered acknowledging a step (ignored).
  /// The marks of the newest step a participant acknowledged replace its earlier ones.
  bool onStepDone(const std::string& participant, std::int64_t step, Marks marks = {});
  /// A VelocityCommand for `robot` with `seq` arrived (the newest one of that robot so far).
  void onCommand(const std::string& robot, std::uint32_t seq) { lastSeq_[robot] = seq; }
  /// Everyone registered has acknowledged `step` (or a later one), and every command their
  /// newest acknowledgements name has arrived.
  [[nodiscard]] bool complete(std::int64_t step) const;
  /// What `step` still waits for: participants that have not acknowledged it, and
  /// "<participant> (command <seq> of <robot>)" for each named command not yet in.
  [[nodiscard]] std::vector<std::string> missing(std::int64_t step) const;
  [[nodiscard]] std::size_t registered() const { return acked_.size(); }

 private:
  struct Participant {
    std::int64_t acked = -1;  // last acknowledged step, -1 = none yet
    Marks marks;              // of that step
  };
  [[nodiscard]] bool arrived(const std::pair<std::string, std::uint32_t>& mark) const;

  std::map<std::string, Participant> acked_;
  std::map<std::string, std::uint32_t> lastSeq_;  // robot -> seq of its newest command received
  std::int64_t current_ = -1;
};

}  // namespace fleet::sim
