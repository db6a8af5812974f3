#pragma once

// The fleet managers' lease in PostgreSQL, without DDS: any number of managers run against one
// database and the one holding the lease is active. A row of table fleet_lease (name, holder,
// epoch, expires_at) on the database's clock: the holder renews it every renew_s for ttl_s; a
// standby takes it once it expired, raising the epoch by one. The epoch fences the store's writes
// (PostgresTaskStore::fenceWith), so a manager that lost the lease commits nothing more. Why a
// lease row and not an advisory lock: docs/algorithms.md, "Standby fleet manager".

#include <chrono>
#include <cstdint>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/pg_connection.hpp"

namespace fleet::manager {

class ManagerLease {
 public:
  using Clock = std::chrono::steady_clock;
  struct Options {
    std::string url;                     ///< libpq URL of the task database
    std::string name = "fleet_manager";  ///< the lease's row: managers of one fleet share it
    std::string holder;                  ///< this manager, unique per process (defaultHolder())
    double ttlS = 3.0;                   ///< a lease not renewed for this long is free
  };
  /// The share of ttl after the last renewal was sent at which the holder itself considers the
  /// lease lost (held() false), before the database lets another manager take it.
  static constexpr double kSelfFence = 0.8;

  explicit ManagerLease(Options o);

  /// host:pid:random, for Options::holder.
  static std::string defaultHolder();

  /// Takes the lease when it is free or expired (epoch + 1). True when held afterwards. Error
  /// "storage" when the database cannot be reached.
  Expected<bool> tryAcquire(Clock::time_point now = Clock::now());
  /// Extends the held lease by ttl from the database's now. False (lost) when another manager
  /// holds it, or when held() had already lapsed at `now`: a lapsed lease is never renewed, the
  /// manager stands by and acquires again with a new epoch. An error leaves held() to lapse.
  Expected<bool> renew(Clock::time_point now = Clock::now());
  /// Gives the lease up (a clean stop): a standby takes it at its next poll.
  void release();

  /// Held, by the local deadline: sent time of the last successful renewal + kSelfFence × ttl.
  [[nodiscard]] bool held(Clock::time_point now = Clock::now()) const;
  /// The epoch of the lease while held (0 before the first acquisition).
  [[nodiscard]] std::int64_t epoch() const { return epoch_; }
  [[nodiscard]] const Options& options() const { return o_; }

 private:
  Expected<void> ensureTable();

  Options o_;
  pg::Connection conn_;
  bool tableReady_ = false;
  bool held_ = false;
  std::int64_t epoch_ = 0;
  Clock::time_point deadline_{};
};

}  // namespace fleet::manager
