// Contacts and near misses from what the fleet reports (services/wms_adapter/proximity_counter.hpp):
// events count when a pair enters a state and not again while it stays, symmetric in the order the
// robots come in, contacts are near misses too, jitter at a threshold is one event, and the closest
// clearance is exact.

#include "proximity_counter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

using namespace fleet;
using namespace fleet::wms;

namespace {

ProximityDisc robot(const std::string& id, double x, double y, double r = 0.3) {
  return {id, {x, y}, r};
}
ProximityDisc person(double x, double y, double r = 0.25) {
  return {"", {x, y}, r};
}

}  // namespace

TEST(ProximityCounter, APairCountsOnceWhileItStaysClose) {
  ProximityCounter c;  // margin 0.2 m, hysteresis 0.05 m
  c.update({robot("a", 0, 0), robot("b", 2, 0)}, {});
  EXPECT_EQ(c.robotRobot().nearMisses, 0U);
  for (double gap : {0.15, 0.1, 0.18, 0.12}) {  // clearance below the margin, cycle after cycle
    c.update({robot("a", 0, 0), robot("b", 0.6 + gap, 0)}, {});
  }
  EXPECT_EQ(c.robotRobot().nearMisses, 1U);
  EXPECT_EQ(c.robotRobot().close, 1U);
  EXPECT_EQ(c.robotRobot().contacts, 0U);
  c.update({robot("a", 0, 0), robot("b", 2, 0)}, {});  // apart
  EXPECT_EQ(c.robotRobot().close, 0U);
  c.update({robot("a", 0, 0), robot("b", 0.7, 0)}, {});  // close again: a second event
  EXPECT_EQ(c.robotRobot().nearMisses, 2U);
}

TEST(ProximityCounter, JitterAtTheMarginIsOneEvent) {
  ProximityCounter c;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.04, 0.04);  // inside the hysteresis
  for (int i = 0; i < 200; ++i) {
    c.update({robot("a", 0, 0), robot("b", 0.6 + 0.2 + jitter(rng), 0)}, {});
  }
  EXPECT_EQ(c.robotRobot().nearMisses, 1U);
}

TEST(ProximityCounter, AContactIsANearMissTooAndCountsOnce) {
  ProximityCounter c;
  c.update({robot("a", 0, 0), robot("b", 3, 0)}, {});
  c.update({robot("a", 0, 0), robot("b", 0.55, 0)}, {});  // overlap 5 cm, from beyond the margin at once
  c.update({robot("a", 0, 0), robot("b", 0.5, 0)}, {});
  c.update({robot("a", 0, 0), robot("b", 0.61, 0)}, {});  // 1 cm apart: still in contact (hysteresis)
  c.update({robot("a", 0, 0), robot("b", 0.58, 0)}, {});
  EXPECT_EQ(c.robotRobot().contacts, 1U);
  EXPECT_EQ(c.robotRobot().nearMisses, 1U);
  EXPECT_EQ(c.robotRobot().inContact, 1U);
  EXPECT_NEAR(c.robotRobot().minClearance, -0.1, 1e-9);
  c.update({robot("a", 0, 0), robot("b", 0.7, 0)}, {});  // 10 cm apart: no contact, still close
  EXPECT_EQ(c.robotRobot().inContact, 0U);
  EXPECT_EQ(c.robotRobot().close, 1U);
  c.update({robot("a", 0, 0), robot("b", 0.55, 0)}, {});  // touching again: a second contact, same near miss
  EXPECT_EQ(c.robotRobot().contacts, 2U);
  EXPECT_EQ(c.robotRobot().nearMisses, 1U);
}

TEST(ProximityCounter, FiguresDoNotDependOnTheOrderRobotsComeIn) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> pos(0.0, 6.0);
  ProximityCounter forward;
  ProximityCounter shuffled;
  for (int step = 0; step < 300; ++step) {
    std::vector<ProximityDisc> robots;
    std::vector<ProximityDisc> people;
    for (int i = 0; i < 12; ++i) {
      robots.push_back(robot("r" + std::to_string(i), pos(rng), pos(rng)));
    }
    for (int i = 0; i < 5; ++i) {
      people.push_back(person(pos(rng), pos(rng)));
    }
    forward.update(robots, people);
    std::shuffle(robots.begin(), robots.end(), rng);
    std::shuffle(people.begin(), people.end(), rng);
    shuffled.update(robots, people);
  }
  for (auto kind : {&ProximityCounter::robotRobot, &ProximityCounter::robotPerson}) {
    const auto& a = (forward.*kind)();
    const auto& b = (shuffled.*kind)();
    EXPECT_EQ(a.contacts, b.contacts);
    EXPECT_EQ(a.nearMisses, b.nearMisses);
    EXPECT_EQ(a.close, b.close);
    EXPECT_EQ(a.inContact, b.inContact);
    EXPECT_DOUBLE_EQ(a.minClearance, b.minClearance);
    EXPECT_LE(a.contacts, a.nearMisses) << "every contact began as a near miss";
    EXPECT_GT(a.nearMisses, 0U) << "12 robots at random in 6 m x 6 m come close";
  }
}

TEST(ProximityCounter, TheClosestClearanceIsThatOfAllPairs) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> pos(0.0, 50.0);
  ProximityCounter c;
  double brute = std::numeric_limits<double>::infinity();
  double brutePerson = std::numeric_limits<double>::infinity();
  for (int step = 0; step < 50; ++step) {
    std::vector<ProximityDisc> robots;
    std::vector<ProximityDisc> people;
    for (int i = 0; i < 40; ++i) {
      robots.push_back(robot("r" + std::to_string(i), pos(rng), pos(rng), 0.2 + 0.01 * i));
    }
    for (int i = 0; i < 10; ++i) {
      people.push_back(person(pos(rng), pos(rng)));
    }
    for (std::size_t i = 0; i < robots.size(); ++i) {
      for (std::size_t j = i + 1; j < robots.size(); ++j) {
        brute = std::min(brute, distance(robots[i].at, robots[j].at) - robots[i].radius - robots[j].radius);
      }
      for (const auto& p : people) {
        brutePerson = std::min(brutePerson, distance(robots[i].at, p.at) - robots[i].radius - p.radius);
      }
    }
    c.update(robots, people);
    EXPECT_DOUBLE_EQ(c.robotRobot().minClearance, brute);
    EXPECT_DOUBLE_EQ(c.robotPerson().minClearance, brutePerson);
  }
}

TEST(ProximityCounter, ARobotAndThePeopleNearItAreOneEventWhateverWhoIsNearest) {
  ProximityCounter c;
  // Two people walk past a robot one after the other, the second close before the first leaves;
  // two robots see the same person (duplicates in the list).
  c.update({robot("a", 0, 0)}, {person(0.6, 0), person(0.6, 0)});
  c.update({robot("a", 0, 0)}, {person(0.62, 0), person(-0.6, 0)});
  c.update({robot("a", 0, 0)}, {person(3, 0), person(-0.6, 0)});
  EXPECT_EQ(c.robotPerson().nearMisses, 1U);
  EXPECT_EQ(c.robotPerson().contacts, 0U);
  EXPECT_EQ(c.robotRobot().nearMisses, 0U) << "people are not robots";
  c.update({robot("a", 0, 0)}, {});  // nobody seen any more
  EXPECT_EQ(c.robotPerson().close, 0U);
  c.update({robot("a", 0, 0)}, {person(0.5, 0)});
  EXPECT_EQ(c.robotPerson().nearMisses, 2U);
  EXPECT_EQ(c.robotPerson().contacts, 1U);
}

TEST(ProximityCounter, AVanishedRobotLeavesItsPairsAndBadDiscsAreIgnored) {
  ProximityCounter c;
  c.update({robot("a", 0, 0), robot("b", 0.5, 0)}, {});
  EXPECT_EQ(c.robotRobot().inContact, 1U);
  c.update({robot("a", 0, 0)}, {});
  EXPECT_EQ(c.robotRobot().inContact, 0U);
  c.update({robot("a", 0, 0), robot("b", 0.5, 0)}, {});
  EXPECT_EQ(c.robotRobot().contacts, 2U) << "back in contact after it was gone";
  const auto before = c.robotRobot().contacts;
  c.update({robot("a", 0, 0), robot("a", 0.1, 0), robot("c", std::nan(""), 0), robot("d", 0.2, 0, -1.0)},
           {person(std::numeric_limits<double>::infinity(), 0)});
  EXPECT_EQ(c.robotRobot().contacts, before) << "a twice, NaN and negative radii are no pairs";
  EXPECT_EQ(c.robotPerson().contacts, 0U);
}

TEST(ProximityCounter, TheVersionChangesOnlyWithTheFigures) {
  ProximityCounter c;
  c.update({robot("a", 0, 0), robot("b", 5, 0)}, {});
  const auto v = c.version();
  c.update({robot("a", 0, 0), robot("b", 5, 0)}, {});
  EXPECT_EQ(c.version(), v);
  c.update({robot("a", 0, 0), robot("b", 0.7, 0)}, {});
  EXPECT_GT(c.version(), v);
}
