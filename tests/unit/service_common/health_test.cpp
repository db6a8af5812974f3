// Liveness is the loop turning and nothing else; readiness is liveness plus every named condition,
// and the answer names the failing ones only. The ops port refuses a port already taken.

#include "fleet/service/health.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <thread>

#include "fleet/service/command_line.hpp"
#include "fleet/service/ops_server.hpp"
#include "fleet/service/service_ops.hpp"

using namespace fleet;
using namespace std::chrono_literals;

TEST(Health, LiveWhileTheLoopTurnsNotAfterItStalls) {
  service::Health h(50ms);
  h.beat();
  EXPECT_TRUE(h.liveness().ok);
  std::this_thread::sleep_for(120ms);
  const auto a = h.liveness();
  EXPECT_FALSE(a.ok);
  EXPECT_NE(a.text.find("has not turned"), std::string::npos);
  h.beat();
  EXPECT_TRUE(h.liveness().ok);
}

TEST(Health, ReadyOnlyWhenEveryConditionHoldsAndLivenessIgnoresThem) {
  service::Health h(10s);
  h.setReady("site", true);
  h.setReady("dds", false);
  EXPECT_TRUE(h.liveness().ok);  // a dependency down never fails liveness
  const auto a = h.readiness();
  EXPECT_FALSE(a.ok);
  EXPECT_EQ(a.text, "not ready: dds\n");
  h.setReady("dds", true);
  EXPECT_TRUE(h.readiness().ok);
}

TEST(OpsServer, ServesMetricsAndProbesAndRefusesATakenPort) {
  service::ServiceOps ops("unit_test");
  ops.health().setReady("thing", false);
  ASSERT_TRUE(ops.start({"127.0.0.1", 0}));
  ASSERT_GT(ops.port(), 0);
  httplib::Client c("127.0.0.1", ops.port());
  auto m = c.Get("/metrics");
  ASSERT_TRUE(m);
  EXPECT_EQ(m->status, 200);
  EXPECT_NE(m->body.find("fleet_build_info{service=\"unit_test\",version=\""), std::string::npos);
  EXPECT_NE(m->body.find("# TYPE unit_test_rejected_samples_total counter"), std::string::npos);
  EXPECT_EQ(c.Get("/livez")->status, 200);
  auto r = c.Get("/readyz");
  EXPECT_EQ(r->status, 503);
  EXPECT_EQ(r->body, "not ready: thing\n");
  ops.health().setReady("thing", true);
  EXPECT_EQ(c.Get("/readyz")->status, 200);

  // The same port again, as a second process would: an error naming the address, no sharing.
  service::Health h;
  metrics::Registry reg;
  service::OpsServer second(reg, h);
  const auto err = second.start({"127.0.0.1", ops.port()});
  ASSERT_TRUE(err.has_value());
  EXPECT_NE(err->find("cannot listen on 127.0.0.1:" + std::to_string(ops.port())), std::string::npos) << *err;
  EXPECT_TRUE(second.start({"127.0.0.1", 70000}).has_value());
}

TEST(ServiceOps, RejectedSamplesAreCountedByReasonWithoutTheSender) {
  service::ServiceOps ops("unit_test");
  ops.rejected("progress:r7").inc();
  ops.rejected("progress:r8").inc();
  EXPECT_EQ(ops.rejected("progress").value(), 2u);
}

TEST(ServiceOps, SamplesFromAWriterOutsideTheRobotsPartitionAreCountedAsForeign) {
  service::ServiceOps ops("unit_test");
  std::uint64_t dropped = 0;
  ops.watchForeign([&] { return dropped; });
  EXPECT_EQ(ops.rejected("foreign_robot").value(), 0u) << "listed from the start";
  dropped = 3;                 // what the readers' foreign() say
  ASSERT_TRUE(ops.refresh());  // the first refresh does the once-a-second part
  EXPECT_EQ(ops.rejected("foreign_robot").value(), 3u);
}

TEST(CommandLine, UsageErrorsExitTwoAndVersionZero) {
  auto run = [](std::vector<std::string> args) {
    CLI::App app{"t"};
    int n = 0;
    app.add_option("--n", n)->check(CLI::Range(0, 5));
    service::addVersion(app);
    std::vector<char*> argv;
    for (auto& a : args) {
      argv.push_back(a.data());
    }
    return service::parse(app, static_cast<int>(argv.size()), argv.data());
  };
  EXPECT_FALSE(run({"t", "--n", "3"}).has_value());
  EXPECT_EQ(run({"t", "--n", "9"}), 2);  // CLI11 would say 105
  EXPECT_EQ(run({"t", "--bogus"}), 2);   // CLI11 would say 109
  EXPECT_EQ(run({"t", "--n"}), 2);       // missing value
  EXPECT_EQ(run({"t", "--version"}), 0);
  EXPECT_EQ(run({"t", "--help"}), 0);
}
