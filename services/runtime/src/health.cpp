#include "fleet/service/health.hpp"

namespace fleet::service {
namespace {
std::int64_t steadyNs() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(
             std::chrono::steady_clock::now().time_since_epoch())
      .count();
}
}  // namespace

Health::Health(std::chrono::milliseconds stallAfter) : stallAfter_(stallAfter), lastBeatNs_(steadyNs()) {}

void Health::beat() {
  lastBeatNs_.store(steadyNs(), std::memory_order_relaxed);
}

void Health::setReady(const std::string& condition, bool ok) {
  std::lock_guard lock(m_);
  conditions_[condition] = ok;
}

ProbeAnswer Health::liveness() const {
  const auto idleNs = steadyNs() - lastBeatNs_.load(std::memory_order_relaxed);
  const auto limitNs = std::chrono::duration_cast<std::chrono::nanoseconds>(stallAfter_).count();
  if (idleNs > limitNs) {
    return {false, "main loop has not turned for " + std::to_string(idleNs / 1'000'000) + " ms\n"};
  }
  return {true, "ok\n"};
}

ProbeAnswer Health::readiness() const {
  ProbeAnswer a = liveness();
  if (!a.ok) {
    return a;
  }
  std::string failed;
  {
    std::lock_guard lock(m_);
    for (const auto& [name, ok] : conditions_) {
      if (!ok) {
        failed += "not ready: " + name + "\n";
      }
    }
  }
  return failed.empty() ? ProbeAnswer{true, "ok\n"} : ProbeAnswer{false, failed};
}

}  // namespace fleet::service
