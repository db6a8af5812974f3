#pragma once

#include <atomic>
#include <chrono>
#include <cstdint>

namespace fleet {

inline constexpr std::int64_t kNsPerSec = 1'000'000'000;

inline constexpr double nsToSec(std::int64_t ns) {
  return static_cast<double>(ns) * 1e-9;
}
inline constexpr std::int64_t secToNs(double s) {
  return static_cast<std::int64_t>(s * 1e9);
}

/// Source of `stamp_ns`: the system clock in `wall` mode, the simulator's time in `lockstep`.
class Clock {
 public:
  virtual ~Clock() = default;
  [[nodiscard]] virtual std::int64_t nowNs() const = 0;
  [[nodiscard]] double nowSec() const { return nsToSec(nowNs()); }
};

class WallClock final : public Clock {
 public:
  [[nodiscard]] std::int64_t nowNs() const override {
    return std::chrono::duration_cast<std::chrono::nanoseconds>(
               std::chrono::system_clock::now().time_since_epoch())
        .count();
  }
};

/// Time set from outside (the simulator's `Clock` topic). Thread-safe; never goes backwards.
class SimClock final : public Clock {
 public:
  explicit SimClock(std::int64_t startNs = 0) : now_(startNs) {}
  [[nodiscard]] std::int64_t nowNs() const override { return now_.load(std::memory_order_acquire); }
  /// Returns false (and keeps the old time) when `ns` is earlier than the current time.
  bool set(std::int64_t ns) {
    std::int64_t cur = now_.load(std::memory_order_acquire);
    while (ns >= cur) {
      if (now_.compare_exchange_weak(cur, ns, std::memory_order_acq_rel)) {
        return true;
      }
    }
    return false;
  }
  void advance(std::int64_t dtNs) { now_.fetch_add(dtNs, std::memory_order_acq_rel); }

 private:
  std::atomic<std::int64_t> now_;
};

}  // namespace fleet
