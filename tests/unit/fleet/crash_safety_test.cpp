// Kill -9 a writer at random points and check that every acknowledged write survived.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <map>
#include <random>
#include <sstream>

#include "fleet/fleet/sqlite_task_store.hpp"
#include "temp_dir.hpp"

namespace fleet {
namespace {

using S = TaskState;

void writeLine(int fd, const std::string& line) {
  const std::string s = line + "\n";
  std::size_t off = 0;
  while (off < s.size()) {
    const ssize_t n = ::write(fd, s.data() + off, s.size() - off);
    if (n <= 0) {
      _exit(3);
    }
    off += static_cast<std::size_t>(n);
  }
}

/// The writer: submits batches and single tasks, drives tasks along legal paths, and reports each
/// write on `fd` only after the store call returned success. Never returns.
[[noreturn]] void runWriter(const std::string& path, int round, int fd, std::uint32_t seed) {
  auto opened = SqliteTaskStore::open({path});
  if (!opened) {
    _exit(2);
  }
  auto& store = **opened;
  std::mt19937 rng(seed);
  std::vector<std::pair<std::string, S>> live;  // tasks this writer moves along
  const std::vector<S> path5 = {S::Assigned, S::EnRoute, S::Loading, S::Delivering, S::Unloading, S::Done};
  int next = 0;
  for (std::int64_t stamp = 1;; ++stamp) {
    const int what = static_cast<int>(rng() % 4);
    if (what == 0 || live.empty()) {
      std::vector<Task> batch(1 + rng() % 20);
      for (auto& t : batch) {
        t.id = "r";  // built by appending: GCC 12 reports a false -Wrestrict on "r" + std::string
        t.id += std::to_string(round);
        t.id += '-';
        t.id += std::to_string(next++);
        t.kind = TaskKind::Transport;
        t.pickup = "P-1";
        t.dropoff = "D-1";
      }
      auto rs = batch.size() == 1 ? std::vector<Expected<SubmitResult>>{store.submit(batch[0], stamp)}
                                  : store.submitBatch(batch, stamp);
      for (std::size_t i = 0; i < rs.size(); ++i) {
        if (!rs[i]) {
          _exit(4);
        }
        writeLine(fd, "S " + batch[i].id);
        live.emplace_back(batch[i].id, S::Queued);
      }
    } else {
      auto& [id, state] = live[rng() % live.size()];
      S to = S::Assigned;
      if (state != S::Queued && state != S::Requeued) {
        const auto it = std::find(path5.begin(), path5.end(), state);
        to = rng() % 8 == 0 ? S::Requeued : *(it + 1);
      }
      auto r = store.transition(id, to, to == S::Requeued ? "" : "robot-1", "", stamp);
      if (!r) {
        _exit(5);
      }
      writeLine(fd, "T " + id + " " + std::to_string(r->revision) + " " + std::string(toString(to)));
      state = to;
      if (to == S::Done) {
        live.erase(std::find_if(live.begin(), live.end(), [&](const auto& p) { return p.first == id; }));
      }
    }
  }
}

struct Acks {
  std::vector<std::string> submitted;
  std::map<std::string, std::pair<std::int64_t, S>> lastTransition;  // id → (revision, state)
};

Acks parseAcks(const std::string& text) {
  Acks a;
  std::istringstream in(text);
  std::string line;
  while (std::getline(in, line)) {
    if (in.eof()) {
      break;  // a partial last line was cut by the kill
    }
    std::istringstream l(line);
    std::string kind, id;
    l >> kind >> id;
    if (kind == "S") {
      a.submitted.push_back(id);
    } else if (kind == "T") {
      std::int64_t rev = 0;
      std::string state;
      l >> rev >> state;
      a.lastTransition[id] = {rev, parseTaskState(state).value()};
    }
  }
  return a;
}

TEST(CrashSafety, AcknowledgedWritesSurviveSigkill) {
  test::TempDir dir;
  const std::string path = dir.file("tasks.db");
  std::mt19937 rng(20261122);
  std::size_t totalAcked = 0;
  constexpr int kRounds = 8;
  for (int round = 0; round < kRounds; ++round) {
    int fds[2];
    ASSERT_EQ(::pipe(fds), 0);
    const std::uint32_t seed = rng();
    const pid_t pid = ::fork();
    ASSERT_GE(pid, 0);
    if (pid == 0) {
      ::close(fds[0]);
      runWriter(path, round, fds[1], seed);
    }
    ::close(fds[1]);
    // Read while the child runs so it never blocks on a full pipe, then kill it mid-flight: once it
    // has acknowledged a random number of writes (not after a random time: on a loaded machine a
    // writer killed after 30-250 ms had sometimes acknowledged almost nothing), or after 20 s.
    const std::size_t killAfterAcks = 20 + rng() % 60;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    std::string acks;
    char buf[4096];
    bool killed = false;
    for (;;) {
      if (!killed && (static_cast<std::size_t>(std::count(acks.begin(), acks.end(), '\n')) >= killAfterAcks ||
                      std::chrono::steady_clock::now() >= deadline)) {
        ASSERT_EQ(::kill(pid, SIGKILL), 0);
        killed = true;
      }
      pollfd p{fds[0], POLLIN, 0};
      ::poll(&p, 1, 5);
      if ((p.revents & (POLLIN | POLLHUP)) != 0) {
        const ssize_t n = ::read(fds[0], buf, sizeof buf);
        if (n > 0) {
          acks.append(buf, static_cast<std::size_t>(n));
        } else if (n == 0) {
          break;  // writer gone (killed) and pipe drained
        }
      }
    }
    ::close(fds[0]);
    int status = 0;
    ASSERT_EQ(::waitpid(pid, &status, 0), pid);
    ASSERT_TRUE(WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL)
        << "writer stopped on its own, status " << status;

    const Acks a = parseAcks(acks);
    totalAcked += a.submitted.size();
    auto opened = SqliteTaskStore::open({path});
    ASSERT_TRUE(opened) << opened.error().message;
    auto& store = **opened;
    for (const auto& id : a.submitted) {
      auto r = store.get(id);
      ASSERT_TRUE(r) << "round " << round << ": acknowledged task " << id << " lost";
    }
    for (const auto& [id, acked] : a.lastTransition) {
      auto r = store.get(id);
      ASSERT_TRUE(r);
      // The acknowledged transition is in the log at its revision (later, unacknowledged ones may follow).
      EXPECT_GE(r->revision, acked.first) << id;
      auto h = store.history(id);
      ASSERT_TRUE(h);
      ASSERT_GE(h->size(), static_cast<std::size_t>(acked.first)) << id;
      EXPECT_EQ((*h)[static_cast<std::size_t>(acked.first - 1)].to, acked.second) << id;
    }
    // Every stored task of this round: one row, a log that is a legal chain ending in its state.
    auto all = store.list(std::nullopt, 1'000'000);
    ASSERT_TRUE(all);
    std::set<std::string> ids;
    for (const auto& r : *all) {
      ASSERT_TRUE(ids.insert(r.task.id).second) << "duplicated " << r.task.id;
      auto h = store.history(r.task.id);
      ASSERT_TRUE(h);
      ASSERT_EQ(static_cast<std::int64_t>(h->size()), r.revision) << r.task.id;
      ASSERT_FALSE(h->front().from.has_value());
      EXPECT_EQ(h->front().to, S::Queued);
      for (std::size_t i = 1; i < h->size(); ++i) {
        ASSERT_EQ((*h)[i].from, (*h)[i - 1].to) << r.task.id;
        ASSERT_TRUE(checkTransition(*(*h)[i].from, (*h)[i].to, r.task.kind)) << r.task.id;
      }
      EXPECT_EQ(h->back().to, r.state) << r.task.id;
    }
  }
  EXPECT_GT(totalAcked, 100u) << "the writer should have made progress before being killed";
}

}  // namespace
}  // namespace fleet
