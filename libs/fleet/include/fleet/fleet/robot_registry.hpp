#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/pose2.hpp"

namespace fleet {

/// What the fleet manager knows about one robot (from its `RobotState` samples).
struct RobotInfo {
  std::string id;
  Pose2 pose;
  double battery = 1.0;         ///< state of charge in [0, 1]
  std::int64_t lastSeenNs = 0;  ///< stamp of the newest state received
  bool lost = false;            ///< lease expired (or liveliness lost) and no state since
  bool fault = false;           ///< its newest state says it is in fault mode
  std::string taskId;           ///< task the manager assigned it; empty when idle

  /// Can take a task: alive, not in fault mode (it would fail the task at once) and free.
  [[nodiscard]] bool idle() const { return !lost && !fault && taskId.empty(); }
};

/// `{"id", "x", "y", "theta", "battery", "last_seen_ns", "lost", "fault", "task"}` for `GET /v1/robots`.
nlohmann::json toJson(const RobotInfo& r);

/// One `RobotState` sample, reduced to what allocation needs.
struct RobotObservation {
  std::string id;
  Pose2 pose;
  double battery = 1.0;
  std::int64_t stampNs = 0;
  bool fault = false;
};

/// Lease after which a silent robot is lost: `missed` state periods at `rateHz`.
std::int64_t leaseFromRate(double rateHz, double missed);

/// Robots by id with liveness. Not thread-safe: the owner (the dispatcher) serialises access.
class RobotRegistry {
 public:
  explicit RobotRegistry(std::int64_t leaseNs) : leaseNs_(leaseNs) {}

  enum class Update { New, Updated, Recovered, Stale };
  /// Records a state. A sample older than the newest one is ignored (Stale); a lost robot that
  /// speaks again is Recovered (idle: its task was requeued when it was lost).
  Update observe(const RobotObservation& o);
  /// Marks robots silent for longer than the lease as lost and returns them (only those newly
  /// lost, each once), sorted by id. Their task ids are kept so the caller can requeue them.
  std::vector<RobotInfo> expire(std::int64_t nowNs);
  /// DDS liveliness lost: lost now, whatever the lease says. False when unknown or already lost.
  bool markLost(std::string_view id);
  /// Known robot whose states are expected from `nowNs` on (used when recovering assignments
  /// after a restart, so the lease starts at the restart).
  void expect(std::string_view id, std::int64_t nowNs);

  bool setTask(std::string_view id, std::string taskId);
  bool clearTask(std::string_view id);

  [[nodiscard]] const RobotInfo* find(std::string_view id) const;
  /// Robots that are alive and hold no task, sorted by id.
  [[nodiscard]] std::vector<RobotInfo> idleRobots() const;
  [[nodiscard]] std::vector<RobotInfo> all() const;
  [[nodiscard]] std::size_t size() const { return robots_.size(); }
  [[nodiscard]] std::size_t onlineCount() const;
  [[nodiscard]] std::int64_t leaseNs() const { return leaseNs_; }

 private:
  std::int64_t leaseNs_;
  std::map<std::string, RobotInfo, std::less<>> robots_;
};

}  // namespace fleet
