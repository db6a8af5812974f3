// Admission by predicted arrival: worked examples, and a cross-check against a second-by-second
// simulation of the station's line.

#include "fleet/core/station_slots.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>
#include <vector>

namespace fleet {
namespace {

TEST(StationSlots, AnEmptyStationServesOnArrival) {
  const auto o = offerSlot({}, 10.0, 5.0, 2);
  EXPECT_TRUE(o.admitted);
  EXPECT_DOUBLE_EQ(o.wait, 0.0);
  EXPECT_DOUBLE_EQ(o.leave, 15.0);
}

TEST(StationSlots, ARobotArrivingAfterTheLineHasClearedTakesNoSlotNow) {
  // One robot docked now; the line holds one. A robot 3 s away would find it there; one 12 s away
  // finds the station free: only the robot that would crowd the line is refused.
  const std::vector<double> there{0.0};
  EXPECT_FALSE(offerSlot(there, 3.0, 10.0, 1).admitted);
  const auto later = offerSlot(there, 12.0, 10.0, 1);
  EXPECT_TRUE(later.admitted);
  EXPECT_DOUBLE_EQ(later.wait, 0.0);
  // With a queue place it waits there for the docked one: 7 s, then 10 s of its own.
  const auto queued = offerSlot(there, 3.0, 10.0, 2);
  EXPECT_TRUE(queued.admitted);
  EXPECT_DOUBLE_EQ(queued.wait, 7.0);
  EXPECT_DOUBLE_EQ(queued.leave, 20.0);
}

TEST(StationSlots, ARobotThatWouldPushOneBookedLaterOutOfTheLineIsRefused) {
  // Robots at 0 and 5, a line of 2: a robot arriving at 3 fits at 3 (0 and itself), but at 5 the
  // line would hold three (0 leaves at 10, the new one at 20).
  const std::vector<double> booked{0.0, 5.0};
  EXPECT_FALSE(offerSlot(booked, 3.0, 10.0, 2).admitted);
  EXPECT_TRUE(offerSlot(booked, 3.0, 10.0, 3).admitted);
}

TEST(StationSlots, NoLimitAdmitsEveryRobotAndARobotWithNoWayThereIsLeftOut) {
  const std::vector<double> booked{0.0, 0.0, 0.0, std::numeric_limits<double>::infinity()};
  const auto o = offerSlot(booked, 0.0, 4.0, 0);
  EXPECT_TRUE(o.admitted);
  EXPECT_DOUBLE_EQ(o.wait, 12.0);  // behind the three there (not the one that cannot come)
}

/// The line second by second: robots arrive, the server takes the first in line (arrival order,
/// the new robot after those booked for the same second) whenever it is free.
bool simulatedFits(std::vector<int> booked, int mine, int cycle, std::size_t slots, int& wait) {
  struct R {
    int arrive;
    int order;
    int leave = -1;
  };
  std::vector<R> rs;
  for (int a : booked) {
    rs.push_back({a, 0});
  }
  rs.push_back({mine, 1});
  std::stable_sort(rs.begin(), rs.end(), [](const R& x, const R& y) {
    return x.arrive != y.arrive ? x.arrive < y.arrive : x.order < y.order;
  });
  int freeAt = 0;
  for (auto& r : rs) {  // in that order the server takes them
    const int start = std::max(r.arrive, freeAt);
    r.leave = freeAt = start + cycle;
    if (r.order == 1) {
      wait = start - r.arrive;
    }
  }
  const int end = rs.back().leave + 1;
  for (int t = mine; t < end; ++t) {
    std::size_t inLine = 0;
    for (const auto& r : rs) {
      inLine += r.arrive <= t && t < r.leave ? 1 : 0;
    }
    if (inLine > slots) {
      return false;
    }
  }
  return true;
}

TEST(StationSlots, AgreesWithTheLineSimulatedSecondBySecond) {
  std::mt19937 rng(7);
  int admitted = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<int> booked(rng() % 6);
    for (int& a : booked) {
      a = static_cast<int>(rng() % 40);
    }
    const int mine = static_cast<int>(rng() % 40);
    const int cycle = 1 + static_cast<int>(rng() % 12);
    const std::size_t slots = 1 + rng() % 4;
    int wait = -1;
    const bool fits = simulatedFits(booked, mine, cycle, slots, wait);
    const std::vector<double> b(booked.begin(), booked.end());
    const auto o = offerSlot(b, mine, cycle, slots);
    ASSERT_EQ(o.admitted, fits) << "trial " << trial;
    ASSERT_DOUBLE_EQ(o.wait, wait) << "trial " << trial;
    admitted += fits ? 1 : 0;
  }
  EXPECT_GT(admitted, 200);  // both answers occur often
  EXPECT_LT(admitted, 1800);
}

}  // namespace
}  // namespace fleet
