// The managers' lease against a real PostgreSQL server (tests/support/postgres_server.hpp, one per
// suite): one holder at a time, takeover after expiry with a new epoch, the holder's own deadline
// before the database's, release for a clean stop, and fencing of the store's writes.

#include "manager_lease.hpp"

#include <gtest/gtest.h>

#include <thread>

#include "fleet/fleet/errors.hpp"
#include "fleet/fleet/postgres_task_store.hpp"
#include "postgres_server.hpp"

namespace fleet::manager {
namespace {

using namespace std::chrono_literals;

class ManagerLeaseTest : public ::testing::Test {
 public:
  static void TearDownTestSuite() { server_.reset(); }

 protected:
  void SetUp() override {
    if (!server_) {
      server_ = std::make_unique<test::PostgresServer>();
    }
    ASSERT_TRUE(server_->ok()) << "the PostgreSQL test server did not start: " << server_->error();
    url_ = server_->freshUrl();
    ASSERT_TRUE(server_->ok()) << server_->error();
  }
  ManagerLease lease(const std::string& holder, double ttlS) {
    return ManagerLease({url_, "fleet_manager", holder, ttlS});
  }

  static inline std::unique_ptr<test::PostgresServer> server_;
  std::string url_;
};

TEST_F(ManagerLeaseTest, OneHolderAtATime) {
  auto a = lease("a", 5.0);
  auto b = lease("b", 5.0);
  auto got = a.tryAcquire();
  ASSERT_TRUE(got) << got.error().message;
  EXPECT_TRUE(*got);
  EXPECT_EQ(a.epoch(), 1);
  EXPECT_TRUE(a.held());
  auto other = b.tryAcquire();
  ASSERT_TRUE(other) << other.error().message;
  EXPECT_FALSE(*other) << "held by a";
  EXPECT_FALSE(b.held());
  EXPECT_TRUE(*a.renew());
  EXPECT_EQ(a.epoch(), 1) << "a renewal keeps the epoch";
}

TEST_F(ManagerLeaseTest, AStandbyTakesAnExpiredLeaseWithTheNextEpochAndTheOldHolderLosesIt) {
  auto a = lease("a", 0.5);
  auto b = lease("b", 0.5);
  ASSERT_TRUE(*a.tryAcquire());
  EXPECT_FALSE(*b.tryAcquire());
  std::this_thread::sleep_for(600ms);  // a stopped renewing (hung, or killed)
  EXPECT_FALSE(a.held()) << "a's own deadline passed first";
  auto got = b.tryAcquire();
  ASSERT_TRUE(got) << got.error().message;
  EXPECT_TRUE(*got);
  EXPECT_EQ(b.epoch(), 2);
  auto renewed = a.renew();
  ASSERT_TRUE(renewed);
  EXPECT_FALSE(*renewed) << "a lapsed lease is never renewed";
  EXPECT_FALSE(a.held());
}

TEST_F(ManagerLeaseTest, TheHoldersDeadlineComesBeforeTheDatabasesExpiry) {
  auto a = lease("a", 2.0);
  const auto t0 = ManagerLease::Clock::now();
  ASSERT_TRUE(*a.tryAcquire(t0));
  EXPECT_TRUE(a.held(t0 + 1500ms));
  EXPECT_FALSE(a.held(t0 + 1700ms)) << "0.8 of the ttl after the acquisition was sent";
  ASSERT_TRUE(*a.renew(t0 + 1s));
  EXPECT_TRUE(a.held(t0 + 2500ms)) << "renewed at 1 s";
  auto b = lease("b", 2.0);
  EXPECT_FALSE(*b.tryAcquire()) << "the database still has a's lease";
}

TEST_F(ManagerLeaseTest, ReleaseHandsTheLeaseOverAtOnce) {
  auto a = lease("a", 30.0);
  auto b = lease("b", 30.0);
  ASSERT_TRUE(*a.tryAcquire());
  a.release();
  EXPECT_FALSE(a.held());
  ASSERT_TRUE(*b.tryAcquire()) << "no need to wait for 30 s";
  EXPECT_EQ(b.epoch(), 2);
}

TEST_F(ManagerLeaseTest, AnUnreachableDatabaseIsAnErrorAndNotALease) {
  ManagerLease gone(
      {"postgresql:///fleet?host=/nonexistent-fleet-dir&connect_timeout=1", "fleet_manager", "a", 3.0});
  auto got = gone.tryAcquire();
  ASSERT_FALSE(got);
  EXPECT_EQ(got.error().code, errc::kStorage);
  EXPECT_FALSE(gone.held());
}

TEST_F(ManagerLeaseTest, TheOldHoldersStoreWritesAreFencedAfterATakeover) {
  auto storeA = PostgresTaskStore::open({url_});
  ASSERT_TRUE(storeA) << storeA.error().message;
  auto a = lease("a", 0.5);
  ASSERT_TRUE(*a.tryAcquire());
  (*storeA)->fenceWith("fleet_manager", a.epoch());
  Task t;
  t.id = "t1";
  t.kind = TaskKind::Transport;
  t.pickup = "P-1";
  t.dropoff = "D-1";
  ASSERT_TRUE((*storeA)->submit(t, 1));
  std::this_thread::sleep_for(600ms);
  auto b = lease("b", 0.5);
  ASSERT_TRUE(*b.tryAcquire());
  auto late = (*storeA)->transition("t1", TaskState::Assigned, "r1", "allocated", 2);
  ASSERT_FALSE(late) << "a's assignment after b took over";
  EXPECT_EQ(late.error().code, errc::kFenced);
  EXPECT_EQ((*storeA)->get("t1")->state, TaskState::Queued) << "nothing assigned";
}

}  // namespace
}  // namespace fleet::manager
