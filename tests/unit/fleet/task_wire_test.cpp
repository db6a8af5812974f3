// The task on the wire between the WMS adapter and the fleet manager.

#include "fleet/fleet/task_wire.hpp"

#include <gtest/gtest.h>

namespace fleet {
namespace {

// The adapter's toWire and the manager's fromWire are one pair: every field survives, exactly
// (durations in integer nanoseconds), and a missing created time is the receiver's clock.
TEST(TaskWire, EveryFieldSurvivesTheRoundTrip) {
  Task t;
  t.id = "order-17";
  t.kind = TaskKind::Transport;
  t.pickup = "P-1";
  t.dropoff = "D-2";
  t.robot = "r3";
  t.loadNs = 1'234'567'891;  // not a whole number of seconds: a double of seconds would lose it
  t.unloadNs = 7;
  t.priority = -5;
  t.deadlineNs = 9'000'000'000;
  t.createdNs = 42;
  const auto m = toWire(t, "req-1", 1000);
  EXPECT_EQ(m.request_id, "req-1");
  EXPECT_EQ(fromWire(m, 2000), t);
  for (const auto kind : {TaskKind::Goto, TaskKind::Charge, TaskKind::Park}) {
    Task k;
    k.id = "k";
    k.kind = kind;
    k.station = "C-1";
    k.createdNs = 5;
    EXPECT_EQ(fromWire(toWire(k, "r", 0), 0), k);
  }
  t.createdNs = 0;
  EXPECT_EQ(toWire(t, "req-2", 1000).created_ns, 1000);
  auto noStamp = toWire(t, "req-3", 0);
  EXPECT_EQ(fromWire(noStamp, 3000).createdNs, 3000);
}

}  // namespace
}  // namespace fleet
