#include "supervisor.hpp"

#include <gtest/gtest.h>
#include <signal.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>

namespace fleet::ctl {
namespace {

std::string procStat(pid_t pid) {
  std::string out;
  if (FILE* f = std::fopen(("/proc/" + std::to_string(pid) + "/stat").c_str(), "r")) {
    char buf[128] = {};
    if (std::fgets(buf, sizeof buf, f)) {
      out = buf;
    }
    std::fclose(f);
  }
  return out;
}

// A zombie (ended, not yet reaped by whoever inherited it) counts as ended.
bool alive(pid_t pid) {
  const std::string s = procStat(pid);
  const auto close = s.rfind(')');
  return ::kill(pid, 0) == 0 && close != std::string::npos && close + 2 < s.size() && s[close + 2] != 'Z';
}

TEST(Supervisor, CrashIsReportedAndStopEndsTheWholeGroup) {
  const std::string tmp = ::testing::TempDir();
  std::remove((tmp + "/gc.pid").c_str());
  Supervisor s;
  // A shell that starts a grandchild in its process group: stopping must end both.
  ASSERT_TRUE(
      s.start({"sleeper", "/bin/sh", {"-c", "sleep 30 & echo $! > " + tmp + "/gc.pid; wait"}, {}, ""}));
  ASSERT_TRUE(s.start({"crasher", "/bin/sh", {"-c", "exit 7"}, {}, ""}));
  std::vector<std::pair<std::string, int>> gone;
  for (int i = 0; i < 200 && gone.empty(); ++i) {
    gone = s.reapUnexpected();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].first, "crasher");
  EXPECT_EQ(gone[0].second, 7);
  EXPECT_TRUE(s.running("sleeper"));
  pid_t grandchild = 0;
  for (int i = 0; i < 200 && grandchild == 0; ++i) {
    if (FILE* f = std::fopen((tmp + "/gc.pid").c_str(), "r")) {
      if (std::fscanf(f, "%d", &grandchild) != 1) {
        grandchild = 0;
      }
      std::fclose(f);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_GT(grandchild, 0);
  s.stopAll(2.0);
  EXPECT_FALSE(s.running("sleeper"));
  for (int i = 0; i < 100 && alive(grandchild); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_FALSE(alive(grandchild)) << procStat(grandchild);
  EXPECT_TRUE(s.reapUnexpected().empty());  // stopped on purpose
}

TEST(Supervisor, KillHardThenRestart) {
  Supervisor s;
  ASSERT_TRUE(s.start({"p", "/bin/sleep", {"30"}, {}, ""}));
  s.killHard("p");
  EXPECT_FALSE(s.running("p"));
  EXPECT_TRUE(s.reapUnexpected().empty());  // a fault, not a crash
  ASSERT_TRUE(s.restart("p"));
  EXPECT_TRUE(s.running("p"));
  s.stop("p", 2.0);
  EXPECT_FALSE(s.running("p"));
}

TEST(Supervisor, MissingExecutableExits127) {
  Supervisor s;
  ASSERT_TRUE(s.start({"nope", "/nonexistent/binary", {}, {}, ""}));
  std::vector<std::pair<std::string, int>> gone;
  for (int i = 0; i < 200 && gone.empty(); ++i) {
    gone = s.reapUnexpected();
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ASSERT_EQ(gone.size(), 1u);
  EXPECT_EQ(gone[0].second, 127);
}

}  // namespace
}  // namespace fleet::ctl
