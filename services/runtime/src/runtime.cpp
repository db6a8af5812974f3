#include "fleet/service/runtime.hpp"

#include <spdlog/spdlog.h>

#include <csignal>

namespace fleet::service {
namespace {
std::atomic<bool> gStop{false};
extern "C" void onSignal(int /*sig*/) {
  gStop.store(true);
}
}  // namespace

void installStopHandlers() {
  struct sigaction sa {};
  sa.sa_handler = onSignal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  signal(SIGPIPE, SIG_IGN);  // a closed HTTP client must not kill a service
}

bool stopRequested() {
  return gStop.load();
}
void requestStop() {
  gStop.store(true);
}

void RateLimitedLog::warn(const std::string& key, const std::string& message) {
  if (onEach_) {
    onEach_(key);
  }
  std::lock_guard lock(m_);
  auto& e = entries_[key];
  ++e.count;
  const auto now = std::chrono::steady_clock::now();
  if (e.count == 1 || now - e.last >= interval_) {
    if (e.suppressed > 0) {
      spdlog::warn("{} (and {} more like it since the last report)", message, e.suppressed);
    } else {
      spdlog::warn("{}", message);
    }
    e.last = now;
    e.suppressed = 0;
  } else {
    ++e.suppressed;
  }
}

std::uint64_t RateLimitedLog::count(const std::string& key) const {
  std::lock_guard lock(m_);
  auto it = entries_.find(key);
  return it == entries_.end() ? 0 : it->second.count;
}

std::uint64_t RateLimitedLog::total() const {
  std::lock_guard lock(m_);
  std::uint64_t n = 0;
  for (const auto& [k, e] : entries_) {
    n += e.count;
  }
  return n;
}

}  // namespace fleet::service
