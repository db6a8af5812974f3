#include "fleet/service/clocked_loop.hpp"

#include <algorithm>

#include "fleet/service/runtime.hpp"

namespace fleet::service {

using namespace std::chrono_literals;

ClockedLoop::ClockedLoop(transport::Participant& p, transport::WaitSet& ws, ClockedLoopSettings settings)
    : ws_(ws), clockIn_(p), stepDone_(p), settings_(std::move(settings)) {
  settings_.periodNs = std::max<std::int64_t>(1, settings_.periodNs);
  ws_.attach(clockIn_);
  now_ = settings_.simClock ? 0 : wall_.nowNs();
  next_ = now_;
  haveClock_ = !settings_.simClock;
  lastRegister_ = std::chrono::steady_clock::now() - 10s;
}

void ClockedLoop::once(const ClockedLoopHooks& h) {
  if (settings_.lockstep && !haveClock_ && std::chrono::steady_clock::now() - lastRegister_ > 1s) {
    stepDone_.write({settings_.id, msg::StepDone::kRegister});
    lastRegister_ = std::chrono::steady_clock::now();
  }
  const auto wait =
      settings_.simClock
          ? 100ms
          : std::chrono::milliseconds(std::max<std::int64_t>(0, (next_ - wall_.nowNs()) / 1'000'000));
  ws_.wait(wait);
  const std::int64_t period = settings_.periodNs;
  if (settings_.simClock) {
    for (const auto& c : clockIn_.take()) {
      now_ = c.sim_time_ns;
      if (!haveClock_) {
        next_ = now_;
        haveClock_ = true;
      }
      h.ingest();
      if (now_ >= next_) {
        h.tick();
        next_ += period * std::max<std::int64_t>(1, (now_ - next_) / period + 1);
      }
      if (settings_.lockstep && c.lockstep) {
        stepDone_.write({settings_.id, c.step});
      }
    }
    h.ingest();
  } else {
    now_ = wall_.nowNs();
    h.ingest();
    if (now_ >= next_) {
      h.tick();
      next_ = std::max(next_ + period, now_);
    }
  }
  if (h.idle) {
    h.idle();
  }
}

void ClockedLoop::run(const ClockedLoopHooks& hooks) {
  while (!stopRequested()) {
    once(hooks);
  }
  if (settings_.lockstep) {
    stepDone_.write({settings_.id, msg::StepDone::kLeave});
  }
}

}  // namespace fleet::service
