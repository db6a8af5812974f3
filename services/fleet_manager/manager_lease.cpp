#include "manager_lease.hpp"

#include <unistd.h>

#include <random>

namespace fleet::manager {
namespace {

ManagerLease::Clock::duration seconds(double s) {
  return std::chrono::duration_cast<ManagerLease::Clock::duration>(std::chrono::duration<double>(s));
}

}  // namespace

ManagerLease::ManagerLease(Options o) : o_(std::move(o)), conn_(o_.url) {
  if (o_.holder.empty()) {
    o_.holder = defaultHolder();
  }
}

std::string ManagerLease::defaultHolder() {
  char host[256] = {};
  ::gethostname(host, sizeof host - 1);
  std::random_device rd;
  return std::string(host) + ":" + std::to_string(::getpid()) + ":" + std::to_string(rd() % 1000000);
}

Expected<void> ManagerLease::ensureTable() {
  if (tableReady_) {
    return {};
  }
  // The same table the PostgreSQL task store creates; here too, so the lease works on a database
  // no store opened yet. Under the store's schema lock: two managers start at once.
  auto r = conn_.exec("create fleet_lease",
                      "BEGIN; SELECT pg_advisory_xact_lock(7379531807330298728); "
                      "CREATE TABLE IF NOT EXISTS fleet_lease(name TEXT PRIMARY KEY, holder TEXT NOT NULL "
                      "DEFAULT '', epoch BIGINT NOT NULL DEFAULT 0, expires_at TIMESTAMPTZ NOT NULL DEFAULT "
                      "'-infinity'); COMMIT");
  if (!r) {
    conn_.close();  // whatever the transaction's state, a new session next time
    return unexpected(r.error());
  }
  tableReady_ = true;
  return {};
}

Expected<bool> ManagerLease::tryAcquire(Clock::time_point now) {
  if (held(now)) {
    return true;
  }
  held_ = false;
  if (auto ok = ensureTable(); !ok) {
    return unexpected(ok.error());
  }
  // One statement: a new row, or the expired one taken over with the next epoch.
  auto r = conn_.exec("acquire the lease",
                      "INSERT INTO fleet_lease AS l(name, holder, epoch, expires_at) "
                      "VALUES ($1, $2, 1, clock_timestamp() + make_interval(secs => $3::float8)) "
                      "ON CONFLICT (name) DO UPDATE SET holder = EXCLUDED.holder, epoch = l.epoch + 1, "
                      "expires_at = EXCLUDED.expires_at WHERE l.expires_at < clock_timestamp() "
                      "RETURNING epoch",
                      {o_.name, o_.holder, std::to_string(o_.ttlS)});
  if (!r) {
    tableReady_ = conn_.connected() && tableReady_;
    return unexpected(r.error());
  }
  if (r->rows() == 0) {
    return false;
  }
  epoch_ = r->integer(0, 0);
  held_ = true;
  deadline_ = now + seconds(o_.ttlS * kSelfFence);
  return true;
}

Expected<bool> ManagerLease::renew(Clock::time_point now) {
  if (!held(now)) {
    held_ = false;
    return false;
  }
  auto r =
      conn_.exec("renew the lease",
                 "UPDATE fleet_lease SET expires_at = clock_timestamp() + make_interval(secs => $3::float8) "
                 "WHERE name = $1 AND holder = $2 AND epoch = $4 RETURNING epoch",
                 {o_.name, o_.holder, std::to_string(o_.ttlS), std::to_string(epoch_)});
  if (!r) {
    return unexpected(r.error());
  }
  if (r->rows() == 0) {
    held_ = false;
    return false;
  }
  deadline_ = now + seconds(o_.ttlS * kSelfFence);
  return true;
}

void ManagerLease::release() {
  if (held_) {
    (void)conn_.exec(
        "release the lease",
        "UPDATE fleet_lease SET expires_at = '-infinity' WHERE name = $1 AND holder = $2 AND epoch = $3",
        {o_.name, o_.holder, std::to_string(epoch_)});
  }
  held_ = false;
}

bool ManagerLease::held(Clock::time_point now) const {
  return held_ && now < deadline_;
}

}  // namespace fleet::manager
