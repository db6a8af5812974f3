#pragma once

// What a manager waits for before it works: its task store, opened with retries, and (standing by)
// the lease.

#include <spdlog/spdlog.h>

#include <chrono>
#include <deque>
#include <iterator>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "fleet/fleet/task_store.hpp"
#include "fleet/service/service_ops.hpp"
#include "fleet_manager_node.hpp"
#include "manager_lease.hpp"

namespace fleet::manager {

/// Sleeps `d` in short steps; false when a stop was requested meanwhile.
bool pause(std::chrono::milliseconds d, service::ServiceOps& ops);

/// The task store, opened with retries: an unreachable PostgreSQL is waited for with back-off
/// (1 s doubling to 10 s; /readyz says task_store not ready). Null when the store cannot be used
/// (exit 2: a SQLite file that cannot be opened, a schema newer than the binary) or a stop was
/// requested (`stopped`).
std::unique_ptr<TaskStore> openStore(const manager::Settings& settings, service::ServiceOps& ops,
                                     bool& stopped);

/// Samples a standby takes off the wire while it waits: its readers' caches must not grow, and the
/// requests and reports of the last `window` are handed to the manager once it is active (the
/// takeover gap loses none; requests are idempotent, a report already applied is refused as stale).
template <class T>
class Recent {
 public:
  explicit Recent(std::chrono::steady_clock::duration window) : window_(window) {}
  void add(std::vector<T> samples) {
    const auto now = std::chrono::steady_clock::now();
    for (auto& s : samples) {
      held_.emplace_back(now, std::move(s));
    }
    while (!held_.empty() && now - held_.front().first > window_) {
      held_.pop_front();
    }
  }
  /// The held samples, oldest first, followed by `fresh`; nothing is held afterwards.
  std::vector<T> with(std::vector<T> fresh) {
    if (held_.empty()) {
      return fresh;
    }
    std::vector<T> out;
    out.reserve(held_.size() + fresh.size());
    for (auto& [at, s] : held_) {
      out.push_back(std::move(s));
    }
    held_.clear();
    std::move(fresh.begin(), fresh.end(), std::back_inserter(out));
    return out;
  }

 private:
  std::chrono::steady_clock::duration window_;
  std::deque<std::pair<std::chrono::steady_clock::time_point, T>> held_;
};

/// Stands by until this manager holds the lease, calling `drain` on every poll; false when a stop
/// was requested.
template <class Drain>
bool awaitLease(manager::ManagerLease& lease, const manager::Settings& settings, service::ServiceOps& ops,
                Drain&& drain) {
  const auto poll = std::chrono::milliseconds(static_cast<int>(settings.store.leaseRenewS * 500));
  bool said = false;
  std::string lastError;
  for (;;) {
    auto got = lease.tryAcquire();
    if (got && *got) {
      return true;
    }
    if (!got && got.error().message != lastError) {
      lastError = got.error().message;
      spdlog::warn("fleet manager: cannot reach the lease: {}", lastError);
    } else if (got && !said) {
      said = true;
      spdlog::info("fleet manager: standing by: lease '{}' held by another manager", lease.options().name);
    }
    drain();
    if (!pause(poll, ops)) {
      return false;
    }
  }
}

}  // namespace fleet::manager
