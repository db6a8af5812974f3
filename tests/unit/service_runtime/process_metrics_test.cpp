// The process_* metrics read from /proc/self are plausible for this very process, render as
// Prometheus text, and appear on every service's /metrics.

#include "fleet/service/process_metrics.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>

#include "fleet/service/service_ops.hpp"

using namespace fleet;

TEST(ProcessMetrics, ReadsPlausibleFiguresOfThisProcess) {
  const auto s = service::readProcessStats();
  ASSERT_TRUE(s.has_value());
  const double now =
      std::chrono::duration<double>(std::chrono::system_clock::now().time_since_epoch()).count();
  EXPECT_GT(s->startTimeSeconds, 1.6e9);      // after 2020
  EXPECT_LE(s->startTimeSeconds, now + 1.0);  // clock ticks round the start to 10 ms
  EXPECT_GE(s->openFds, 3.0);                 // stdin, stdout, stderr
  EXPECT_GE(s->maxFds, s->openFds);
  EXPECT_GT(s->residentBytes, 0.0);
  EXPECT_GE(s->virtualBytes, s->residentBytes);
  EXPECT_GE(s->cpuSeconds, 0.0);
}

TEST(ProcessMetrics, RendersEachFamilyWithHelpTypeAndValue) {
  service::ProcessStats s;
  s.cpuSeconds = 1.5;
  s.residentBytes = 4096;
  s.virtualBytes = 8192;
  s.openFds = 7;
  s.maxFds = 1024;
  s.startTimeSeconds = 1764670000.5;
  const std::string t = service::processMetricsText(s);
  EXPECT_NE(t.find("# TYPE process_cpu_seconds_total counter\nprocess_cpu_seconds_total 1.5\n"),
            std::string::npos)
      << t;
  EXPECT_NE(t.find("# TYPE process_resident_memory_bytes gauge\nprocess_resident_memory_bytes 4096\n"),
            std::string::npos);
  EXPECT_NE(t.find("process_virtual_memory_bytes 8192\n"), std::string::npos);
  EXPECT_NE(t.find("process_open_fds 7\n"), std::string::npos);
  EXPECT_NE(t.find("process_max_fds 1024\n"), std::string::npos);
  EXPECT_NE(t.find("process_start_time_seconds 1764670000.5\n"), std::string::npos);
  EXPECT_NE(t.find("# HELP process_open_fds "), std::string::npos);
}

TEST(ProcessMetrics, AppearOnTheOpsPortMetrics) {
  service::ServiceOps ops("unit_test");
  ASSERT_TRUE(ops.start({"127.0.0.1", 0}));
  httplib::Client c("127.0.0.1", ops.port());
  auto m = c.Get("/metrics");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->status, 200);
  for (const char* name :
       {"process_cpu_seconds_total ", "process_resident_memory_bytes ", "process_virtual_memory_bytes ",
        "process_open_fds ", "process_max_fds ", "process_start_time_seconds "}) {
    EXPECT_NE(m->body.find(std::string("\n") + name), std::string::npos) << name;
  }
  EXPECT_NE(m->body.find("fleet_build_info{"), std::string::npos);  // the registry's families still there
}
