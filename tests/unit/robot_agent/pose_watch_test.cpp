// PoseWatch: the pose is doubted when a whole window's lines are mostly refused, trusted again when
// they match, and too few lines are no evidence either way.

#include "pose_watch.hpp"

#include <gtest/gtest.h>

using fleet::agent::PoseWatch;
using fleet::agent::PoseWatchParams;

namespace {

constexpr std::int64_t kTick = 100'000'000;  // 0.1 s

// Feeds `cycles` cycles of `lines` extracted lines each, `fused` of them accepted; returns the
// changes seen, in order.
struct Feed {
  // The mechanism at round numbers (the defaults are checked on their own below).
  PoseWatch watch{PoseWatchParams{.windowS = 5.0, .minLines = 20, .doubtBelow = 0.2, .trustAbove = 0.6}};
  std::int64_t now = 0;
  std::uint64_t extracted = 0;
  std::uint64_t accepted = 0;
  std::vector<PoseWatch::Change> changes;
  std::vector<std::int64_t> at;

  void run(int cycles, std::uint64_t lines, std::uint64_t fused) {
    for (int i = 0; i < cycles; ++i) {
      now += kTick;
      extracted += lines;
      accepted += fused;
      const auto c = watch.update(now, extracted, accepted);
      if (c != PoseWatch::Change::kNone) {
        changes.push_back(c);
        at.push_back(now);
      }
    }
  }
};

}  // namespace

TEST(PoseWatch, MatchingLinesKeepThePoseTrustedForever) {
  Feed f;
  f.run(600, 3, 3);
  f.run(600, 3, 2);  // a third refused (people in front of walls): still trusted
  EXPECT_TRUE(f.changes.empty());
  EXPECT_FALSE(f.watch.doubted());
}

TEST(PoseWatch, ARobotWhoseLinesAreRefusedIsDoubtedAfterAWholeWindowAndSaysWhy) {
  Feed f;
  f.run(30, 3, 3);   // 3 s of good lines
  f.run(100, 3, 0);  // then every line refused
  ASSERT_EQ(f.changes.size(), 1u);
  EXPECT_EQ(f.changes[0], PoseWatch::Change::kDoubted);
  // Doubted once under a fifth fused over the last 5 s: 3 s of good lines age out first.
  EXPECT_GE(f.at[0], 30 * kTick + 40 * kTick);
  EXPECT_LE(f.at[0], 30 * kTick + 50 * kTick);
  EXPECT_TRUE(f.watch.doubted());
  EXPECT_EQ(f.watch.doubts(), 1u);
  EXPECT_NE(f.watch.why().find("of 150 laser lines matched the site's walls in the last 5.0 s"),
            std::string::npos)
      << f.watch.why();
}

TEST(PoseWatch, ADoubtedPoseIsTrustedAgainWhenTheLinesMatchAndHysteresisHolds) {
  Feed f;
  f.run(60, 3, 0);
  ASSERT_TRUE(f.watch.doubted());
  f.run(100, 10, 4);  // 40 %: between the thresholds, the judgement stands
  EXPECT_TRUE(f.watch.doubted());
  f.run(100, 3, 3);
  EXPECT_FALSE(f.watch.doubted());
  ASSERT_EQ(f.changes.size(), 2u);
  EXPECT_EQ(f.changes[1], PoseWatch::Change::kTrusted);
}

TEST(PoseWatch, TooFewLinesAreNoEvidenceEitherWay) {
  Feed f;
  f.run(600, 0, 0);  // open floor: no lines
  EXPECT_FALSE(f.watch.doubted());
  Feed g;
  g.watch = PoseWatch(PoseWatchParams{.windowS = 5.0, .minLines = 20});
  // 19 lines in every 5 s window, none fused.
  for (int i = 0; i < 600; ++i)
    g.run(1, i % 26 == 0 ? 1 : 0, 0);
  EXPECT_FALSE(g.watch.doubted());
}

TEST(PoseWatch, CountsThatStartAgainAreJudgedAfresh) {
  Feed f;
  f.run(60, 3, 0);
  ASSERT_TRUE(f.watch.doubted());
  // The localizer was replaced (its counts from 0): no window spans the restart.
  f.extracted = f.accepted = 0;
  f.run(10, 3, 3);
  EXPECT_TRUE(f.watch.doubted()) << "not a whole window of the new counts yet";
  f.run(50, 3, 3);
  EXPECT_FALSE(f.watch.doubted());
}

TEST(PoseWatch, ByDefaultAFullyRefusedRobotIsDoubtedWithinTenSecondsAndOneFusingAFifthIsNot) {
  // The defaults: a 10 s window, doubted under a tenth fused (a robot among parked robots and
  // people fuses more than that; a lost one ~7 %).
  PoseWatch lost;
  PoseWatch crowded;
  std::uint64_t e = 0;
  std::uint64_t a = 0;
  int doubtedAt = -1;
  for (int i = 1; i <= 300; ++i) {
    e += 3;
    a += i % 5 == 0 ? 3 : 0;  // a fifth of the lines fused
    if (lost.update(i * kTick, e, 0) == PoseWatch::Change::kDoubted)
      doubtedAt = i;
    (void)crowded.update(i * kTick, e, a);
  }
  EXPECT_GE(doubtedAt, 100);
  EXPECT_LE(doubtedAt, 101);
  EXPECT_FALSE(crowded.doubted());
}
