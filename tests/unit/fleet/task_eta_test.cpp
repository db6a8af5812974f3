#include "fleet/fleet/task_eta.hpp"

#include <gtest/gtest.h>

#include <limits>

namespace fleet {
namespace {

constexpr std::int64_t kS = 1'000'000'000;

TEST(TaskEta, BeforeAnyTaskIsDoneAnActiveTaskIsDueAtItsPrediction) {
  TaskEta eta;
  EXPECT_DOUBLE_EQ(eta.pace(), 1.0);
  EXPECT_EQ(eta.assigned("t1", 10 * kS, 40.0), 50 * kS);
  EXPECT_EQ(eta.active("t1", 20 * kS), 50 * kS);
  // Running late: due now, never in the past.
  EXPECT_EQ(eta.active("t1", 70 * kS), 70 * kS);
  EXPECT_EQ(eta.active("unknown", 20 * kS), 0);
}

TEST(TaskEta, NoPredictionNoEstimate) {
  TaskEta eta;
  EXPECT_EQ(eta.assigned("t1", kS, std::numeric_limits<double>::infinity()), 0);
  EXPECT_EQ(eta.assigned("t2", kS, -1.0), 0);
  EXPECT_EQ(eta.assigned("t3", kS, 0.0), kS) << "on the spot, nothing to dwell: due now";
  EXPECT_EQ(eta.active("t1", kS), 0);
  EXPECT_EQ(eta.waiting(kS, 0, 4, std::numeric_limits<double>::quiet_NaN()), 0);
  EXPECT_EQ(eta.waiting(kS, 0, 0, 30.0), 0) << "no robot to take it";
}

TEST(TaskEta, ThePaceIsLearntFromTasksDoneAndStretchesLaterEstimates) {
  TaskEta eta;
  // Two tasks predicted at 40 s that took 80 s and 120 s: the fleet runs at 2.5x its prediction.
  eta.assigned("a", 0, 40.0);
  eta.assigned("b", 0, 40.0);
  eta.ended("a", 80 * kS, true);
  eta.ended("b", 120 * kS, true);
  EXPECT_DOUBLE_EQ(eta.pace(), 2.5);
  EXPECT_EQ(eta.assigned("c", 200 * kS, 10.0), 225 * kS);
  // A requeued task teaches nothing and is forgotten.
  eta.ended("c", 500 * kS, false);
  EXPECT_DOUBLE_EQ(eta.pace(), 2.5);
  EXPECT_EQ(eta.active("c", 300 * kS), 0);
}

TEST(TaskEta, ThePaceIsClampedAndKeptOverItsWindow) {
  TaskEta eta({.window = 2, .minPace = 1.0, .maxPace = 3.0});
  eta.assigned("fast", 0, 100.0);
  eta.ended("fast", 10 * kS, true);  // 0.1 -> 1.0: never stated faster than free flow
  EXPECT_DOUBLE_EQ(eta.pace(), 1.0);
  eta.assigned("slow", 0, 10.0);
  eta.ended("slow", 100 * kS, true);  // 10 -> 3.0
  EXPECT_DOUBLE_EQ(eta.pace(), 2.0);
  eta.assigned("mid", 100 * kS, 10.0);
  eta.ended("mid", 120 * kS, true);  // 2.0; the window drops "fast"
  EXPECT_DOUBLE_EQ(eta.pace(), 2.5);
}

TEST(TaskEta, TheRateCountsCompletionsOverTheWindow) {
  TaskEta eta({.window = 3});
  EXPECT_DOUBLE_EQ(eta.rate(), 0.0);
  for (int i = 0; i < 6; ++i) {
    eta.ended("x" + std::to_string(i), i * 10 * kS, true);
  }
  // The last four completions (window + 1) span 30 s: 3 tasks in 30 s.
  EXPECT_DOUBLE_EQ(eta.rate(), 0.1);
}

TEST(TaskEta, AWaitingTaskWithAFreeRobotStartsNow) {
  TaskEta eta;
  EXPECT_EQ(eta.waiting(5 * kS, 0, 2, 30.0), 35 * kS);
  EXPECT_EQ(eta.waiting(5 * kS, 1, 2, 30.0), 35 * kS);
}

TEST(TaskEta, AWaitingTaskBehindABusyFleetWaitsForTheQueueAheadToDrain) {
  TaskEta eta;
  eta.assigned("a", 0, 60.0);
  eta.assigned("b", 0, 60.0);
  // Two robots, both busy, no completion yet: 2 tasks per 60 s; 3 ahead -> 4 completions = 120 s.
  EXPECT_EQ(eta.waiting(0, 3, 2, 60.0), (120 + 60) * kS);
  // Once completions are seen, their rate counts: one every 20 s.
  eta.ended("a", 20 * kS, true);
  eta.assigned("c", 20 * kS, 60.0);
  eta.ended("b", 40 * kS, true);
  eta.assigned("d", 40 * kS, 60.0);
  // pace: a 20/60 and b 40/60 clamped to 1; rate 1 per 20 s; 3 ahead -> 80 s, then 60 s.
  EXPECT_EQ(eta.waiting(40 * kS, 3, 2, 60.0), (40 + 80 + 60) * kS);
}

TEST(TaskEta, AnEstimateNeverMovesEarlierThanTheLaterQueuePlace) {
  // Property: further back in the queue is never due sooner.
  TaskEta eta;
  eta.assigned("a", 0, 45.0);
  eta.ended("a", 90 * kS, true);
  eta.assigned("b", 50 * kS, 45.0);
  eta.ended("b", 130 * kS, true);
  for (std::size_t robots : {1U, 3U, 10U}) {
    std::int64_t last = 0;
    for (std::size_t ahead = 0; ahead < 40; ++ahead) {
      const auto t = eta.waiting(200 * kS, ahead, robots, 45.0);
      EXPECT_GE(t, last) << robots << " robots, " << ahead << " ahead";
      last = t;
    }
  }
}

TEST(TaskEta, TheTypicalPredictionIsTheMeanOfTheLastAssignments) {
  TaskEta eta({.window = 2});
  EXPECT_DOUBLE_EQ(eta.typical(), 0.0);
  eta.assigned("a", 0, 10.0);
  eta.assigned("b", 0, 20.0);
  eta.assigned("c", 0, 40.0);
  EXPECT_DOUBLE_EQ(eta.typical(), 30.0);
  EXPECT_EQ(eta.running(), 3U);
}

}  // namespace
}  // namespace fleet
