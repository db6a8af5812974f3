// Hostile clients of the WMS API (reliability findings of 2026-12-02): bodies shaped to multiply
// memory when parsed (a megabyte of '[', deep objects, floods of small numbers) get a 4xx naming
// the limit and leave the peak RSS bounded; a %0d%0a in a path cannot forge an access-log line;
// logging out ends the session on the server.

#include <gmock/gmock.h>
#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <fstream>
#include <sstream>

#include "api_fixture.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using ::testing::HasSubstr;

namespace {

class Hostile : public Api {};

std::string deepObjects(int levels) {
  std::string s;
  for (int i = 0; i < levels; ++i) {
    s += R"({"a":)";
  }
  return s + "1" + std::string(static_cast<std::size_t>(levels), '}');
}

std::string manyNumbers(std::size_t bytes) {
  std::string s = "[1";
  while (s.size() + 3 < bytes) {
    s += ",1";
  }
  return s + "]";
}

/// Peak resident memory of this process (kB) since the last resetPeak().
long peakRssKb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) {
      return std::stol(line.substr(6));
    }
  }
  return -1;
}

void resetPeak() {
  std::ofstream("/proc/self/clear_refs") << "5";  // VmHWM := VmRSS (Linux 4.0+)
}

}  // namespace

TEST_F(Hostile, BodiesShapedToMultiplyMemoryGet4xxNamingTheLimit) {
  start();
  // Beyond the route's own body limit: refused before the body is read.
  auto big = post(std::string(1 << 20, '['));
  ASSERT_TRUE(big);
  EXPECT_EQ(big->status, 413);
  EXPECT_THAT(big->body, HasSubstr("http.max_task_body_bytes"));
  // Within it, refused by the bounded parse before any document is built.
  auto deep = post(std::string(200 * 1024, '['));
  ASSERT_TRUE(deep);
  EXPECT_EQ(deep->status, 413);
  EXPECT_THAT(deep->body, HasSubstr("max_depth"));
  auto objects = post(deepObjects(100));
  EXPECT_EQ(objects->status, 413);
  EXPECT_THAT(objects->body, HasSubstr("max_depth"));
  auto numbers = post(manyNumbers(200 * 1024));
  EXPECT_EQ(numbers->status, 413);
  EXPECT_THAT(numbers->body, HasSubstr("max_elements"));
  auto broken = post("[1,");
  EXPECT_EQ(broken->status, 400);
  EXPECT_EQ(json::parse(broken->body)["error"], "invalid_json");
  // A small task still goes through.
  auto ok = post(R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})");
  EXPECT_EQ(ok->status, 201) << ok->body;
}

TEST_F(Hostile, SixteenHostileBodiesAtOnceKeepThePeakRssBounded) {
  // The worst case the settings allow: a task body as large as any body.
  ApiSettings s;
  s.maxTaskBodyBytes = s.limits.maxBodyBytes;
  start(s);
  const std::string brackets(s.limits.maxBodyBytes - 1024, '[');
  const std::string numbers = manyNumbers(s.limits.maxBodyBytes - 1024);
  resetPeak();
  const long before = peakRssKb();
  ASSERT_GT(before, 0);
  std::vector<std::thread> clients;
  std::atomic<int> refused{0};
  for (int i = 0; i < 16; ++i) {
    clients.emplace_back([&, i] {
      httplib::Client c("127.0.0.1", api_->port());
      c.set_read_timeout(20);
      auto r = c.Post("/v1/tasks", i % 2 == 0 ? brackets : numbers, "application/json");
      refused += r && (r->status == 413 || r->status == 429) ? 1 : 0;
    });
  }
  for (auto& t : clients) {
    t.join();
  }
  EXPECT_EQ(refused, 16);
  // The bound: the 16 bodies in flight (client copies, read buffers, the request) and the small
  // documents the parse may build, well below what a DOM of them would take (~76 MB each before).
  const long grownKb = peakRssKb() - before;
  std::printf("peak RSS grew by %ld kB\n", grownKb);
  EXPECT_LT(grownKb, 160 * 1024) << "peak RSS grew by " << grownKb << " kB";
}

TEST_F(Hostile, AForgedLineInThePathIsEscapedInTheAccessLog) {
  ApiSettings s;
  s.token = "s3cret";  // the request is refused 401, and logged all the same
  start(s);
  metrics::Registry registry;
  api_->instrument(registry);
  std::ostringstream captured;
  auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(captured);
  auto logger = spdlog::default_logger();
  logger->sinks().push_back(sink);
  auto r =
      client_->Get("/v1/tasks/x%0d%0a2026-12-02%20[info]%20access%2010.0.0.9%20admin%20DELETE%20all%20200");
  logger->sinks().pop_back();
  ASSERT_TRUE(r);
  EXPECT_EQ(r->status, 401);
  const std::string text = captured.str();
  EXPECT_THAT(text, HasSubstr("access 127.0.0.1 - GET /v1/tasks/x\\r\\n2026-12-02"));
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 1) << text;
}

TEST_F(Hostile, LoggingOutEndsTheSessionOnTheServer) {
  ApiSettings s;
  s.token = "s3cret";
  start(s);
  auto login = client_->Post("/v1/session", {{"Authorization", "Bearer s3cret"}}, "", "text/plain");
  ASSERT_TRUE(login);
  ASSERT_EQ(login->status, 201);
  const std::string setCookie = login->get_header_value("Set-Cookie");
  const std::string cookie = setCookie.substr(0, setCookie.find(';'));
  const std::string csrf = json::parse(login->body)["csrf"];
  EXPECT_EQ(client_->Get("/v1/session", {{"Cookie", cookie}})->status, 200);
  auto out = client_->Delete("/v1/session", {{"Cookie", cookie}, {kCsrfHeader, csrf}});
  ASSERT_TRUE(out);
  EXPECT_EQ(out->status, 200);
  // A copy of the old cookie (the browser dropped it, someone else kept it) no longer works.
  EXPECT_EQ(client_->Get("/v1/session", {{"Cookie", cookie}})->status, 401);
  EXPECT_EQ(client_->Get("/v1/tasks/t-1", {{"Cookie", cookie}})->status, 401);
  EXPECT_EQ(client_
                ->Post("/v1/tasks", {{"Cookie", cookie}, {kCsrfHeader, csrf}},
                       R"({"id": "t-2", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})",
                       "application/json")
                ->status,
            401);
}

TEST(BrowserSessionTable, IsBoundedAndRevokesOnlyItsOwn) {
  const auto tokens = TokenStore::single("token", "token-a");
  BrowserSessions s(tokens, false, 60, 2);
  const auto a = *s.issue("token", 1000);
  const auto b = *s.issue("token", 1001);
  const auto c = *s.issue("token", 1002);  // the table holds two: the one expiring first goes
  EXPECT_EQ(s.liveSessions(), 2u);
  EXPECT_FALSE(s.check(a, 1002));
  EXPECT_TRUE(s.check(b, 1002));
  EXPECT_TRUE(s.check(c, 1002));
  EXPECT_FALSE(s.revoke("garbage", 1002));
  EXPECT_TRUE(s.revoke(b, 1002));
  EXPECT_FALSE(s.check(b, 1002));
  EXPECT_FALSE(s.revoke(b, 1002)) << "already ended";
  EXPECT_TRUE(s.check(c, 1002));
}
