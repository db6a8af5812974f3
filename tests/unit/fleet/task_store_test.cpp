// Every TaskStore backend passes one suite (TaskStoreTest, parameterised by backend; the fixture is
// task_store_fixture.hpp, and the changes of priority and deadline are in task_change_test.cpp).
// Backend-specific cases follow the suite.

#include <gtest/gtest.h>
#include <sqlite3.h>

#include <set>
#include <thread>

#include "task_store_fixture.hpp"

namespace fleet {
namespace {

using store_test::Backend;
using store_test::numbered;
using store_test::TaskStoreTest;
using store_test::transport;
using S = TaskState;

/// The tables of schema version 1 (before `paused`).
constexpr const char* kSchemaV1 = R"sql(
CREATE TABLE tasks(id TEXT PRIMARY KEY, kind TEXT NOT NULL, body TEXT NOT NULL, state TEXT NOT NULL,
  robot TEXT NOT NULL DEFAULT '', attempts INTEGER NOT NULL DEFAULT 0, reason TEXT NOT NULL DEFAULT '',
  created_ns INTEGER NOT NULL, updated_ns INTEGER NOT NULL, revision INTEGER NOT NULL) WITHOUT ROWID;
CREATE TABLE transitions(seq INTEGER PRIMARY KEY AUTOINCREMENT, task_id TEXT NOT NULL, from_state TEXT,
  to_state TEXT NOT NULL, robot TEXT NOT NULL DEFAULT '', reason TEXT NOT NULL DEFAULT '', stamp_ns INTEGER NOT NULL);
)sql";

/// A database file as an older manager left it: `sql` run on a fresh file.
void writeDatabase(const std::string& path, const std::string& sql) {
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open(path.c_str(), &db), SQLITE_OK);
  EXPECT_EQ(sqlite3_exec(db, sql.c_str(), nullptr, nullptr, nullptr), SQLITE_OK) << sqlite3_errmsg(db);
  sqlite3_close(db);
}

std::unique_ptr<SqliteTaskStore> openStore(const std::string& path) {
  auto s = SqliteTaskStore::open({path});
  EXPECT_TRUE(s) << s.error().message;
  return std::move(s).value();
}

INSTANTIATE_TEST_SUITE_P(Backends, TaskStoreTest, ::testing::Values(Backend::Sqlite, Backend::Postgres),
                         [](const auto& p) { return p.param == Backend::Sqlite ? "sqlite" : "postgresql"; });

TEST_P(TaskStoreTest, RecordsItsSchemaVersionAndRefusesANewerOne) {
  ASSERT_TRUE(open());
  EXPECT_EQ(schemaVersion(), 4);
  ASSERT_TRUE(open()) << "opened again as it is";
  setSchemaVersion(9);
  auto s = tryOpen();
  ASSERT_FALSE(s) << "a schema newer than the binary";
  EXPECT_EQ(s.error().code, errc::kSchemaNewer);
  EXPECT_NE(s.error().message.find("schema version 9"), std::string::npos) << s.error().message;
  EXPECT_NE(s.error().message.find("version 4"), std::string::npos) << s.error().message;
  EXPECT_EQ(schemaVersion(), 9) << "left as it was";
}

TEST_P(TaskStoreTest, PausedFlagIsDurableAndRefusedOnFinishedTasks) {
  {
    auto store = open();
    ASSERT_TRUE(store->submit(transport("t1"), 1));
    ASSERT_TRUE(store->transition("t1", S::Assigned, "r1", "", 2));
    auto p = store->setPaused("t1", true, 3);
    ASSERT_TRUE(p) << p.error().message;
    EXPECT_TRUE(p->paused);
    EXPECT_EQ(p->state, S::Assigned);
    EXPECT_EQ(p->revision, 3) << "not a transition, but an event of the task's: the revision counts it";
    EXPECT_EQ(store->history("t1")->size(), 2u) << "not a transition";
    EXPECT_EQ(store->setPaused("t1", true, 3)->revision, 3) << "unchanged: no event, no count";
    // A transition keeps the flag.
    EXPECT_TRUE(store->transition("t1", S::EnRoute, "r1", "", 4)->paused);
    EXPECT_EQ(store->setPaused("nope", true, 5).error().code, errc::kNotFound);
  }
  auto store = open();
  EXPECT_TRUE(store->get("t1")->paused);
  EXPECT_TRUE(store->openTasks()->front().paused);
  ASSERT_TRUE(store->setPaused("t1", false, 6));
  EXPECT_FALSE(store->get("t1")->paused);
  ASSERT_TRUE(store->transition("t1", S::Cancelled, "", "", 7));
  EXPECT_EQ(store->setPaused("t1", true, 8).error().code, errc::kIllegalTransition);
}

TEST(SqliteTaskStore, OpensAVersionOneDatabaseAddingThePausedColumn) {
  // The schema before `paused` (user_version 1), with one task in it.
  test::TempDir dir;
  const std::string path = dir.file("v1.db");
  writeDatabase(path, std::string(kSchemaV1) + R"sql(
INSERT INTO tasks VALUES('old', 'goto', '{"id":"old","kind":"goto","station":"D-1"}', 'queued', '', 0, '', 5, 5, 1);
PRAGMA user_version = 1;
)sql");
  auto store = openStore(path);
  auto old = store->get("old");
  ASSERT_TRUE(old) << old.error().message;
  EXPECT_FALSE(old->paused);
  ASSERT_TRUE(store->setPaused("old", true, 6));
  store.reset();
  EXPECT_TRUE(openStore(path)->get("old")->paused) << "migrated once, then used as version 2";
}

TEST_P(TaskStoreTest, AChosenStationIsStoredWithTheAssignmentAndDroppedOnRequeue) {
  Task park;
  park.id = "park-1";
  park.kind = TaskKind::Park;
  {
    auto store = open();
    ASSERT_TRUE(store->submit(park, 1));
    ASSERT_TRUE(store->submit(transport("t1"), 1));
    auto a = store->transition({"park-1", S::Assigned, "r1", "allocated", 2, "K-2"});
    ASSERT_TRUE(a) << a.error().message;
    EXPECT_EQ(a->task.station, "K-2");
    EXPECT_TRUE(a->stationChosen);
    EXPECT_EQ(store->transition({"t1", S::Assigned, "r2", "", 2, "K-2"}).error().code, errc::kInvalid)
        << "only charge and park tasks get a station chosen";
  }
  auto store = open();  // a restart
  const auto got = store->get("park-1");
  ASSERT_TRUE(got);
  EXPECT_EQ(got->task.station, "K-2");
  EXPECT_TRUE(got->stationChosen);
  EXPECT_EQ(store->openTasks()->front().task.station, "K-2");
  const auto retry = store->submit(park, 3);
  ASSERT_TRUE(retry) << retry.error().message;
  EXPECT_FALSE(retry->created) << "the request as sent is the same request";
  // Back in the queue: the choice goes; the next assignment chooses again.
  auto rq = store->transition("park-1", S::Requeued, "", "robot r1 lost", 4);
  ASSERT_TRUE(rq);
  EXPECT_TRUE(rq->task.station.empty());
  EXPECT_FALSE(rq->stationChosen);
  EXPECT_TRUE(store->get("park-1")->task.station.empty());
  // Why it waits is stored without a transition, and only for a waiting task.
  auto w = store->setWaitReason("park-1", "waiting for a free parking station", 5);
  ASSERT_TRUE(w) << w.error().message;
  EXPECT_EQ(store->get("park-1")->reason, "waiting for a free parking station");
  EXPECT_EQ(store->history("park-1")->size(), 3u) << "not a transition";
  EXPECT_EQ(w->revision, 4) << "but an event of the task's: the revision counts it";
  EXPECT_EQ(store->get("park-1")->revision, 4);
  ASSERT_TRUE(store->transition({"park-1", S::Assigned, "r3", "allocated", 6, "K-1"}));
  EXPECT_EQ(store->setWaitReason("park-1", "x", 7).error().code, errc::kIllegalTransition);
  ASSERT_TRUE(store->transition("park-1", S::EnRoute, "r3", "", 8));
  ASSERT_TRUE(store->transition("park-1", S::Done, "r3", "", 9));
  EXPECT_EQ(store->get("park-1")->task.station, "K-1") << "a finished task keeps where it went";
}

TEST(SqliteTaskStore, OpensAVersionTwoDatabaseAddingTheStationColumn) {
  test::TempDir dir;
  const std::string path = dir.file("v2.db");
  // Version 2 as the migration left it: version 1 plus `paused`.
  writeDatabase(path, std::string(kSchemaV1) + R"sql(
ALTER TABLE tasks ADD COLUMN paused INTEGER NOT NULL DEFAULT 0;
INSERT INTO tasks VALUES('old', 'park', '{"id":"old","kind":"park"}', 'queued', '', 0, '', 5, 5, 1, 1);
PRAGMA user_version = 2;
)sql");
  {
    auto store = openStore(path);
    const auto old = store->get("old");
    ASSERT_TRUE(old) << old.error().message;
    EXPECT_TRUE(old->paused);
    EXPECT_FALSE(old->stationChosen);
    ASSERT_TRUE(store->transition({"old", S::Assigned, "r1", "", 6, "K-1"}));
  }
  EXPECT_EQ(openStore(path)->get("old")->task.station, "K-1") << "migrated once, then used as version 3";
}

TEST(SqliteTaskStore, OpensAVersionThreeDatabaseAddingThePriorityAndDeadlineColumns) {
  test::TempDir dir;
  const std::string path = dir.file("v3.db");
  // Version 3 as the migrations left it: version 1 plus `paused` and `station`.
  writeDatabase(path, std::string(kSchemaV1) + R"sql(
ALTER TABLE tasks ADD COLUMN paused INTEGER NOT NULL DEFAULT 0;
ALTER TABLE tasks ADD COLUMN station TEXT NOT NULL DEFAULT '';
INSERT INTO tasks VALUES('old', 'goto', '{"id":"old","kind":"goto","priority":3,"station":"D-1"}', 'queued', '',
  0, '', 5, 5, 1, 0, '');
PRAGMA user_version = 3;
)sql");
  {
    auto store = openStore(path);
    const auto old = store->get("old");
    ASSERT_TRUE(old) << old.error().message;
    EXPECT_EQ(old->task.priority, 3) << "as submitted";
    EXPECT_FALSE(old->submitted);
    ASSERT_TRUE(store->change({"old", 9, std::nullopt, 6}));
  }
  const auto got = openStore(path)->get("old");
  EXPECT_EQ(got->task.priority, 9) << "migrated once, then used as version 4";
  EXPECT_EQ(got->submitted->priority, 3);
}

TEST_P(TaskStoreTest, SubmitIsIdempotentAndDetectsConflicts) {
  auto store = open();
  auto first = store->submit(transport("t1"), 100);
  ASSERT_TRUE(first) << first.error().message;
  EXPECT_TRUE(first->created);
  EXPECT_EQ(first->record.state, S::Queued);
  EXPECT_EQ(first->record.task.createdNs, 100) << "created_ns defaults to the submit stamp";
  EXPECT_EQ(first->record.revision, 1);

  auto again = store->submit(transport("t1"), 200);
  ASSERT_TRUE(again);
  EXPECT_FALSE(again->created);
  EXPECT_EQ(again->record.task.createdNs, 100) << "the retry returns the original record";

  Task withStamp = transport("t1");
  withStamp.createdNs = 555;
  auto sameBody = store->submit(withStamp, 300);
  ASSERT_TRUE(sameBody) << "created_ns is not part of the body";
  EXPECT_FALSE(sameBody->created);

  auto conflict = store->submit(transport("t1", 7), 300);
  ASSERT_FALSE(conflict);
  EXPECT_EQ(conflict.error().code, errc::kConflict);

  Task bad = transport("t 2");
  auto invalid = store->submit(bad, 300);
  ASSERT_FALSE(invalid);
  EXPECT_EQ(invalid.error().code, errc::kInvalid);
  EXPECT_EQ(store->get("t 2").error().code, errc::kNotFound);
}

TEST_P(TaskStoreTest, TransitionsFollowTheStateMachine) {
  auto store = open();
  ASSERT_TRUE(store->submit(transport("t1"), 1));
  EXPECT_EQ(store->transition("t1", S::EnRoute, "r1", "", 2).error().code, errc::kIllegalTransition);
  EXPECT_EQ(store->transition("t1", S::Assigned, "", "", 2).error().code, errc::kInvalid);
  EXPECT_EQ(store->transition("nope", S::Assigned, "r1", "", 2).error().code, errc::kNotFound);

  auto a = store->transition("t1", S::Assigned, "r1", "allocated", 3);
  ASSERT_TRUE(a) << a.error().message;
  EXPECT_EQ(a->robotId, "r1");
  EXPECT_EQ(a->attempts, 1);
  EXPECT_EQ(store->transition("t1", S::EnRoute, "r2", "", 4).error().code, errc::kWrongRobot);
  ASSERT_TRUE(store->transition("t1", S::EnRoute, "r1", "", 4));
  EXPECT_EQ(store->transition("t1", S::Done, "r1", "", 5).error().code, errc::kIllegalTransition)
      << "a transport task must load and unload";
  auto rq = store->transition("t1", S::Requeued, "", "robot lost", 6);
  ASSERT_TRUE(rq);
  EXPECT_TRUE(rq->robotId.empty());
  auto again = store->transition("t1", S::Assigned, "r2", "", 7);
  ASSERT_TRUE(again);
  EXPECT_EQ(again->attempts, 2);
  for (auto s : {S::EnRoute, S::Loading, S::Delivering, S::Unloading, S::Done}) {
    ASSERT_TRUE(store->transition("t1", s, "r2", "", 8)) << toString(s);
  }
  auto done = store->get("t1");
  ASSERT_TRUE(done);
  EXPECT_EQ(done->state, S::Done);
  EXPECT_EQ(done->revision, 10);
  EXPECT_EQ(store->transition("t1", S::Cancelled, "", "", 9).error().code, errc::kIllegalTransition);

  auto h = store->history("t1");
  ASSERT_TRUE(h);
  ASSERT_EQ(h->size(), 10u);
  EXPECT_FALSE(h->front().from.has_value());
  for (std::size_t i = 1; i < h->size(); ++i) {
    EXPECT_EQ((*h)[i].from, (*h)[i - 1].to);
    EXPECT_GT((*h)[i].seq, (*h)[i - 1].seq);
  }
  EXPECT_EQ((*h)[3].reason, "robot lost");
  EXPECT_EQ((*h)[3].robotId, "r1") << "the log keeps who held the task";
}

// A robot's error that was not UTF-8 was stored as it came, and every reader that made
// JSON of the record threw, across restarts. Reasons are repaired when read back.
TEST_P(TaskStoreTest, ReasonsThatAreNotUtf8AreRepairedWhenRead) {
  {
    auto store = open();
    ASSERT_TRUE(store->submit(transport("t1"), 1));
    ASSERT_TRUE(store->transition("t1", S::Assigned, "r1", "", 2));
    ASSERT_TRUE(store->transition("t1", S::Requeued, "", "motor \xFF fault", 3));
  }
  auto store = open();
  EXPECT_EQ(store->get("t1")->reason, "motor \xEF\xBF\xBD fault");
  EXPECT_EQ(store->openTasks()->front().reason, "motor \xEF\xBF\xBD fault");
  EXPECT_EQ(store->history("t1")->back().reason, "motor \xEF\xBF\xBD fault");
  EXPECT_NO_THROW((void)toJson(*store->get("t1")).dump());
}

TEST_P(TaskStoreTest, PinnedTaskOnlyForItsRobot) {
  auto store = open();
  Task c;
  c.id = "charge-r1";
  c.kind = TaskKind::Charge;
  c.robot = "r1";
  ASSERT_TRUE(store->submit(c, 1));
  EXPECT_EQ(store->transition("charge-r1", S::Assigned, "r2", "", 2).error().code, errc::kWrongRobot);
  EXPECT_TRUE(store->transition("charge-r1", S::Assigned, "r1", "", 2));
  EXPECT_TRUE(store->transition("charge-r1", S::EnRoute, "r1", "", 3));
  EXPECT_TRUE(store->transition("charge-r1", S::Done, "r1", "", 4));
}

TEST_P(TaskStoreTest, BatchesAreIndependentItemsInOneCommit) {
  auto store = open();
  ASSERT_TRUE(store->submit(transport("old"), 1));
  auto rs = store->submitBatch(
      {transport("a"), transport("old"), transport("old", 3), transport("a"), transport("b")}, 10);
  ASSERT_EQ(rs.size(), 5u);
  EXPECT_TRUE(rs[0] && rs[0]->created);
  EXPECT_TRUE(rs[1] && !rs[1]->created);
  ASSERT_FALSE(rs[2]);
  EXPECT_EQ(rs[2].error().code, errc::kConflict);
  EXPECT_TRUE(rs[3] && !rs[3]->created) << "a repeat inside the batch is a retry of the first";
  EXPECT_TRUE(rs[4] && rs[4]->created);

  auto ts = store->transitionBatch({{"a", S::Assigned, "r1", "", 11, {}},
                                    {"a", S::EnRoute, "r1", "", 12, {}},
                                    {"b", S::EnRoute, "r1", "", 12, {}},
                                    {"b", S::Cancelled, "", "operator", 13, {}}});
  ASSERT_EQ(ts.size(), 4u);
  EXPECT_TRUE(ts[0]);
  EXPECT_TRUE(ts[1]) << "checked against the state the previous item left";
  EXPECT_FALSE(ts[2]);
  EXPECT_TRUE(ts[3]);
  auto counts = store->countByState();
  ASSERT_TRUE(counts);
  EXPECT_EQ((*counts)[S::Queued], 1);
  EXPECT_EQ((*counts)[S::EnRoute], 1);
  EXPECT_EQ((*counts)[S::Cancelled], 1);
}

TEST_P(TaskStoreTest, ListFiltersAndPages) {
  auto store = open();
  std::vector<Task> batch;
  for (int i = 0; i < 25; ++i) {
    batch.push_back(transport(numbered("t", 100 + i)));
  }
  ASSERT_EQ(store->submitBatch(batch, 1).size(), 25u);
  for (int i = 0; i < 25; i += 3) {
    ASSERT_TRUE(store->transition(numbered("t", 100 + i), S::Assigned, "r", "", 2));
  }
  auto assigned = store->list(S::Assigned, 100);
  ASSERT_TRUE(assigned);
  EXPECT_EQ(assigned->size(), 9u);
  std::vector<std::string> ids;
  std::string after;
  for (;;) {
    auto page = store->list(std::nullopt, 10, after);
    ASSERT_TRUE(page);
    if (page->empty()) {
      break;
    }
    EXPECT_LE(page->size(), 10u);
    for (const auto& r : *page) {
      ids.push_back(r.task.id);
    }
    after = page->back().task.id;
  }
  EXPECT_EQ(ids.size(), 25u);
  EXPECT_TRUE(std::is_sorted(ids.begin(), ids.end()));
  EXPECT_EQ(std::set<std::string>(ids.begin(), ids.end()).size(), 25u);
}

TEST_P(TaskStoreTest, ReopenRebuildsOpenState) {
  {
    auto store = open();
    Task late = transport("late");
    late.deadlineNs = 99;
    late.loadNs = 5;
    ASSERT_TRUE(store->submit(transport("a"), 3));
    ASSERT_TRUE(store->submit(late, 1));
    ASSERT_TRUE(store->submit(transport("done"), 2));
    ASSERT_TRUE(store->transition("a", S::Assigned, "r1", "", 4));
    ASSERT_TRUE(store->transition("done", S::Cancelled, "", "", 4));
  }
  auto store = open();
  auto open = store->openTasks();
  ASSERT_TRUE(open);
  ASSERT_EQ(open->size(), 2u);
  EXPECT_EQ((*open)[0].task.id, "late") << "oldest first";
  EXPECT_EQ((*open)[0].task.deadlineNs, 99);
  EXPECT_EQ((*open)[0].task.loadNs, 5);
  EXPECT_EQ((*open)[1].state, S::Assigned);
  EXPECT_EQ((*open)[1].robotId, "r1");
  EXPECT_EQ((*open)[1].attempts, 1);
}

TEST_P(TaskStoreTest, AMultistopTasksStepsSurviveARestart) {
  Task m;
  m.id = "m-1";
  m.kind = TaskKind::Multistop;
  m.steps = {{StepAction::Pick, "P-1", "L-42", 2'000'000'000},
             {StepAction::Drop, "D-1", "L-42", 0},
             {StepAction::Wait, "", "", 5'000'000'000},
             {StepAction::Charge, "C-1", "", 0}};
  {
    auto store = open();
    ASSERT_TRUE(store->submit(m, 1));
    ASSERT_TRUE(store->transition("m-1", S::Assigned, "r1", "", 2));
  }
  auto store = open();  // a restart
  auto open = store->openTasks();
  ASSERT_TRUE(open);
  ASSERT_EQ(open->size(), 1u);
  EXPECT_EQ((*open)[0].task.kind, TaskKind::Multistop);
  EXPECT_EQ((*open)[0].task.steps, m.steps);
  EXPECT_EQ(store->get("m-1")->task.steps, m.steps);
  auto again = store->submit(m, 3);
  ASSERT_TRUE(again) << again.error().message;
  EXPECT_FALSE(again->created) << "the same steps: the same request";
  Task other = m;
  other.steps[2].durationNs = 6'000'000'000;
  EXPECT_EQ(store->submit(other, 3).error().code, errc::kConflict) << "other steps: another task";
}

TEST_P(TaskStoreTest, JsonViewsOfRecordsAndLog) {
  auto store = open();
  ASSERT_TRUE(store->submit(transport("t1", 2), 100));
  auto rec = store->transition("t1", S::Assigned, "r1", "allocated", 200);
  ASSERT_TRUE(rec);
  const auto j = toJson(*rec);
  EXPECT_EQ(j.at("state"), "assigned");
  EXPECT_EQ(j.at("robot"), "r1");
  EXPECT_EQ(j.at("attempts"), 1);
  EXPECT_EQ(j.at("revision"), 2);
  EXPECT_EQ(j.at("task").at("created_ns"), 100);
  EXPECT_EQ(j.at("task").at("priority"), 2);
  // The task part parses back to the same task.
  auto back = parseTask(j.at("task"));
  ASSERT_TRUE(back) << back.error().message;
  EXPECT_EQ(*back, rec->task);
  auto h = store->history("t1");
  ASSERT_TRUE(h);
  EXPECT_TRUE(toJson(h->front()).at("from").is_null());
  EXPECT_EQ(toJson(h->back()).at("from"), "queued");
  EXPECT_EQ(toJson(h->back()).at("to"), "assigned");
}

TEST_P(TaskStoreTest, ConcurrentWritersShareOneStore) {
  auto store = open();
  std::vector<std::thread> threads;
  for (int w = 0; w < 4; ++w) {
    threads.emplace_back([&store, w] {
      for (int i = 0; i < 40; ++i) {
        // Every writer also submits task "shared-i": exactly one of them creates it.
        ASSERT_TRUE(store->submit(transport(numbered(numbered("w", w) + '-', i)), 1));
        ASSERT_TRUE(store->submit(transport(numbered("shared-", i)), 1));
      }
    });
  }
  for (auto& t : threads) {
    t.join();
  }
  auto all = store->list(std::nullopt, 10'000);
  ASSERT_TRUE(all);
  EXPECT_EQ(all->size(), 4u * 40u + 40u);
  for (int i = 0; i < 40; ++i) {
    auto h = store->history(numbered("shared-", i));
    ASSERT_TRUE(h);
    EXPECT_EQ(h->size(), 1u) << "one submission logged, however many retries";
  }
}

TEST(SqliteTaskStore, OpenFailsWithStorageError) {
  auto s = SqliteTaskStore::open({"/nonexistent-dir/x/tasks.db"});
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code, errc::kStorage);
}

TEST(PostgresTaskStore, AMalformedUrlIsInvalidAndAnUnreachableServerAStorageError) {
  auto bad = PostgresTaskStore::open({"postgresql://host:notaport/db"});
  ASSERT_FALSE(bad);
  EXPECT_EQ(bad.error().code, errc::kInvalid) << bad.error().message;
  EXPECT_NE(bad.error().message.find("not a PostgreSQL connection URL"), std::string::npos);
  auto typo = pg::checkUrl("postgresql://db1,db2/fleet?target_session_attr=read-write");
  ASSERT_FALSE(typo);
  EXPECT_NE(typo.error().message.find("target_session_attr"), std::string::npos) << typo.error().message;
  test::TempDir dir;
  auto gone = PostgresTaskStore::open({"postgresql:///fleet?host=" + dir.file("") + "&connect_timeout=2"});
  ASSERT_FALSE(gone);
  EXPECT_EQ(gone.error().code, errc::kStorage) << gone.error().message;
  EXPECT_NE(gone.error().message.find("cannot connect to PostgreSQL"), std::string::npos)
      << gone.error().message;
  EXPECT_EQ(pg::redacted("postgresql://fleet:s3cret@db1,db2/fleet?target_session_attrs=read-write"),
            "postgresql://fleet:***@db1,db2/fleet?target_session_attrs=read-write");
  EXPECT_TRUE(pg::checkUrl("postgresql://db1:5432,db2:5432/fleet?target_session_attrs=read-write"));
}

// Fencing is the PostgreSQL store's (SQLite has one manager): after another manager took the
// lease, a write of the older epoch stores nothing.
TEST(PostgresTaskStore, WritesOfAnOlderLeaseEpochAreFenced) {
  auto& server = TaskStoreTest::server();
  ASSERT_TRUE(server.ok()) << "the PostgreSQL test server did not start: " << server.error();
  const std::string url = server.freshUrl();
  auto store = PostgresTaskStore::open({url});
  ASSERT_TRUE(store) << store.error().message;
  ASSERT_EQ(server.sql(url, "INSERT INTO fleet_lease(name, holder, epoch) VALUES ('m', 'a', 4)"), "");
  (*store)->fenceWith("m", 4);
  ASSERT_TRUE((*store)->submit(transport("t1"), 1));
  ASSERT_TRUE((*store)->transition("t1", S::Assigned, "r1", "", 2));
  ASSERT_EQ(server.sql(url, "UPDATE fleet_lease SET holder = 'b', epoch = 5"), "");
  auto late = (*store)->transition("t1", S::EnRoute, "r1", "", 3);
  ASSERT_FALSE(late);
  EXPECT_EQ(late.error().code, errc::kFenced) << late.error().message;
  auto batch = (*store)->submitBatch({transport("t2"), transport("t3")}, 4);
  ASSERT_EQ(batch.size(), 2u);
  EXPECT_EQ(batch[1].error().code, errc::kFenced);
  EXPECT_EQ((*store)->get("t2").error().code, errc::kNotFound) << "nothing stored";
  EXPECT_EQ((*store)->get("t1")->state, S::Assigned);
  EXPECT_TRUE((*store)->get("t1")) << "reads are not fenced";
  (*store)->fenceWith("m", 5);
  EXPECT_TRUE((*store)->transition("t1", S::EnRoute, "r1", "", 5)) << "the new epoch writes";
}

// libpq's multi-host form: a host that is down is skipped, and target_session_attrs=read-write
// takes the primary (here the only server; a read-only replica is skipped the same way).
TEST(PostgresTaskStore, AMultiHostUrlFindsTheWritableServer) {
  auto& server = TaskStoreTest::server();
  ASSERT_TRUE(server.ok()) << "the PostgreSQL test server did not start: " << server.error();
  test::TempDir nothing;
  const std::string url = "postgresql:///postgres?host=" + nothing.file("") + "," + server.socketDir() +
                          "&user=fleet&target_session_attrs=read-write&connect_timeout=2";
  auto store = PostgresTaskStore::open({url});
  ASSERT_TRUE(store) << store.error().message;
  EXPECT_TRUE((*store)->submit(transport("t1"), 1));
}

// The server goes away (a crash, a fail-over) and comes back: calls fail with "storage" meanwhile
// and the store connects again by itself, committed work intact. Its own server: it is stopped.
TEST(PostgresTaskStore, ReconnectsByItselfWhenTheServerIsBack) {
  test::PostgresServer server(true);  // durable: the test server's asynchronous commits die with it
  ASSERT_TRUE(server.ok()) << "the PostgreSQL test server did not start: " << server.error();
  auto store = PostgresTaskStore::open({server.url()});
  ASSERT_TRUE(store) << store.error().message;
  ASSERT_TRUE((*store)->submit(transport("t1"), 1));
  server.stop();
  auto down = (*store)->submit(transport("t2"), 2);
  ASSERT_FALSE(down);
  EXPECT_EQ(down.error().code, errc::kStorage) << down.error().message;
  EXPECT_EQ((*store)->get("t1").error().code, errc::kStorage);
  server.restart();
  ASSERT_TRUE(server.ok()) << server.error();
  auto t1 = (*store)->get("t1");
  ASSERT_TRUE(t1) << t1.error().message;
  EXPECT_EQ(t1->state, S::Queued);
  auto t2 = (*store)->submit(transport("t2"), 3);
  ASSERT_TRUE(t2) << t2.error().message;
  EXPECT_TRUE(t2->created) << "nothing of the failed call was stored";
  EXPECT_TRUE((*store)->transition("t1", S::Assigned, "r1", "", 4)) << "statements prepared again";
}

}  // namespace
}  // namespace fleet
