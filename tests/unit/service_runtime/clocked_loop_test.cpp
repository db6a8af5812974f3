#include "fleet/service/clocked_loop.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <thread>
#include <vector>

#include "test_process.hpp"

using namespace fleet;
using namespace std::chrono_literals;

namespace {

/// A lockstep participant on the simulator's clock: it registers until the first Clock sample,
/// acts once per period of simulated time (not per step), acknowledges every step after acting on
/// it, and sees nothing before the first sample.
TEST(ClockedLoop, InLockstepActsOncePerPeriodAndAcknowledgesEveryStep) {
  setenv("FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain()).c_str(), 1);
  transport::Participant p;
  transport::Writer<msg::Clock> clock(p);
  transport::Reader<msg::StepDone> done(p);
  transport::WaitSet ws(p);
  service::ClockedLoop loop(p, ws, {true, true, "svc", 300'000'000});  // acts every 0.3 s
  EXPECT_FALSE(loop.haveClock());
  std::vector<std::int64_t> ticks;
  int ingests = 0;
  const service::ClockedLoopHooks hooks{[&] { ++ingests; }, [&] { ticks.push_back(loop.now()); }, {}};

  std::vector<msg::StepDone> acks;
  const auto drain = [&] {
    for (auto& d : done.take())
      acks.push_back(d);
  };
  // Before any Clock sample: it registers (StepDone kRegister, again every second) and acts on
  // nothing.
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (acks.empty() && std::chrono::steady_clock::now() < end) {
    loop.once(hooks);
    drain();
  }
  EXPECT_TRUE(ticks.empty());
  ASSERT_FALSE(acks.empty());
  EXPECT_EQ(acks.front().participant_id, "svc");
  EXPECT_EQ(acks.front().step, msg::StepDone::kRegister);
  acks.clear();

  // Ten steps of 0.1 s: it acts at 0, 0.3, 0.6 and 0.9 s and acknowledges each step.
  while (clock.matchedReaders() == 0 && std::chrono::steady_clock::now() < end)
    std::this_thread::sleep_for(5ms);
  for (std::int64_t step = 0; step < 10; ++step) {
    clock.write({step, step * 100'000'000, 100'000'000, true});
    while ((!loop.haveClock() || loop.now() != step * 100'000'000) && std::chrono::steady_clock::now() < end)
      loop.once(hooks);
    drain();
  }
  EXPECT_TRUE(loop.haveClock());
  EXPECT_EQ(ticks, (std::vector<std::int64_t>{0, 300'000'000, 600'000'000, 900'000'000}));
  EXPECT_GT(ingests, 10);
  std::vector<std::int64_t> steps;
  while (std::chrono::steady_clock::now() < end) {
    drain();
    steps.clear();
    for (const auto& d : acks) {
      if (d.step >= 0)
        steps.push_back(d.step);
    }
    if (steps.size() >= 10)
      break;
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(steps, (std::vector<std::int64_t>{0, 1, 2, 3, 4, 5, 6, 7, 8, 9}));
}

/// On the wall clock it has the time from the start and acts at once.
TEST(ClockedLoop, OnTheWallClockActsAtOnce) {
  setenv("FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain()).c_str(), 1);
  transport::Participant p;
  transport::WaitSet ws(p);
  service::ClockedLoop loop(p, ws, {false, false, "svc", 1'000'000'000});
  EXPECT_TRUE(loop.haveClock());
  EXPECT_GT(loop.now(), 0);
  int ticks = 0;
  const service::ClockedLoopHooks hooks{[] {}, [&] { ++ticks; }, {}};
  loop.once(hooks);
  EXPECT_EQ(ticks, 1);
}

}  // namespace
