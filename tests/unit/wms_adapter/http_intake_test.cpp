// HTTP intake that one client cannot stop. Each test is a way a client stopped the
// cpp-httplib server (slow heads and bodies, open event streams, chunked bodies read whole, a burst
// of connections against a backlog of 5); the bounds in the tests (client timeouts, receive
// limits) only keep a broken server from hanging the test. Same-id requests at once are answered
// since the Task topic is keyed by request id: FleetE2E.ConcurrentRequestsOnOneTaskAreAllAnswered.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <sys/resource.h>

#include <atomic>
#include <chrono>
#include <thread>

#include "api_fixture.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using ::testing::HasSubstr;

namespace {

const std::string kTask = R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})";

std::string goTo(const std::string& id) {
  return R"({"id": ")" + id + R"(", "kind": "goto", "station": "D-1"})";
}

/// A client that keeps a request unfinished: a head one byte at a time, or a body one byte at a
/// time after a complete head, until stopped.
class Slowloris {
 public:
  Slowloris(int port, int connections) {
    for (int i = 0; i < connections; ++i) {
      clients_.push_back(std::make_unique<RawClient>(port));
      if (i % 2 == 1) {
        // A slow body: the head is complete and promises 100000 bytes.
        clients_.back()->send(
            "POST /v1/tasks HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: "
            "100000\r\n\r\n");
      } else {
        clients_.back()->send("POST /v1/tasks HTTP/1.1\r\nHost: x\r\n");
      }
    }
    thread_ = std::thread([this] {
      while (!stop_) {
        for (std::size_t i = 0; i < clients_.size(); ++i) {
          clients_[i]->send(i % 2 == 1 ? " " : "X");
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
      }
    });
  }
  ~Slowloris() {
    stop_ = true;
    thread_.join();
  }
  Slowloris(const Slowloris&) = delete;
  Slowloris& operator=(const Slowloris&) = delete;
  RawClient& client(std::size_t i) { return *clients_[i]; }

 private:
  std::vector<std::unique_ptr<RawClient>> clients_;
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

class Intake : public Api {
 protected:
  void startWithBodiesUpTo64KiB() {
    ApiSettings s;
    s.limits.maxBodyBytes = 64 * 1024;
    start(s);
  }
};

}  // namespace

TEST_F(Intake, SlowClientsHoldNoWorkerAndOthersAreServed) {
  ApiSettings s;
  s.limits.threads = 2;
  s.limits.maxInFlight = 2;
  start(s);
  Slowloris slow(api_->port(), 16);  // twice the old server's 8 threads, eight times these 2
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  client_->set_read_timeout(8, 0);
  auto h = client_->Get("/v1/health");
  ASSERT_TRUE(h) << "health did not answer while slow clients were connected";
  EXPECT_EQ(h->status, 200);
  auto r = post(kTask);
  ASSERT_TRUE(r) << "POST /v1/tasks did not answer while slow clients were connected";
  EXPECT_EQ(r->status, 201);
  EXPECT_EQ(client_->Get("/v1/tasks/t-1")->status, 200);
}

TEST_F(Intake, AClientTooSlowToFinishItsRequestIsCutOff) {
  ApiSettings s;
  s.limits.requestTimeoutMs = 300;
  start(s);
  Slowloris slow(api_->port(), 2);  // one slow head, one slow body, a byte every 50 ms each
  EXPECT_EQ(slow.client(0).receive(), "") << "a request never finished gets no answer";
  EXPECT_TRUE(slow.client(0).closedByPeer()) << "the slow head's connection stays open";
  slow.client(1).receive();
  EXPECT_TRUE(slow.client(1).closedByPeer()) << "the slow body's connection stays open";
  // The server counts a timeout after its stream has closed the socket: the client can see the
  // close first (it did once in CI under load), so give the count a moment.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(2);
  while (api_->serverStats().timedOut.load() < 2 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_GE(api_->serverStats().timedOut.load(), 2);
}

TEST_F(Intake, OpenEventStreamsDoNotBlockSubmissions) {
  ApiSettings s;
  s.limits.threads = 2;
  s.limits.maxInFlight = 2;
  start(s);
  std::vector<std::unique_ptr<RawClient>> streams;
  for (int i = 0; i < 12; ++i) {
    streams.push_back(std::make_unique<RawClient>(api_->port()));
    streams.back()->send("GET /v1/events HTTP/1.1\r\nHost: x\r\n\r\n");
    ASSERT_THAT(streams.back()->receive("\r\n\r\n"), HasSubstr("text/event-stream"));
  }
  EXPECT_EQ(api_->serverStats().openStreams.load(), 12);
  client_->set_read_timeout(8, 0);
  auto r = post(kTask);
  ASSERT_TRUE(r) << "POST /v1/tasks did not answer with event streams open";
  EXPECT_EQ(r->status, 201);
  view_.onEvent({"t-1", msg::TaskState::Assigned, "r1", "", 1, 1, ""});
  EXPECT_THAT(streams.front()->receive("assigned"), HasSubstr("\"state\":\"assigned\""));
  EXPECT_THAT(streams.back()->receive("assigned"), HasSubstr("\"state\":\"assigned\""));
}

TEST_F(Intake, EventStreamsBeyondTheLimitGet503WithRetryAfter) {
  ApiSettings s;
  s.limits.maxStreams = 2;
  start(s);
  RawClient a(api_->port());
  RawClient b(api_->port());
  for (auto* c : {&a, &b}) {
    c->send("GET /v1/events HTTP/1.1\r\nHost: x\r\n\r\n");
    ASSERT_THAT(c->receive("\r\n\r\n"), HasSubstr("200 OK"));
  }
  auto r = client_->Get("/v1/events");
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 503);
  EXPECT_EQ(r->get_header_value("Retry-After"), "5");
  EXPECT_EQ(client_->Get("/v1/health")->status, 200);
}

TEST_F(Intake, OversizedChunkedBodyIsRefusedWith413BeforeItIsRead) {
  startWithBodiesUpTo64KiB();
  RawClient c(api_->port());
  c.send(
      "POST /v1/tasks HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nTransfer-Encoding: "
      "chunked\r\n\r\n");
  const std::string chunk = "2000\r\n" + std::string(0x2000, ' ') + "\r\n";
  // Four times the limit; the server stops reading at the limit (the old one read it all, then 400).
  for (int i = 0; i < 32 && c.send(chunk); ++i) {
  }
  const auto response = c.receive("}");
  EXPECT_EQ(statusOf(response), 413) << response;
  EXPECT_THAT(response, HasSubstr("too_large"));
  EXPECT_TRUE(gateway_.bodies.empty());
  EXPECT_EQ(api_->serverStats().tooLarge.load(), 1);
}

TEST_F(Intake, DeclaredOversizedBodyIsRefusedWithoutWaitingForIt) {
  startWithBodiesUpTo64KiB();
  RawClient c(api_->port());
  c.send(
      "POST /v1/tasks HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: "
      "1000000000\r\n\r\n");
  EXPECT_EQ(statusOf(c.receive("}")), 413);
}

TEST_F(Intake, ABurstOfConnectionsIsAnsweredWith429NotReset) {
  start();  // the defaults: 16 workers, 16 in flight, backlog 1024
  gateway_.delay = std::chrono::milliseconds(300);
  constexpr int kClients = 400;
  // Both ends of 400 connections live in this process: more descriptors than a soft limit of 1024
  // leaves room for on some machines.
  rlimit files{};
  getrlimit(RLIMIT_NOFILE, &files);
  files.rlim_cur = std::max<rlim_t>(files.rlim_cur, std::min<rlim_t>(files.rlim_max, 4096));
  setrlimit(RLIMIT_NOFILE, &files);
  std::vector<std::unique_ptr<RawClient>> clients;
  for (int i = 0; i < kClients; ++i) {
    clients.push_back(std::make_unique<RawClient>(api_->port()));
    ASSERT_TRUE(clients.back()->connected()) << "connection " << i << " refused";
  }
  for (int i = 0; i < kClients; ++i) {
    clients[static_cast<std::size_t>(i)]->send(rawPost("/v1/tasks", goTo("b-" + std::to_string(i))));
  }
  std::map<int, int> byStatus;
  for (auto& c : clients) {
    const auto response = c->receive("}");
    const int status = statusOf(response);
    ++byStatus[status];
    if (status == 429) {
      EXPECT_THAT(response, HasSubstr("Retry-After: 1"));
    }
  }
  EXPECT_EQ(byStatus[0], 0) << "connections closed or reset without an answer";
  EXPECT_GT(byStatus[201], 0);
  EXPECT_GT(byStatus[429], 0) << "nothing was refused with 429";
  EXPECT_EQ(byStatus[201] + byStatus[429], kClients);
  EXPECT_EQ(gateway_.bodies.size(), static_cast<std::size_t>(byStatus[201])) << "a 429 stored nothing";
}

TEST_F(Intake, ConnectionsBeyondTheLimitAreAnswered503) {
  ApiSettings s;
  s.limits.maxConnections = 3;
  start(s);
  RawClient a(api_->port());
  RawClient b(api_->port());
  RawClient c(api_->port());
  std::this_thread::sleep_for(std::chrono::milliseconds(100));
  RawClient extra(api_->port());
  extra.send("GET /v1/health HTTP/1.1\r\nHost: x\r\n\r\n");
  const auto response = extra.receive("}");
  EXPECT_EQ(statusOf(response), 503) << response;
  EXPECT_THAT(response, HasSubstr("Retry-After: 1"));
  EXPECT_EQ(api_->serverStats().refusedConnections.load(), 1);
}

TEST_F(Intake, AClientPastItsRateGets429WithRetryAfter) {
  ApiSettings s;
  s.limits.ratePerClient = 0.01;  // one request per 100 s once the burst is spent
  s.limits.rateBurst = 3;
  start(s);
  for (int i = 0; i < 3; ++i) {
    EXPECT_EQ(client_->Get("/v1/tasks")->status, 200) << "request " << i << " of the burst";
  }
  auto r = post(kTask);
  ASSERT_EQ(r->status, 429);
  EXPECT_EQ(json::parse(r->body)["error"], "rate_limited");
  EXPECT_GE(std::stoi(r->get_header_value("Retry-After")), 90);
  EXPECT_TRUE(gateway_.bodies.empty());
  EXPECT_EQ(client_->Get("/v1/health")->status, 200) << "the probe is not rate-limited";
}
