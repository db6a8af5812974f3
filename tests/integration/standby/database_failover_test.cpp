// The task database fails over under a running fleet: two fleet managers on a primary PostgreSQL
// and its streaming replica (pg_basebackup -R; synchronous_standby_names '*', so a commit returns,
// and a task is acknowledged, only once the replica has it), given both in one libpq URL with
// target_session_attrs=read-write. Tasks are submitted all along and robots played by the test
// take and finish them; the primary is killed with -9 (every process of it), the replica promoted
// with pg_ctl promote. The managers find the new primary by themselves (one is active again, with
// the next epoch), every acknowledged task is done, and none is lost or done twice (the load
// test's ledger, on the promoted replica's rows).

#include <gtest/gtest.h>
#include <httplib.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fake_robots.hpp"
#include "fleet_stack.hpp"
#include "postgres_server.hpp"
#include "store_contents.hpp"
#include "test_process.hpp"

namespace fs = std::filesystem;
using namespace std::chrono_literals;

namespace {

const std::string kBin = FLEET_BINARY_DIR;

std::optional<int> status(int port, const std::string& path, std::string* body = nullptr) {
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(1s);
  c.set_read_timeout(2s);
  auto r = c.Get(path);
  if (!r) {
    return std::nullopt;
  }
  if (body != nullptr) {
    *body = r->body;
  }
  return r->status;
}

bool has(int port, const std::string& line) {
  std::string body;
  return status(port, "/metrics", &body) == 200 && body.find(line + "\n") != std::string::npos;
}

template <typename Cond>
bool waitUntil(Cond&& cond, std::chrono::seconds within) {
  const auto end = std::chrono::steady_clock::now() + within;
  while (!cond() && std::chrono::steady_clock::now() < end) {
    std::this_thread::sleep_for(50ms);
  }
  return cond();
}

/// Submits tasks f-0001, f-0002, ... one after the other, each until the manager acknowledges it
/// (stored, or duplicate: an earlier attempt stored it), and keeps the acknowledged ids.
class Intake {
 public:
  Intake() = default;
  /// Submits the next task until acknowledged or `wait` passed; true when acknowledged.
  bool submitNext(std::chrono::seconds wait) {
    char id[16];
    std::snprintf(id, sizeof id, "f-%04d", next_ + 1);
    const auto task = fleet::test::transportTask(id, "P-1", "D-1");
    const auto end = std::chrono::steady_clock::now() + wait;
    while (std::chrono::steady_clock::now() < end) {
      auto ack = client_.submit(task, 5s);
      if (ack &&
          (ack->result == fleet::msg::AckResult::Stored || ack->result == fleet::msg::AckResult::Duplicate)) {
        std::lock_guard<std::mutex> lock(mu_);
        ledger_.acknowledged(id);
        ++next_;
        return true;
      }
      if (ack) {
        ++unavailable_;  // the database away: the same request again
      }
      std::this_thread::sleep_for(100ms);
    }
    return false;
  }
  std::size_t acknowledged() {
    std::lock_guard<std::mutex> lock(mu_);
    return ledger_.count();
  }
  fleet::ctl::TaskLedger ledger() {
    std::lock_guard<std::mutex> lock(mu_);
    return ledger_;
  }
  [[nodiscard]] int unavailable() const { return unavailable_; }

 private:
  fleet::test::TaskClient client_;
  std::mutex mu_;
  fleet::ctl::TaskLedger ledger_;
  int next_ = 0;
  std::atomic<int> unavailable_{0};
};

/// The replica streams synchronously: the primary lists it as its synchronous standby.
bool replicaIsSynchronous(const fleet::test::PostgresServer& primary) {
  fleet::pg::Connection c(primary.url());
  auto r = c.exec("replication", "SELECT count(*) FROM pg_stat_replication WHERE sync_state = 'sync'");
  return r && r->rows() == 1 && r->integer(0, 0) == 1;
}

/// The fail-over with the replica promoted `promoteAfter` the kill of the primary; with
/// `newEpoch`, a manager must be active with a later lease epoch afterwards.
void failOver(std::chrono::seconds promoteAfter, bool newEpoch) {
  fleet::test::PostgresServer::Options primaryOptions;
  primaryOptions.synchronousStandbys = "*";
  fleet::test::PostgresServer primary(primaryOptions);
  ASSERT_TRUE(primary.ok()) << "the primary did not start: " << primary.error();
  fleet::test::PostgresServer::Options replicaOptions;
  replicaOptions.replicaOf = &primary;
  fleet::test::PostgresServer replica(replicaOptions);
  ASSERT_TRUE(replica.ok()) << "the replica did not start: " << replica.error();
  ASSERT_TRUE(waitUntil([&] { return replicaIsSynchronous(primary); }, 30s))
      << "the replica is not the primary's synchronous standby; its log:\n"
      << replica.log();

  const auto run = fleet::test::freshRun("fleet-db-failover-");
  const std::string url = fleet::pgserver::PostgresServer::failoverUrl({&primary, &replica});
  // Stations on open floor (no site map): every robot reaches every station.
  std::ofstream(run.dir / "stations.json") << R"({"stations": [
      {"name": "P-1", "x": 2, "y": 1, "kinds": ["pickup"]},
      {"name": "D-1", "x": 8, "y": 1, "kinds": ["dropoff"]},
      {"name": "C-1", "x": 0, "y": 0, "kinds": ["charging", "parking"]}]})";
  std::ofstream(run.dir / "manager.json") << nlohmann::json{
      {"store", url},
      {"stations", (run.dir / "stations.json").string()},
      {"tick_s", 0.05},
      {"lease_s", 2.0}}.dump();
  const std::vector<std::pair<std::string, std::string>> env = {{"FLEET_DDS_DOMAIN", run.domain}};
  const int ops[2] = {fleet::test::freePort(), fleet::test::freePort()};
  std::unique_ptr<fleet::test::ChildProcess> managers[2];
  for (int i = 0; i < 2; ++i) {
    managers[i] = std::make_unique<fleet::test::ChildProcess>(
        kBin + "/services/fleet_manager/fleet_manager",
        std::vector<std::string>{"--config", (run.dir / "manager.json").string(), "--metrics-port",
                                 std::to_string(ops[i]), "--log-level", "warn"},
        env);
  }
  auto activeOne = [&]() -> int {
    for (int i = 0; i < 2; ++i) {
      if (status(ops[i], "/readyz") == 200) {
        return i;
      }
    }
    return -1;
  };
  ASSERT_TRUE(waitUntil([&] { return activeOne() >= 0; }, 30s)) << "no manager became active";

  // Robots played by the test take every task and finish it at once: assignment and completion
  // go on through the fail-over as intake does.
  fleet::transport::Participant robotSide;
  fleet::test::FakeRobots robots(robotSide, 20);
  std::atomic<bool> robotsStop{false};
  std::thread robotsLoop([&] {
    while (!robotsStop) {
      robots.publishStates();
      robots.work();
      std::this_thread::sleep_for(50ms);
    }
  });
  struct Join {
    std::atomic<bool>& stop;
    std::thread& t;
    ~Join() {
      stop = true;
      if (t.joinable()) {
        t.join();
      }
    }
  } joinRobots{robotsStop, robotsLoop};

  Intake intake;
  for (int i = 0; i < 10; ++i) {
    ASSERT_TRUE(intake.submitNext(30s)) << "task " << i + 1 << " before the fail-over";
  }
  // Intake goes on through the fail-over.
  std::atomic<bool> stop{false};
  std::atomic<bool> stuck{false};
  std::thread feeder([&] {
    while (!stop) {
      if (!intake.submitNext(60s)) {
        stuck = true;
        return;
      }
      std::this_thread::sleep_for(5ms);  // within what the robots take
    }
  });
  std::this_thread::sleep_for(1s);
  const std::size_t beforeKill = intake.acknowledged();
  primary.crash();
  const auto killed = std::chrono::steady_clock::now();
  std::this_thread::sleep_for(promoteAfter);
  ASSERT_EQ(replica.promote(), "") << replica.log();
  const double promotedAfter =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();

  // A manager active on the promoted replica (with newEpoch: a later epoch than before, having
  // rebuilt its state from the store as a restarted manager does).
  int active = -1;
  EXPECT_TRUE(waitUntil(
      [&] {
        active = activeOne();
        return active >= 0 && (!newEpoch || (!has(ops[active], "fleet_manager_lease_epoch 1") &&
                                             !has(ops[active], "fleet_manager_lease_epoch 0")));
      },
      30s))
      << "no manager active on the promoted replica";
  const double activeAfter = std::chrono::duration<double>(std::chrono::steady_clock::now() - killed).count();
  const std::size_t atTakeover = intake.acknowledged();
  // Intake resumes: more tasks acknowledged after the fail-over.
  EXPECT_TRUE(waitUntil([&] { return intake.acknowledged() >= atTakeover + 5; }, 30s))
      << "intake did not resume after the fail-over";
  stop = true;
  feeder.join();
  EXPECT_FALSE(stuck) << "a task was not acknowledged within 60 s";
  std::cout << "primary killed after " << beforeKill << " acknowledged tasks; replica promoted after "
            << promotedAfter << " s; a manager active again after " << activeAfter << " s; "
            << intake.acknowledged() << " acknowledged in all, " << intake.unavailable()
            << " answers 'unavailable' while the database was away\n";

  // The robots finish what is left: every acknowledged task done in the store (the promoted
  // replica), then nothing queued or active on the active manager.
  const auto ledger = intake.ledger();
  fleet::ctl::StoreContents store;
  fleet::ctl::Accounting acc;
  EXPECT_TRUE(waitUntil(
      [&] {
        store = fleet::ctl::readPostgresStore(replica.url());
        acc = ledger.reconcile(store.tasks, store.transitions);
        return store.error.empty() && acc.done >= acc.acknowledged;
      },
      60s))
      << "acknowledged tasks left undone after the fail-over: " << acc.acknowledged - acc.done;
  EXPECT_TRUE(waitUntil(
      [&] {
        active = activeOne();
        return active >= 0 && has(ops[active], "fleet_manager_tasks{state=\"queued\"} 0") &&
               has(ops[active], "fleet_manager_tasks{state=\"active\"} 0");
      },
      10s));
  if (active >= 0) {
    EXPECT_TRUE(has(ops[1 - active], "fleet_manager_active 0")) << "exactly one active";
  }
  robotsStop = true;
  robotsLoop.join();

  ASSERT_EQ(store.error, "");
  const auto& [tasks, transitions, error] = store;
  EXPECT_EQ(acc.acknowledged, intake.acknowledged());
  EXPECT_TRUE(acc.lost.empty()) << acc.lost.size() << " acknowledged tasks lost, the first "
                                << acc.lost.front();
  EXPECT_TRUE(acc.duplicated.empty())
      << acc.duplicated.size() << " done more than once, the first " << acc.duplicated.front();
  EXPECT_EQ(acc.done, acc.acknowledged) << "every acknowledged task done, once";
  EXPECT_EQ(tasks.size(), intake.acknowledged() + acc.unacknowledgedKnown);
  std::size_t assigned = 0;
  for (const auto& t : transitions) {
    assigned += t.toState == "assigned" ? 1 : 0;
  }
  std::cout << acc.done << " done, " << assigned << " assignments for " << tasks.size() << " tasks\n";
  for (auto& m : managers) {
    m->kill(SIGTERM);
    EXPECT_EQ(m->wait(10s), 0);
  }
  fs::remove_all(run.dir);
}

// A cluster manager (Patroni) takes longer than the managers' lease (3 s) to decide: the active
// manager's lease lapses while there is no primary, and a manager takes it again on the new one.
TEST(DatabaseFailover, ManagersFollowAPromotedReplicaAndNoAcknowledgedTaskIsLostOrDuplicated) {
  failOver(std::chrono::seconds(4), true);
}

// A promotion within the lease: the active manager may keep its lease (renewed on the new primary
// before it lapsed) or lose it to either manager; either way intake goes on, nothing lost.
TEST(DatabaseFailover, APromotionWithinTheLeaseLosesNothingEither) {
  failOver(std::chrono::seconds(1), false);
}

}  // namespace
