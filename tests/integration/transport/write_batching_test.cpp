// Write batching across processes: a burst queued on a write-batching participant arrives complete
// at a reader in another process once flushed (the last, partly filled datagram included), and
// write() on such a participant still delivers each sample without an explicit flush.

#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <thread>

#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace fleet::transport;
using namespace std::chrono_literals;

namespace {
const QosProfile kAll{true, true, 0, 0, 2000};

class WriteBatching : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    setenv("FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain()).c_str(), 1);
    peer_ = new test::ChildProcess(FLEET_BINARY_DIR "/tests/integration/transport/transport_echo_peer",
                                   {"60"}, {{"FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain())}});
    participant_ = new Participant(ParticipantOptions{.writeBatching = true});
  }
  static void TearDownTestSuite() {
    delete participant_;
    delete peer_;
  }
  static test::ChildProcess* peer_;
  static Participant* participant_;
};
test::ChildProcess* WriteBatching::peer_ = nullptr;
Participant* WriteBatching::participant_ = nullptr;

msg::RobotState state(std::uint32_t i) {
  msg::RobotState s;
  s.robot_id = "robot-" + std::to_string(i % 7);
  s.stamp_ns = i;
  s.pose = {0.5 * i, 1.0, 0.25};
  s.v = 0.8;
  s.task_id = "t" + std::to_string(i);
  return s;
}

template <class T>
std::vector<T> collect(Reader<T>& r, std::size_t n, std::chrono::steady_clock::time_point deadline) {
  std::vector<T> got;
  while (got.size() < n && std::chrono::steady_clock::now() < deadline) {
    r.waitForData(100ms);
    for (auto& m : r.take()) {
      got.push_back(std::move(m));
    }
  }
  return got;
}
}  // namespace

TEST_F(WriteBatching, QueuedBurstArrivesWholeAfterFlush) {
  Writer<msg::RobotState> w(*participant_, kAll);
  w.forRobots({"robot-0", "robot-1", "robot-2", "robot-3", "robot-4", "robot-5", "robot-6", "warm-up"});
  Reader<msg::RobotState> r(*participant_, kAll, std::string(Traits<msg::RobotState>::kTopic) + "_echo");
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  // The peer's echo writer of a robot is made at that robot's first sample (one writer per robot,
  // in its partition); transient-local, it reaches this reader whenever it matches.
  while (w.matchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(w.matchedReaders(), 0u);
  // One round trip first. Our reader seeing the peer's echo writer does not mean that writer has
  // seen our reader yet; until it has, transient-local keeps only the last sample per instance for
  // us (on a loaded CI machine 7 of 1,003 arrived, one per robot id).
  msg::RobotState warm = state(0);
  warm.robot_id = "warm-up";
  bool echoed = false;
  while (!echoed && std::chrono::steady_clock::now() < deadline) {
    w.write(warm);
    r.waitForData(200ms);
    for (const auto& m : r.take()) {
      echoed = echoed || m.robot_id == "warm-up";
    }
  }
  ASSERT_TRUE(echoed) << "the peer never echoed";
  // 1,003 samples: many full datagrams plus a partial last one that only flush() sends.
  constexpr std::uint32_t kN = 1003;
  for (std::uint32_t i = 0; i < kN; ++i) {
    w.queue(state(i));
  }
  w.flush();
  std::vector<msg::RobotState> got;
  while (got.size() < kN && std::chrono::steady_clock::now() < deadline) {
    r.waitForData(100ms);
    for (auto& m : r.take()) {
      if (m.robot_id != "warm-up") {  // repeats of the round trip may still come in
        got.push_back(std::move(m));
      }
    }
  }
  ASSERT_EQ(got.size(), kN);
  // A take() returns samples grouped by instance (robot id), so compare in write order by stamp.
  std::sort(got.begin(), got.end(), [](const auto& a, const auto& b) { return a.stamp_ns < b.stamp_ns; });
  for (std::uint32_t i = 0; i < kN; ++i) {
    EXPECT_TRUE(got[i] == state(i)) << "sample " << i;
  }
}

TEST_F(WriteBatching, WriteDeliversWithoutExplicitFlush) {
  Writer<msg::TaskStatus> w(*participant_, kAll);
  w.forRobots({"robot-1"});
  Reader<msg::TaskStatus> r(*participant_, kAll, std::string(Traits<msg::TaskStatus>::kTopic) + "_echo");
  const auto deadline = std::chrono::steady_clock::now() + 20s;
  // The peer's echo writer of a robot is made at that robot's first sample (one writer per robot,
  // in its partition); transient-local, it reaches this reader whenever it matches.
  while (w.matchedReaders() == 0 && std::chrono::steady_clock::now() < deadline) {
    std::this_thread::sleep_for(10ms);
  }
  ASSERT_GT(w.matchedReaders(), 0u);
  msg::TaskStatus s;
  s.task_id = "single";
  s.robot_id = "robot-1";
  w.write(s);
  const auto got = collect(r, 1, deadline);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].task_id, "single");
}

TEST_F(WriteBatching, MixingSettingsOnOneDomainIsRefused) {
  try {
    Participant plain(participant_->domain(), ParticipantOptions{.writeBatching = false});
    FAIL() << "expected DdsError";
  } catch (const DdsError& e) {
    EXPECT_NE(std::string(e.what()).find("already joined the domain with the other setting"),
              std::string::npos)
        << e.what();
  }
}
