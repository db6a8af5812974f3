#pragma once

// The main loop of a service that acts at a fixed rate (the risk map's fusion, the traffic
// manager's planning tick), on the wall clock or on the simulator's Clock topic (clock "sim"), and
// as a lockstep participant: it registers with StepDone until the first Clock sample arrives,
// acknowledges each simulated step once it has acted on it, and leaves when it stops. One copy of
// the loop for every such service, so that they keep time the same way.

#include <chrono>
#include <cstdint>
#include <functional>
#include <string>

#include "fleet/core/clock.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/transport/dds.hpp"

namespace fleet::service {

struct ClockedLoopSettings {
  bool simClock = false;  ///< time from the Clock topic (else the wall clock)
  bool lockstep = false;  ///< a lockstep participant (with simClock)
  std::string id;         ///< its participant id in lockstep
  std::int64_t periodNs = 100'000'000;
};

/// What the loop calls, each on the loop's thread.
struct ClockedLoopHooks {
  std::function<void()> ingest;  ///< take what arrived (after every wake-up and every Clock sample)
  std::function<void()> tick;    ///< act once per period, at now()
  std::function<void()> idle;    ///< after every wake-up: metrics, periodic logs (optional)
};

class ClockedLoop {
 public:
  /// Attaches its Clock reader to `ws`; the service attaches its own readers.
  ClockedLoop(transport::Participant& p, transport::WaitSet& ws, ClockedLoopSettings settings);

  /// The time the service acts at: the latest Clock sample's simulated time, or the wall clock.
  [[nodiscard]] std::int64_t now() const { return now_; }
  /// false until the first Clock sample (sim clock): nothing that arrives before it is acted on.
  [[nodiscard]] bool haveClock() const { return haveClock_; }

  /// Runs until a stop is requested (service::stopRequested); sends StepDone kLeave on the way out
  /// in lockstep.
  void run(const ClockedLoopHooks& hooks);
  /// One wake-up of run(): waits for data, a Clock sample or the next period, then calls the hooks.
  void once(const ClockedLoopHooks& hooks);

 private:
  transport::WaitSet& ws_;
  transport::Reader<msg::Clock> clockIn_;
  transport::Writer<msg::StepDone> stepDone_;
  ClockedLoopSettings settings_;
  WallClock wall_;
  std::int64_t now_ = 0;
  std::int64_t next_ = 0;
  bool haveClock_ = false;
  std::chrono::steady_clock::time_point lastRegister_;
};

}  // namespace fleet::service
