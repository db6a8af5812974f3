// Webhooks (docs/operator-guide.md#webhooks): subscriptions through the API, URLs checked against
// the allow-list, deliveries signed (HMAC-SHA256 over timestamp and body) and retried with back-off
// until a loopback receiver that fails, is slow and comes back has every event; a receiver that
// never answers is marked failing and holds up no other; the outbox survives an adapter restart.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <fstream>
#include <set>

#include "../fleet/temp_dir.hpp"
#include "api_fixture.hpp"
#include "webhook_receiver.hpp"
#include "webhook_signature.hpp"
#include "webhook_url.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using nlohmann::json;
using ::testing::HasSubstr;

namespace {

msg::TaskEvent ev(const std::string& task, std::uint32_t seq) {
  return {task, msg::TaskState::Assigned, "r1", "", static_cast<std::int64_t>(seq), seq, ""};
}

/// A loopback port that takes connections and never answers (the kernel completes them from
/// the listen backlog; nobody reads).
class BlackHole {
 public:
  BlackHole() {
    fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    ::bind(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    ::listen(fd_, 64);
    socklen_t len = sizeof a;
    ::getsockname(fd_, reinterpret_cast<sockaddr*>(&a), &len);
    port_ = ntohs(a.sin_port);
  }
  ~BlackHole() { ::close(fd_); }
  BlackHole(const BlackHole&) = delete;
  BlackHole& operator=(const BlackHole&) = delete;
  [[nodiscard]] std::string url() const {
    return "http://127.0.0.1:" + std::to_string(port_) + "/hooks/fleet";
  }

 private:
  int fd_ = -1;
  int port_ = 0;
};

class Webhook : public Api {
 protected:
  ApiSettings settings(const std::vector<std::string>& allow) {
    ApiSettings s;
    s.webhooks.allow = allow;
    s.webhooks.timeoutMs = 200;
    s.webhooks.backoffMs = 20;
    s.webhooks.backoffMaxMs = 100;
    s.webhooks.maxAttempts = 10;
    s.webhooks.failingRetryMs = 60'000;
    return s;
  }
  json subscribe(const std::string& url, const std::string& secret = "") {
    json b = {{"url", url}};
    if (!secret.empty()) {
      b["secret"] = secret;
    }
    auto r = client_->Post("/v1/webhooks", b.dump(), "application/json");
    EXPECT_TRUE(r);
    EXPECT_EQ(r->status, 201) << r->body;
    return json::parse(r->body);
  }
  json listed(const std::string& id) {
    auto r = client_->Get("/v1/webhooks/" + id);
    EXPECT_TRUE(r && r->status == 200);
    return json::parse(r->body);
  }
  void restart(ApiSettings s) {
    api_->stop();
    thread_.join();
    spec_.report();
    api_.reset();
    start(std::move(s));
  }
  fleet::test::TempDir dir_;
};

}  // namespace

TEST(WebhookUrl, OnlyHttpUrlsAnEntryOfTheAllowListAdmits) {
  const std::vector<std::string> allow = {"https://wms.example/hooks", "http://127.0.0.1:9000"};
  EXPECT_EQ(refuseWebhookUrl("https://wms.example/hooks", allow), std::nullopt);
  EXPECT_EQ(refuseWebhookUrl("https://WMS.example:443/hooks/fleet?x=1", allow), std::nullopt);
  EXPECT_EQ(refuseWebhookUrl("http://127.0.0.1:9000/anything", allow), std::nullopt);
  for (const std::string bad :
       {"https://wms.example/hooksX", "https://wms.example.evil/hooks", "http://wms.example/hooks",
        "https://wms.example:8443/hooks", "http://127.0.0.1:9001/", "https://user@wms.example/hooks"}) {
    EXPECT_NE(refuseWebhookUrl(bad, allow), std::nullopt) << bad;
  }
  EXPECT_THAT(*refuseWebhookUrl("ftp://wms.example/hooks", allow), HasSubstr("only http and https"));
  EXPECT_THAT(*refuseWebhookUrl("https://wms.example/hooks", {}), HasSubstr("webhooks.allow is empty"));
  EXPECT_THAT(*refuseWebhookUrl("https://wms.example/a b", allow), HasSubstr("space"));
  EXPECT_THAT(*refuseWebhookUrl("http://127.0.0.1:99999/", allow), HasSubstr("port"));
}

TEST(WebhookSignature, IsHmacSha256OverTimestampDotBody) {
  // RFC 4231 test case 2.
  EXPECT_EQ(hmacSha256Hex("Jefe", "what do ya want for nothing?"),
            "5bdcc146bf60754e6a042426089575c75a003f089d2739839dec58b964ec3843");
  EXPECT_EQ(webhookSignature("Jefe", 1700000000, "{}"), "sha256=" + hmacSha256Hex("Jefe", "1700000000.{}"));
  EXPECT_EQ(randomHex(32).size(), 64U);
}

TEST_F(Webhook, SubscriptionsAreMadeListedAndDeletedAndABadUrlIsRefusedNamingTheField) {
  start(settings({"http://127.0.0.1:1/hooks"}));
  auto refused = [&](const std::string& body, const std::string& field) {
    auto r = client_->Post("/v1/webhooks", body, "application/json");
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << body;
    EXPECT_EQ(json::parse(r->body)["fields"][0]["path"], field) << r->body;
  };
  refused(R"({"url": "ftp://127.0.0.1:1/hooks"})", "url");
  refused(R"({"url": "http://127.0.0.1:1/hooksX"})", "url");
  refused(R"({"url": "http://127.0.0.1:2/hooks"})", "url");
  refused(R"({"url": "http://localhost:1/hooks"})", "url");
  refused(R"({"url": 5})", "url");
  refused(R"({})", "url");
  refused(R"({"url": "http://127.0.0.1:1/hooks", "events": ["task"]})", "events");
  refused(R"({"url": "http://127.0.0.1:1/hooks", "secret": "short"})", "secret");
  refused("[", "body");
  const auto made = subscribe("http://127.0.0.1:1/hooks/a", "0123456789abcdef-secret");
  EXPECT_EQ(made["secret"], "0123456789abcdef-secret");
  EXPECT_EQ(made["state"], "active");
  const auto generated = subscribe("http://127.0.0.1:1/hooks/b");
  EXPECT_EQ(generated["secret"].get<std::string>().size(), 64U);
  auto list = json::parse(client_->Get("/v1/webhooks")->body);
  EXPECT_EQ(list["count"], 2);
  EXPECT_FALSE(list["webhooks"][0].contains("secret"));
  EXPECT_EQ(list["webhooks"][0]["url"], "http://127.0.0.1:1/hooks/a");
  EXPECT_EQ(client_->Delete("/v1/webhooks/" + made["id"].get<std::string>())->status, 200);
  EXPECT_EQ(client_->Delete("/v1/webhooks/" + made["id"].get<std::string>())->status, 404);
  EXPECT_EQ(client_->Get("/v1/webhooks/" + made["id"].get<std::string>())->status, 404);
  EXPECT_EQ(json::parse(client_->Get("/v1/webhooks")->body)["count"], 1);
}

TEST_F(Webhook, DeliveriesAreSignedAndRetriedUntilAFailingSlowReceiverComesBack) {
  Receiver rx;
  start(settings({rx.url()}));
  const auto made = subscribe(rx.url());
  const std::string secret = made["secret"];
  // Two failures, one answer too late (after the adapter's 200 ms), then it is back.
  rx.set(Receiver::Mode::Ok, {Receiver::Mode::Fail, Receiver::Mode::Fail, Receiver::Mode::Slow});
  for (std::uint32_t i = 1; i <= 5; ++i) {
    view_.onEvent(ev("t-1", i));
  }
  const auto ids = rx.waitFor(5);
  EXPECT_EQ(ids, (std::set<std::int64_t>{1, 2, 3, 4, 5}));
  EXPECT_GE(rx.attempts(), 8);
  std::int64_t previous = 0;
  for (const auto& g : rx.got()) {
    const auto body = json::parse(g.body);
    EXPECT_EQ(std::to_string(body["event_id"].get<std::int64_t>()), g.eventId);
    EXPECT_EQ(body["type"], "task");
    EXPECT_EQ(body["id"], "t-1");
    EXPECT_EQ(g.webhook, made["id"]);
    EXPECT_EQ(g.signature, "sha256=" + hmacSha256Hex(secret, g.timestamp + "." + g.body));
    if (!g.late) {
      EXPECT_GT(std::stoll(g.eventId), previous) << "in event-id order, each once when answered in time";
      previous = std::stoll(g.eventId);
    }
  }
  // The event answered too late came again: at least once, de-duplicated by its id.
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (rx.got().size() < 6 && std::chrono::steady_clock::now() < until) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  const auto got = rx.got();
  EXPECT_EQ(std::count_if(got.begin(), got.end(), [](const auto& g) { return g.eventId == "1"; }), 2);
  EXPECT_EQ(std::count_if(got.begin(), got.end(), [](const auto& g) { return g.late; }), 1);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  json w;
  do {
    w = listed(made["id"]);
  } while (w["delivered_through"] != 5 && std::chrono::steady_clock::now() < deadline);
  EXPECT_EQ(w["delivered_through"], 5);
  EXPECT_EQ(w["pending"], 0);
  EXPECT_EQ(w["state"], "active");
  EXPECT_EQ(w["failures"], 0);
  EXPECT_THAT(w["last_error"].get<std::string>(), HasSubstr("no answer"));
}

TEST_F(Webhook, AReceiverThatNeverAnswersIsMarkedFailingAndHoldsUpNoOther) {
  Receiver good;
  BlackHole dead;
  auto s = settings({good.url(), dead.url()});
  s.webhooks.maxAttempts = 3;
  start(s);
  const auto bad = subscribe(dead.url());
  subscribe(good.url());
  for (std::uint32_t i = 1; i <= 20; ++i) {
    view_.onEvent(ev("t-" + std::to_string(i), 1));
  }
  EXPECT_EQ(good.waitFor(20).size(), 20U);
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(5);
  json w;
  do {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
    w = listed(bad["id"]);
  } while (w["state"] != "failing" && std::chrono::steady_clock::now() < deadline);
  EXPECT_EQ(w["state"], "failing");
  EXPECT_EQ(w["failures"], 3) << "bounded: tried again only every failing_retry_ms";
  EXPECT_EQ(w["delivered_through"], 0);
  EXPECT_EQ(w["pending"], 20);
  EXPECT_THAT(w["last_error"].get<std::string>(), HasSubstr("no answer"));
  // The adapter stops at once although a delivery is stuck (each attempt is bounded).
  const auto t0 = std::chrono::steady_clock::now();
  api_->stop();
  thread_.join();
  api_.reset();
  EXPECT_LT(std::chrono::steady_clock::now() - t0, std::chrono::seconds(2));
}

TEST_F(Webhook, TheOutboxSurvivesAnAdapterRestart) {
  Receiver rx;
  auto s = settings({rx.url()});
  s.events.path = dir_.file("events.db");
  start(s);
  rx.set(Receiver::Mode::Fail);
  const auto made = subscribe(rx.url());
  view_.onEvent(ev("t-1", 1));
  view_.onEvent(ev("t-1", 2));
  view_.onEvent(ev("t-1", 3));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  ASSERT_TRUE(rx.got().empty());
  restart(s);
  rx.set(Receiver::Mode::Ok);
  view_.onEvent(ev("t-1", 4));
  EXPECT_EQ(rx.waitFor(4), (std::set<std::int64_t>{1, 2, 3, 4}));
  const auto list = json::parse(client_->Get("/v1/webhooks")->body);
  ASSERT_EQ(list["count"], 1);
  EXPECT_EQ(list["webhooks"][0]["id"], made["id"]);
}

// Scope-checked as the other routes: a read token lists, only a submit token makes or deletes.
TEST_F(Webhook, AReadTokenListsButOnlyASubmitTokenMakesOrDeletes) {
  const std::string tokens = dir_.file("tokens");
  std::ofstream(tokens) << "# name scopes token\nreader read reader-token-0123456789abcdef\n"
                           "wms read,submit wms-token-0123456789abcdef0123\n";
  auto s = settings({"http://127.0.0.1:1/hooks"});
  s.tokenFile = tokens;
  start(s);
  const httplib::Headers reader = {{"Authorization", "Bearer reader-token-0123456789abcdef"}};
  const httplib::Headers wms = {{"Authorization", "Bearer wms-token-0123456789abcdef0123"}};
  const std::string body = R"({"url": "http://127.0.0.1:1/hooks"})";
  EXPECT_EQ(client_->Post("/v1/webhooks", body, "application/json")->status, 401);
  auto r = client_->Post("/v1/webhooks", reader, body, "application/json");
  EXPECT_EQ(r->status, 403);
  EXPECT_THAT(r->body, HasSubstr("submit"));
  r = client_->Post("/v1/webhooks", wms, body, "application/json");
  ASSERT_EQ(r->status, 201) << r->body;
  const std::string id = json::parse(r->body)["id"];
  EXPECT_EQ(client_->Get("/v1/webhooks", reader)->status, 200);
  EXPECT_EQ(client_->Get("/v1/webhooks/" + id, reader)->status, 200);
  EXPECT_EQ(client_->Delete("/v1/webhooks/" + id, reader)->status, 403);
  EXPECT_EQ(client_->Delete("/v1/webhooks/" + id, wms)->status, 200);
}
