// The load test's fault stage alone: each fault's steps at their time, through a recorder.
#include "fault_injector.hpp"

#include <gtest/gtest.h>
#include <signal.h>

namespace fleet::ctl {
namespace {

using nlohmann::json;
using Clock = FaultInjector::Clock;

struct Recorder : FaultActions {
  std::vector<std::string> steps;
  std::string active = "fleet_manager_2";
  void signal(const std::string& p, int sig) override {
    steps.push_back((sig == SIGSTOP ? "STOP " : sig == SIGCONT ? "CONT " : "SIG ") + p);
  }
  void kill(const std::string& p) override { steps.push_back("KILL " + p); }
  void restart(const std::string& p) override { steps.push_back("RESTART " + p); }
  std::string killActiveManager() override {
    steps.push_back("KILL-ACTIVE " + active);
    return active;
  }
  std::string putClosure(const std::string& path, const json& body) override {
    steps.push_back("PUT " + path + " " + body["area"].dump());
    return "201";
  }
  std::string deleteClosure(const std::string& path) override {
    steps.push_back("DELETE " + path);
    return "204";
  }
};

std::vector<Fault> plan(const std::vector<std::string>& specs) {
  auto f = parseFaults(specs);
  EXPECT_TRUE(f) << (f ? "" : f.error().message);
  return f ? *f : std::vector<Fault>{};
}

TEST(FaultInjector, KillsAtTheirSimulatedTimeAndRestartsAfterTheirWallDownTime) {
  Recorder r;
  std::vector<std::string> said;
  FaultInjector inj(plan({"kill-agent@10+2:1", "kill-traffic@20+1"}), {}, false, r,
                    [&](const std::string& s) { said.push_back(s); });
  const auto t0 = Clock::now();
  inj.apply(9.9, t0);
  EXPECT_TRUE(r.steps.empty());
  inj.apply(10.0, t0);
  EXPECT_EQ(r.steps, (std::vector<std::string>{"KILL agent-1"}));
  inj.apply(30.0, t0 + std::chrono::milliseconds(1900));  // kill-traffic starts; agent-1 not yet back
  EXPECT_EQ(r.steps, (std::vector<std::string>{"KILL agent-1", "KILL traffic_manager"}));
  inj.apply(31.0, t0 + std::chrono::milliseconds(2100));
  EXPECT_EQ(r.steps.back(), "RESTART agent-1");
  inj.apply(32.0, t0 + std::chrono::seconds(10));
  EXPECT_EQ(r.steps.back(), "RESTART traffic_manager");
  EXPECT_EQ(inj.log().size(), 4u);
  EXPECT_EQ(inj.log()[0]["sim_s"], 10.0);
  EXPECT_EQ(inj.log()[0]["event"], "SIGKILL agent-1");
  EXPECT_EQ(said.front(), "fault: SIGKILL agent-1");
  EXPECT_EQ(inj.endAll(40.0), 0);  // nothing in progress
}

TEST(FaultInjector, AStallStopsTheRobotsProcessAndTheEndOfTheRunResumesIt) {
  Recorder r;
  FaultInjector inj(plan({"stall:r3@5+60"}), {{"r3", "agent-r3"}}, false, r, [](const std::string&) {});
  inj.apply(5.0, Clock::now());
  EXPECT_EQ(r.steps, (std::vector<std::string>{"STOP agent-r3"}));
  EXPECT_EQ(inj.log()[0]["event"], "SIGSTOP agent-r3 (robot r3)");
  EXPECT_EQ(inj.endAll(6.0), 0);
  EXPECT_EQ(r.steps.back(), "CONT agent-r3");
  EXPECT_EQ(inj.log().back()["event"], "SIGCONT agent-r3 (end of run)");
}

TEST(FaultInjector, WithStandbyManagersTheActiveOneIsKilledAndComesBackAtTheEnd) {
  Recorder r;
  FaultInjector inj(plan({"kill-manager@1+100"}), {}, true, r, [](const std::string&) {});
  inj.apply(1.0, Clock::now());
  EXPECT_EQ(r.steps, (std::vector<std::string>{"KILL-ACTIVE fleet_manager_2"}));
  EXPECT_EQ(inj.log()[0]["event"], "SIGKILL fleet_manager_2 (active)");
  EXPECT_EQ(inj.endAll(2.0), 1);
  EXPECT_EQ(r.steps.back(), "RESTART fleet_manager_2");
  // With none active nothing is killed, and nothing comes back.
  Recorder none;
  none.active = "";
  FaultInjector idle(plan({"kill-manager@1+100"}), {}, true, none, [](const std::string&) {});
  idle.apply(1.0, Clock::now());
  EXPECT_EQ(idle.log()[0]["event"], "no active fleet manager to kill");
  EXPECT_EQ(idle.endAll(2.0), 0);
  EXPECT_EQ(none.steps.size(), 1u);
}

TEST(FaultInjector, AnAreaClosesAndReopensOnTheSimulatedClockThroughTheApi) {
  Recorder r;
  FaultInjector inj(plan({"close@10+5:0,0,4,0,4,3", "hide-landmarks@12+2"}), {}, false, r,
                    [](const std::string&) {});
  const auto t = Clock::now();
  inj.apply(10.0, t);
  EXPECT_EQ(r.steps,
            (std::vector<std::string>{"PUT /v1/traffic/closures/fault-0 [[0.0,0.0],[4.0,0.0],[4.0,3.0]]"}));
  inj.apply(12.0, t + std::chrono::hours(1));  // wall time does not end a closure
  EXPECT_EQ(r.steps.size(), 1u);
  inj.apply(15.0, t);
  EXPECT_EQ(r.steps.back(), "DELETE /v1/traffic/closures/fault-0");
  inj.apply(14.0, t);
  std::vector<std::string> events;
  for (const auto& e : inj.log()) {
    events.push_back(e["event"]);
  }
  EXPECT_EQ(events,
            (std::vector<std::string>{"closed area fault-0: 201", "landmarks hidden (fleet-sim) for 2 s",
                                      "reopened area fault-0: 204", "landmarks visible again"}));
}

}  // namespace
}  // namespace fleet::ctl
