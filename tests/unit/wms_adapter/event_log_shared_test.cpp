// The event log and the webhook subscriptions on PostgreSQL, shared by adapter replicas
// (postgres_event_store.hpp, webhook_store.hpp): a transition heard by two replicas is logged once,
// both serve the same ids in the same order, a reopened log keeps its ids, retention says what is
// gone, concurrent appends never show a reader an id below one it has already seen; a subscription
// made on one replica is listed and delivered by either, one at a time, and the other takes over
// the deliveries when the first one dies. Against a PostgreSQL server the test starts itself.

#include <gtest/gtest.h>

#include <httplib.h>

#include <atomic>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "event_log.hpp"
#include "postgres_event_store.hpp"
#include "postgres_server.hpp"
#include "webhook_receiver.hpp"
#include "webhook_store.hpp"
#include "webhooks.hpp"

using namespace fleet;
using namespace fleet::wms;

namespace {

msg::TaskEvent ev(const std::string& task, std::uint32_t seq,
                  msg::TaskState state = msg::TaskState::Assigned) {
  return {task, state, "r1", "", static_cast<std::int64_t>(seq) * 1000, seq, ""};
}

std::vector<std::pair<std::int64_t, std::string>> rows(const EventLog& log) {
  std::vector<std::pair<std::int64_t, std::string>> out;
  for (const auto& l : log.after(0, 1000)) {
    out.emplace_back(l.id, l.event.task_id + "#" + std::to_string(l.event.seq));
  }
  return out;
}

std::unique_ptr<EventLog> open(const std::string& url, EventLogSettings s = {}) {
  s.path = url;
  return std::make_unique<EventLog>(s, std::make_unique<PostgresEventStore>(url));
}

class SharedEventLog : public ::testing::Test {
 protected:
  static void SetUpTestSuite() { server_ = new test::PostgresServer(); }
  static void TearDownTestSuite() {
    delete server_;
    server_ = nullptr;
  }
  void SetUp() override { ASSERT_TRUE(server_->ok()) << server_->error(); }
  static test::PostgresServer* server_;
};
test::PostgresServer* SharedEventLog::server_ = nullptr;

TEST_F(SharedEventLog, TwoReplicasLogATransitionOnceAndServeTheSameIds) {
  const std::string url = server_->freshUrl();
  auto a = open(url);
  auto b = open(url);
  EXPECT_TRUE(a->shared());
  EXPECT_TRUE(a->durable());
  // Both hear t1#1; each hears one the other does not.
  EXPECT_EQ(a->append({ev("t1", 1), ev("t2", 1)}, 1'000), 2u);
  EXPECT_EQ(b->append({ev("t1", 1)}, 1'000), 2u);  // none new, but it now has both of a's
  EXPECT_EQ(b->append({ev("t3", 1)}, 1'000), 1u);
  a->catchUp();
  const auto expected =
      std::vector<std::pair<std::int64_t, std::string>>{{1, "t1#1"}, {2, "t2#1"}, {3, "t3#1"}};
  EXPECT_EQ(rows(*a), expected);
  EXPECT_EQ(rows(*b), expected);
  EXPECT_EQ(a->lastId(), 3);
  EXPECT_EQ(b->lastId(), 3);
  // seq 0 is always new (the manager never sends it; a hand-made event might).
  a->append({ev("t4", 0), ev("t4", 0)}, 1'000);
  EXPECT_EQ(a->lastId(), 5);
}

TEST_F(SharedEventLog, TheOtherReplicasRowsReachTheListenerAndWakeTheStream) {
  const std::string url = server_->freshUrl();
  auto a = open(url);
  auto b = open(url);
  std::atomic<int> heard{0};
  b->onCatchUp([&](const std::vector<LoggedEvent>& rows) { heard += static_cast<int>(rows.size()); });
  a->append({ev("t1", 1), ev("t1", 2)}, 1'000);
  // b's own thread takes them (four times a second); its stream wakes.
  EXPECT_TRUE(b->waitAfter(0, std::chrono::seconds(5)));
  // The thread moves lastId() before it calls the listener: wait for both.
  for (int i = 0; i < 100 && (b->lastId() < 2 || heard.load() < 2); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(b->lastId(), 2);
  EXPECT_EQ(heard.load(), 2);
  // Rows of a's that b takes with an append of its own reach the listener too (its thread will
  // not see them again).
  a->append({ev("t2", 1)}, 1'000);
  b->append({ev("t3", 1)}, 1'000);
  EXPECT_EQ(b->lastId(), 4);
  for (int i = 0; i < 100 && heard.load() < 4; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_GE(heard.load(), 4);
}

TEST_F(SharedEventLog, AReopenedLogKeepsItsIdsAndRetentionSaysWhatIsGone) {
  const std::string url = server_->freshUrl();
  EventLogSettings s;
  s.retainEvents = 3;
  {
    auto a = open(url, s);
    for (std::uint32_t i = 1; i <= 5; ++i) {
      a->append({ev("t1", i)}, 1'000);
    }
  }
  auto again = open(url, s);
  EXPECT_EQ(again->lastId(), 5);
  again->append({ev("t1", 3)}, 1'000);  // heard before, still held: not logged again
  EXPECT_EQ(again->lastId(), 5);
  again->append({ev("t1", 6)}, 2'000'000'000);  // a second later: retention runs
  EXPECT_EQ(again->lastId(), 6);
  EXPECT_EQ(again->prunedThrough(), 3);
  const auto held = again->after(0, 100);
  ASSERT_EQ(held.size(), 3u);
  EXPECT_EQ(held.front().id, 4);
  // By age: everything logged before the cut goes; the ids are not given again.
  EventLogSettings aged = s;
  aged.retainSeconds = 1;
  auto old = open(url, aged);
  old->append({ev("t2", 1)}, 100'000'000'000);
  EXPECT_EQ(old->lastId(), 7);
  EXPECT_EQ(old->prunedThrough(), 6);
}

TEST_F(SharedEventLog, ConcurrentAppendsNeverShowAReaderAnIdBelowOneItHasSeen) {
  const std::string url = server_->freshUrl();
  auto a = open(url);
  auto b = open(url);
  auto reader = open(url);
  std::atomic<bool> done{false};
  std::vector<std::thread> writers;
  for (auto* log : {a.get(), b.get()}) {
    writers.emplace_back([log, name = log == a.get() ? "a" : "b"] {
      for (std::uint32_t i = 1; i <= 200; ++i) {
        log->append({ev(std::string(name) + std::to_string(i % 7), i)}, 1'000);
      }
    });
  }
  std::int64_t seen = 0;
  std::size_t taken = 0;
  bool ordered = true;
  std::thread watcher([&] {
    while (!done) {
      reader->catchUp();
      for (const auto& l : reader->after(seen, 1000)) {
        ordered = ordered && l.id > seen;
        seen = l.id;
        ++taken;
      }
    }
  });
  for (auto& w : writers) {
    w.join();
  }
  done = true;
  watcher.join();
  reader->catchUp();
  for (const auto& l : reader->after(seen, 1000)) {
    seen = l.id;
    ++taken;
  }
  EXPECT_TRUE(ordered);
  EXPECT_EQ(taken, 400u);  // every row, none skipped by a late commit
  a->catchUp();
  b->catchUp();
  EXPECT_EQ(rows(*a), rows(*b));
  EXPECT_EQ(rows(*a), rows(*reader));
}

TEST_F(SharedEventLog, AnUnreachableDatabaseIsAnErrorNamingItWithoutThePassword) {
  try {
    PostgresEventStore store("postgresql://fleet:secret@/postgres?host=/nonexistent-dir&connect_timeout=1");
    FAIL() << "opened";
  } catch (const std::runtime_error& e) {
    EXPECT_EQ(std::string(e.what()).find("secret"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("nonexistent-dir"), std::string::npos) << e.what();
  }
}

/// An adapter replica's status push: its event log and webhooks on the shared database.
struct Replica {
  std::unique_ptr<EventLog> log;
  std::unique_ptr<Webhooks> hooks;
  explicit Replica(const std::string& url) : log(open(url)) {
    WebhookSettings w;
    w.backoffMs = 50;
    hooks = std::make_unique<Webhooks>(w, std::make_unique<PostgresWebhookStore>(url), *log);
  }
  ~Replica() {
    hooks->stop();
    hooks.reset();
  }
};

}  // namespace

TEST_F(SharedEventLog, ASubscriptionIsDeliveredByOneReplicaAndTakenOverWhenItDies) {
  const std::string url = server_->freshUrl();
  fleet::wms::testing::Receiver rx;
  auto a = std::make_unique<Replica>(url);
  Replica b(url);
  const auto made = a->hooks->create(rx.url(), "", 1'000);
  ASSERT_TRUE(made);
  const std::string id = made->status.id;
  // b lists it within its next look (once a second), and removing an unknown one is refused.
  for (int i = 0; i < 150 && !b.hooks->find(id); ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(b.hooks->find(id));
  EXPECT_FALSE(b.hooks->remove("wh-none"));
  // Events heard by both: each delivered, by one replica at a time.
  for (std::uint32_t i = 1; i <= 5; ++i) {
    a->log->append({ev("t1", i)}, 1'000);
    b.log->append({ev("t1", i)}, 1'000);
  }
  ASSERT_EQ(rx.waitFor(5).size(), 5u);
  // a dies: b takes the deliveries over once a's lease has run out, from the stored cursor.
  a.reset();
  for (std::uint32_t i = 6; i <= 8; ++i) {
    b.log->append({ev("t1", i)}, 1'000);
  }
  // The lease (5 s) runs out first.
  std::set<std::int64_t> ids;
  for (int i = 0; i < 3 && ids.size() < 8; ++i) {
    ids = rx.waitFor(8);
  }
  ASSERT_EQ(ids.size(), 8u);
  const auto got = rx.timesById();
  for (std::int64_t e = 1; e <= 8; ++e) {
    EXPECT_EQ(got.count(e), 1u) << "event " << e;
  }
  for (const auto& [e, n] : got) {
    EXPECT_EQ(n, 1) << "event " << e << " delivered " << n << " times";
  }
  // The cursor is stored once the receiver has answered, a moment after it has the event: under
  // load the status may still say 7 when the receiver already holds 8.
  auto status = b.hooks->find(id);
  for (int i = 0; i < 250 && status && status->deliveredThrough < 8; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    status = b.hooks->find(id);
  }
  ASSERT_TRUE(status);
  EXPECT_EQ(status->deliveredThrough, 8);
  // Removed through b: gone from the store.
  EXPECT_TRUE(b.hooks->remove(id));
  Replica c(url);
  EXPECT_TRUE(c.hooks->list().empty());
}

// Replicas start together: each creates the tables it needs when missing. Every one of them must
// open on a fresh database, however their CREATE statements interleave (a lock released before the
// creation committed once let the second replica fail with PostgreSQL's duplicate pg_type row).
TEST_F(SharedEventLog, ReplicasStartingTogetherAllOpenTheirTables) {
  constexpr int kRounds = 6;
  constexpr int kReplicas = 6;
  for (int round = 0; round < kRounds; ++round) {
    const std::string url = server_->freshUrl();
    std::atomic<int> ready{0};
    std::mutex m;
    std::vector<std::string> errors;
    std::vector<std::thread> replicas;
    for (int i = 0; i < kReplicas; ++i) {
      replicas.emplace_back([&] {
        ready.fetch_add(1);
        while (ready.load() < kReplicas) {
          std::this_thread::yield();
        }
        try {
          PostgresWebhookStore hooks(url);
          PostgresEventStore events(url);
          (void)hooks.load();
        } catch (const std::exception& e) {
          std::lock_guard lock(m);
          errors.emplace_back(e.what());
        }
      });
    }
    for (auto& t : replicas) {
      t.join();
    }
    EXPECT_TRUE(errors.empty()) << "round " << round << ": " << errors.front();
  }
}
