// Liveness is the loop turning and nothing else; readiness is liveness plus every named condition,
// and the answer names the failing ones only. The ops port refuses a port already taken.

#include "fleet/service/health.hpp"

#include <gtest/gtest.h>
#include <httplib.h>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <atomic>
#include <thread>
#include <vector>

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

namespace {

/// A client that sends a request line, then one header byte every 50 ms, and connects again
/// whenever the server closes it: it never finishes its head.
int slowConnect(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_port = htons(static_cast<std::uint16_t>(port));
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) {
    ::close(fd);
    return -1;
  }
  const std::string line = "GET /livez HTTP/1.1\r\nHost: x\r\n";
  ::send(fd, line.data(), line.size(), MSG_NOSIGNAL);
  return fd;
}

}  // namespace

TEST(OpsServer, SlowClientsTricklingTheirHeadsNeverKeepLivezWaiting) {
  service::Health h;
  metrics::Registry reg;
  service::OpsServer server(reg, h);
  ASSERT_FALSE(server.start({"127.0.0.1", 0}).has_value());
  constexpr int kSlow = 12;  // three times the worker threads the ops port used to have
  std::atomic<bool> stop{false};
  std::vector<std::thread> slow;
  for (int i = 0; i < kSlow; ++i) {
    slow.emplace_back([&, port = server.port()] {
      int fd = slowConnect(port);
      while (!stop) {
        std::this_thread::sleep_for(50ms);
        if (fd < 0 || ::send(fd, "X", 1, MSG_NOSIGNAL) != 1) {
          if (fd >= 0) {
            ::close(fd);
          }
          fd = slowConnect(port);
        }
      }
      if (fd >= 0) {
        ::close(fd);
      }
    });
  }
  std::this_thread::sleep_for(300ms);  // every slow client connected and trickling
  // Probes through the trickle, past the header timeout (the slow ones are cut off and come back).
  httplib::Client c("127.0.0.1", server.port());
  c.set_connection_timeout(3);
  c.set_read_timeout(3);
  int answered = 0;
  for (int i = 0; i < 6; ++i) {
    auto r = c.Get("/livez");
    answered += r && r->status == 200 ? 1 : 0;
    std::this_thread::sleep_for(400ms);
  }
  stop = true;
  for (auto& t : slow) {
    t.join();
  }
  EXPECT_EQ(answered, 6);
  EXPECT_GE(server.timedOut(), kSlow) << "every slow client was cut off at the header timeout";
  // A connection table full of slow ones makes room for the newest.
  service::OpsServer small(reg, h, {.headerTimeoutMs = 60000, .maxConnections = 4});
  ASSERT_FALSE(small.start({"127.0.0.1", 0}).has_value());
  std::vector<int> held;
  for (int i = 0; i < 8; ++i) {
    held.push_back(slowConnect(small.port()));
  }
  httplib::Client c2("127.0.0.1", small.port());
  c2.set_read_timeout(3);
  auto r = c2.Get("/livez");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 200);
  EXPECT_GE(small.evicted(), 4);
  for (int fd : held) {
    ::close(fd);
  }
}

TEST(OpsServer, AnswersOtherMethodsPathsAndLargeHeadsWithoutServingThem) {
  service::Health h;
  metrics::Registry reg;
  service::OpsServer server(reg, h);
  ASSERT_FALSE(server.start({"127.0.0.1", 0}).has_value());
  httplib::Client c("127.0.0.1", server.port());
  EXPECT_EQ(c.Get("/nothing")->status, 404);
  EXPECT_EQ(c.Post("/livez", "x", "text/plain")->status, 405);
  httplib::Headers big{{"X-Big", std::string(10000, 'a')}};
  EXPECT_EQ(c.Get("/livez", big)->status, 431);
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
