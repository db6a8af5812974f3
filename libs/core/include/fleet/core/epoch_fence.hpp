#pragma once

// Fencing of a standby fleet manager's output on the wire. The active manager stamps the epoch of
// its lease (PostgreSQL; 0 without one) on every TaskAssignment and TaskEvent it publishes; a
// reader keeps the newest epoch it has seen and drops what comes from an older one, so a manager
// that lost its lease but still runs (stopped, cut off from the database) cannot move a robot or a
// task's view once its successor has spoken. Pure: no DDS, no logging.

#include <cstdint>

namespace fleet {

class EpochFence {
 public:
  /// True when a message of `epoch` is current (not older than the newest seen), which it then
  /// makes the newest; false (and counted) when it is older.
  bool admit(std::int64_t epoch) {
    if (epoch < newest_) {
      ++dropped_;
      return false;
    }
    newest_ = epoch;
    return true;
  }
  [[nodiscard]] std::int64_t newest() const { return newest_; }
  /// Messages dropped as older than the newest epoch seen.
  [[nodiscard]] std::int64_t dropped() const { return dropped_; }

 private:
  std::int64_t newest_ = 0;
  std::int64_t dropped_ = 0;
};

}  // namespace fleet
