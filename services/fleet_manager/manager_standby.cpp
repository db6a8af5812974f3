#include "manager_standby.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/pg_connection.hpp"
#include "fleet/service/runtime.hpp"

namespace fleet::manager {

using namespace std::chrono_literals;

bool pause(std::chrono::milliseconds d, service::ServiceOps& ops) {
  const auto until = std::chrono::steady_clock::now() + d;
  while (std::chrono::steady_clock::now() < until) {
    if (service::stopRequested()) {
      return false;
    }
    ops.refresh();
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(
        100ms, std::max<std::chrono::steady_clock::duration>(until - std::chrono::steady_clock::now(), 0ms)));
  }
  return !service::stopRequested();
}
std::unique_ptr<TaskStore> openStore(const manager::Settings& settings, service::ServiceOps& ops,
                                     bool& stopped) {
  const bool pgStore = settings.store.backend == manager::StoreSettings::Backend::Postgres;
  const std::string where = pgStore ? pg::redacted(settings.store.url) : settings.db;
  auto backoff = 1000ms;
  for (;;) {
    auto s = manager::openTaskStore(settings);
    if (s) {
      return std::move(*s);
    }
    if (!pgStore || s.error().code != errc::kStorage) {
      spdlog::critical("fleet manager: cannot open task store {}: {}", where, s.error().message);
      return nullptr;
    }
    ops.health().setReady("task_store", false);
    spdlog::warn("fleet manager: task store {} unreachable, not ready, retrying in {} s: {}", where,
                 backoff.count() / 1000.0, s.error().message);
    if (!pause(backoff, ops)) {
      stopped = true;
      return nullptr;
    }
    backoff = std::min(backoff * 2, std::chrono::milliseconds(10000));
  }
}
}  // namespace fleet::manager
