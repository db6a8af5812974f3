#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <chrono>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace fleet::transport;
using namespace std::chrono_literals;
using ::testing::HasSubstr;

namespace {
class Transport : public ::testing::Test {
 protected:
  void SetUp() override { setenv("FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain()).c_str(), 1); }
};

template <class W, class R>
void waitMatched(const W& w, const R& r) {
  const auto end = std::chrono::steady_clock::now() + 10s;
  while ((w.matchedReaders() == 0 || r.matchedWriters() == 0) && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(5ms);
  }
}
}  // namespace

TEST_F(Transport, OversizedFieldsAreRefusedWithTheFieldName) {
  Participant p;
  Writer<msg::RobotState> w(p);
  msg::RobotState s;
  s.robot_id = std::string(64, 'x');
  try {
    w.write(s);
    FAIL() << "expected MessageError";
  } catch (const MessageError& e) {
    EXPECT_THAT(e.what(), HasSubstr("RobotState.robot_id: 64 bytes, at most 63 allowed"));
  }
  Writer<msg::PredictedDiscs> wd(p);
  msg::PredictedDiscs d;
  d.source_id = "s";
  d.discs.resize(65);
  EXPECT_THROW(wd.write(d), MessageError);
  msg::TaskEvent ev;
  ev.task_id = std::string("a\0b", 3);
  Writer<msg::TaskEvent> we(p);
  EXPECT_THROW(we.write(ev), MessageError);
}

TEST_F(Transport, InProcessPublishSubscribe) {
  Participant p;
  Writer<msg::VelocityCommand> w(p, qos::command(true));
  w.forRobots({"r0", "r1", "r2"});  // a writer per robot, in its partition
  Reader<msg::VelocityCommand> r(p, qos::command(true));
  waitMatched(w, r);
  for (std::uint32_t i = 0; i < 3; ++i) {
    w.write({"r" + std::to_string(i), 0.1 * i, 0.0, 0, i});
  }
  std::vector<msg::VelocityCommand> got;
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (got.size() < 3 && std::chrono::steady_clock::now() < end) {
    r.waitForData(100ms);
    for (auto& m : r.take()) {
      got.push_back(m);
    }
  }
  ASSERT_EQ(got.size(), 3u);
  EXPECT_EQ(got[2].robot_id, "r2");
  EXPECT_TRUE(r.take().empty());
}

TEST_F(Transport, TransientLocalReachesLateJoiner) {
  Participant p;
  Writer<msg::TaskAssignment> w(p);
  w.write({"robot-1", "task-1", 1, {}, false, 0});
  w.write({"robot-1", "task-2", 2, {}, false, 0});  // keep-last 1 per key: only this one survives
  w.write({"robot-2", "task-3", 1, {}, false, 0});
  Participant late;
  Reader<msg::TaskAssignment> r(late);
  std::vector<msg::TaskAssignment> got;
  const auto end = std::chrono::steady_clock::now() + 5s;
  while (got.size() < 2 && std::chrono::steady_clock::now() < end) {
    r.waitForData(100ms);
    for (auto& m : r.take()) {
      got.push_back(m);
    }
  }
  ASSERT_EQ(got.size(), 2u);
  for (const auto& a : got) {
    EXPECT_EQ(a.task_id, a.robot_id == "robot-1" ? "task-2" : "task-3");
  }
}

TEST_F(Transport, AcknowledgedMeansTheLateJoinerAlreadyHoldsTheData) {
  Participant p;
  Writer<msg::TaskAssignment> w(p);
  w.write({"robot-1", "task-1", 1, {}, false, 0});
  w.write({"robot-2", "task-2", 1, {}, false, 0});
  Participant late;
  Reader<msg::TaskAssignment> r(late);
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (w.matchedReaders() == 0 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_TRUE(w.waitForAcks(10s));
  EXPECT_EQ(r.take().size(), 2u);  // no waiting for data: acknowledged means delivered
}

// Per-robot topics (robot_partition.hpp): a sample counts only when it comes from a writer in the
// partition of the robot it names; a human's discs only from the default partition.
TEST_F(Transport, ASampleCountsOnlyFromItsRobotsPartition) {
  Participant p;
  const QosProfile q{true, true, 0, 0, 1000};  // reliable keep-all: nothing is lost in the test
  Reader<msg::RobotState> r(p, q);
  Writer<msg::RobotState> w(p, q);
  w.forRobots({"r1"});
  // A writer in r1's partition made by hand, as a process speaking for r2 would.
  using Tr = Traits<msg::RobotState>;
  const dds_entity_t r1sWriter = detail::createWriter(
      p.handle(), detail::createTopic(p, Tr::descriptor(), Tr::kTopic), q, {robotPartition("r1")});
  const auto end = std::chrono::steady_clock::now() + 10s;
  while (r.matchedWriters() < 2 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(r.matchedWriters(), 2u);
  msg::RobotState mine;
  mine.robot_id = "r1";
  w.write(mine);
  msg::RobotState other;
  other.robot_id = "r2";
  fleet_RobotState c{};
  Arena arena;
  Tr::toC(other, c, arena);
  ASSERT_EQ(dds_write(r1sWriter, &c), DDS_RETCODE_OK);
  std::vector<msg::RobotState> got;
  while (got.size() + r.foreign() < 2 && std::chrono::steady_clock::now() < end) {
    for (auto& m : r.take()) {
      got.push_back(std::move(m));
    }
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].robot_id, "r1");
  EXPECT_EQ(r.foreign(), 1u);

  Reader<msg::PredictedDiscs> rd(p, q);
  Writer<msg::PredictedDiscs> wd(p, q);
  msg::PredictedDiscs human;
  human.source_id = "h1";
  human.kind = msg::SourceKind::Human;
  msg::PredictedDiscs robot;
  robot.source_id = "r1";
  wd.forRobots({"", "r1"});  // the default partition (humans) and r1's
  while (rd.matchedWriters() < 2 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(5ms);
  }
  wd.write(human);
  wd.write(robot);
  msg::PredictedDiscs robotAsHuman = robot;  // a robot's discs in the default partition
  using Td = Traits<msg::PredictedDiscs>;
  const dds_entity_t plain =
      detail::createWriter(p.handle(), detail::createTopic(p, Td::descriptor(), Td::kTopic), q);
  fleet_PredictedDiscs cd{};
  Td::toC(robotAsHuman, cd, arena);
  while (rd.matchedWriters() < 3 && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(5ms);
  }
  ASSERT_EQ(dds_write(plain, &cd), DDS_RETCODE_OK);
  std::vector<msg::PredictedDiscs> discs;
  while (discs.size() + rd.foreign() < 3 && std::chrono::steady_clock::now() < end) {
    for (auto& m : rd.take()) {
      discs.push_back(std::move(m));
    }
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_EQ(discs.size(), 2u);
  EXPECT_EQ(rd.foreign(), 1u);
}

TEST_F(Transport, WaitSetWakesOnGuard) {
  Participant p;
  WaitSet ws(p);
  Reader<msg::Clock> r(p);
  ws.attach(r);
  std::thread t([&] {
    std::this_thread::sleep_for(50ms);
    ws.wake();
  });
  const auto t0 = std::chrono::steady_clock::now();
  EXPECT_GT(ws.wait(10s), 0);
  EXPECT_LT(std::chrono::steady_clock::now() - t0, 5s);
  t.join();
  EXPECT_EQ(ws.wait(10ms), 0);  // the guard was reset
}

TEST(TransportConfig, QosByNameAndDomainValidation) {
  QosProfile q;
  EXPECT_TRUE(qos::byName("robot_state", q));
  EXPECT_FALSE(q.reliable);
  EXPECT_EQ(q.livelinessLeaseMs, 1000);
  EXPECT_TRUE(qos::byName("assignment", q));
  EXPECT_TRUE(q.reliable && q.transientLocal);
  EXPECT_FALSE(qos::byName("nope", q));
  setenv("FLEET_DDS_DOMAIN", "999", 1);
  EXPECT_THROW((void)domainFromEnvironment(), DdsError);
  setenv("FLEET_DDS_DOMAIN", "12", 1);
  EXPECT_EQ(domainFromEnvironment(), 12);
  EXPECT_THAT(std::string(loopbackConfig()), HasSubstr("<NetworkInterface name=\"lo\"/>"));
  EXPECT_THAT(std::string(loopbackConfig()), HasSubstr("<AllowMulticast>false</AllowMulticast>"));
  // Repair of lost packets: full-size retransmits, heartbeats at least once a second.
  EXPECT_THAT(std::string(loopbackConfig()),
              HasSubstr("<MaxRexmitMessageSize>14720 B</MaxRexmitMessageSize>"));
  EXPECT_THAT(std::string(loopbackConfig()), HasSubstr("<HeartbeatInterval max=\"1 s\">"));
  EXPECT_THAT(std::string(loopbackConfig(false, 50)), HasSubstr("<XmitLossiness>50</XmitLossiness>"));
  try {
    check(DDS_RETCODE_BAD_PARAMETER, "dds_something");
    FAIL();
  } catch (const DdsError& e) {
    EXPECT_THAT(e.what(), HasSubstr("dds_something failed: "));
    EXPECT_EQ(e.code(), DDS_RETCODE_BAD_PARAMETER);
  }
}

TEST(MessageNames, RoundTrip) {
  for (int i = 0; i <= static_cast<int>(msg::TaskState::Rejected); ++i) {
    msg::TaskState s{};
    ASSERT_TRUE(msg::parse(msg::toString(static_cast<msg::TaskState>(i)), s));
    EXPECT_EQ(static_cast<int>(s), i);
  }
  msg::TaskKind k{};
  EXPECT_TRUE(msg::parse("goto", k));
  EXPECT_EQ(k, msg::TaskKind::GoTo);
  EXPECT_FALSE(msg::parse("teleport", k));
}

// RobotState.activity (appended 2026-12-02) crosses the C struct both ways; a value this build does
// not know (a newer peer's) reads as Unset, so the reader derives the activity from the mode.
TEST(TransportConvert, RobotActivityRoundTripsAndAnUnknownOneReadsAsUnset) {
  using Tr = Traits<msg::RobotState>;
  msg::RobotState s;
  s.robot_id = "r1";
  s.activity = msg::RobotActivity::HeldByPerson;
  fleet_RobotState c{};
  Arena arena;
  Tr::toC(s, c, arena);
  EXPECT_EQ(Tr::fromC(c).activity, msg::RobotActivity::HeldByPerson);
  c.activity = static_cast<fleet_RobotActivity>(42);
  EXPECT_EQ(Tr::fromC(c).activity, msg::RobotActivity::Unset);
}
