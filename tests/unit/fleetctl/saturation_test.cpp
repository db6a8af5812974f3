#include "saturation.hpp"

#include <gtest/gtest.h>

namespace fleet::ctl {
namespace {

TransitionRow at(double s, const std::string& id, const std::string& to) {
  return {id, to, static_cast<std::int64_t>(s * 1e9)};
}

TEST(SaturatedWindow, SpansTheTimeAtLeastAsManyTasksWaitAsThereAreRobots) {
  // Four tasks wait from 0 s; two robots take a and b at 10 s (two still wait: it holds); c is
  // taken at 50 s (one waits: it ends). a and b are done inside, c after.
  const std::vector<TransitionRow> t = {
      at(0, "a", "queued"),    at(0, "b", "queued"),    at(0, "c", "queued"), at(0, "d", "queued"),
      at(10, "a", "assigned"), at(10, "b", "assigned"), at(40, "a", "done"),  at(45, "b", "done"),
      at(50, "c", "assigned"), at(90, "c", "done")};
  const auto w = saturatedWindow(t, 2, 100.0);
  ASSERT_TRUE(w.found);
  EXPECT_DOUBLE_EQ(w.fromS, 0.0);
  EXPECT_DOUBLE_EQ(w.toS, 50.0);
  EXPECT_DOUBLE_EQ(w.heldFraction, 1.0);
  EXPECT_EQ(w.done, 2u);
  EXPECT_EQ(w.peakWaiting, 4u);
  EXPECT_DOUBLE_EQ(w.perRobotPerH, 2.0 / 2.0 * 3600.0 / 50.0);
}

TEST(SaturatedWindow, ADipInsideStaysInTheWindowAndIsReportedAsTheShareHeld) {
  const std::vector<TransitionRow> t = {
      at(0, "a", "queued"),    at(0, "b", "queued"), at(10, "a", "assigned"), at(20, "c", "queued"),
      at(30, "b", "assigned"), at(25, "a", "done"),  at(40, "c", "assigned")};
  // Stamps need not be sorted by the caller's clock: the manager's order is what counts, and a
  // done at 25 s stored after the assignment at 30 s is still inside (0, 30].
  const auto w = saturatedWindow(t, 2, 60.0);
  ASSERT_TRUE(w.found);
  EXPECT_DOUBLE_EQ(w.fromS, 0.0);
  EXPECT_DOUBLE_EQ(w.toS, 30.0);
  EXPECT_NEAR(w.heldFraction, 20.0 / 30.0, 1e-12);
  EXPECT_EQ(w.done, 1u);
}

TEST(SaturatedWindow, AWindowStillOpenAtTheEndClosesThere) {
  const std::vector<TransitionRow> t = {at(5, "a", "queued"), at(6, "b", "queued"), at(30, "x", "done")};
  const auto w = saturatedWindow(t, 1, 65.0);
  ASSERT_TRUE(w.found);
  EXPECT_DOUBLE_EQ(w.fromS, 5.0);
  EXPECT_DOUBLE_EQ(w.toS, 65.0);
  EXPECT_EQ(w.done, 1u);
  EXPECT_DOUBLE_EQ(w.perRobotPerH, 3600.0 / 60.0);
}

TEST(SaturatedWindow, ARequeuedTaskWaitsAgainAndADuplicateDoneCountsOnce) {
  const std::vector<TransitionRow> t = {
      at(0, "a", "queued"), at(1, "a", "assigned"), at(20, "a", "queued"),  at(30, "a", "assigned"),
      at(50, "a", "done"),  at(55, "a", "done"),    at(60, "b", "assigned")};
  const auto w = saturatedWindow(t, 1, 100.0);
  ASSERT_TRUE(w.found);
  EXPECT_DOUBLE_EQ(w.fromS, 0.0);
  EXPECT_DOUBLE_EQ(w.toS, 30.0);
  EXPECT_NEAR(w.heldFraction, 11.0 / 30.0, 1e-12);
  EXPECT_EQ(w.done, 0u);  // done at 50 s, after the window
  // With b waiting from 0 s until it is taken at 60 s, one robot is saturated over [0, 60], and
  // a's two "done" (50 s, 55 s) inside it count once.
  auto withB = t;
  withB.insert(withB.begin(), at(0, "b", "queued"));
  const auto all = saturatedWindow(withB, 1, 100.0);
  ASSERT_TRUE(all.found);
  EXPECT_DOUBLE_EQ(all.toS, 60.0);
  EXPECT_EQ(all.done, 1u);
}

TEST(SaturatedWindow, NoWindowWhenFewerTasksThanRobotsEverWaitOrOnlyInsideOneBatch) {
  // Three stored and two assigned in the same tick: never more than one waits between ticks.
  const std::vector<TransitionRow> batch = {at(3, "a", "queued"), at(3, "b", "queued"), at(3, "c", "queued"),
                                            at(3, "a", "assigned"), at(3, "b", "assigned")};
  EXPECT_FALSE(saturatedWindow(batch, 2, 10.0).found);
  EXPECT_EQ(saturatedWindow(batch, 2, 10.0).peakWaiting, 1u);  // as the window counts it
  EXPECT_FALSE(saturatedWindow(batch, 0, 10.0).found);
  EXPECT_FALSE(saturatedWindow({}, 1, 10.0).found);
  // Reached at the run's very end only: a window of no length.
  EXPECT_FALSE(saturatedWindow({at(10, "a", "queued")}, 1, 10.0).found);
}

TEST(SaturatedWindow, MoreRobotsNeverWidenTheWindow) {
  std::vector<TransitionRow> t;
  for (int i = 0; i < 30; ++i) {
    t.push_back(at(i * 2.0, "t" + std::to_string(i), "queued"));
  }
  for (int i = 0; i < 30; ++i) {
    t.push_back(at(70.0 + i * 3.0, "t" + std::to_string(i), "assigned"));
  }
  double previous = 1e9;
  for (std::size_t robots = 1; robots <= 30; ++robots) {
    const auto w = saturatedWindow(t, robots, 200.0);
    const double len = w.found ? w.toS - w.fromS : 0.0;
    EXPECT_LE(len, previous) << robots << " robots";
    previous = len;
  }
}

TEST(SaturatedWindow, TheReportGivesTheWindowsRatesAndNoLoneRobotEta) {
  const std::vector<TransitionRow> t = {at(0, "a", "queued"), at(0, "b", "queued"), at(36, "x", "done"),
                                        at(72, "a", "assigned")};
  const auto w = saturatedWindow(t, 2, 100.0);  // [0, 72]: one done by two robots
  const auto plain = saturatedJson(w);
  EXPECT_TRUE(plain["found"].get<bool>());
  EXPECT_DOUBLE_EQ(plain["per_robot_rate_per_h"].get<double>(), 25.0);
  EXPECT_FALSE(plain.contains("efficiency"));
  EXPECT_EQ(saturatedLine(plain).find("eta"), std::string::npos) << saturatedLine(plain);
  const auto none = saturatedJson(saturatedWindow({}, 3, 10.0));
  EXPECT_FALSE(none["found"].get<bool>());
  EXPECT_NE(saturatedLine(none).find("none"), std::string::npos);
}

}  // namespace
}  // namespace fleet::ctl
