#pragma once

// The adapter's durable log of task transitions (docs/operator-guide.md#status-push): every
// TaskEvent the adapter hears gets the next event id (1, 2, 3, ... never reused, also across
// restarts when the log is a file), which the event stream sends as `id:` and resumes after
// (Last-Event-ID, ?since=) and webhooks carry for de-duplication. A transition heard twice (the
// manager's history to a late joiner, its announcement of open tasks after a restart: the same
// task id and seq) is logged once.
//
// Retention: the newest `retainEvents` events, none older than `retainSeconds`; a resume from an id
// the log no longer holds is told so (prunedThrough()), never served a silent gap.
//
// The rows live in an EventStore (event_store.hpp): a SQLite file of this adapter's own, or a
// PostgreSQL database that adapter replicas share (`events.log` a postgresql:// URL). A shared log
// also looks for the other replicas' rows four times a second, so each replica serves the same ids
// in the same order and a client resumes on either.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>
#include <thread>
#include <vector>

#include "event_store.hpp"
#include "fleet/messages/messages.hpp"
#include "sqlite_db.hpp"

namespace fleet::wms {

struct EventLogSettings {
  /// events.log: a SQLite file, or a postgresql:// URL (shared by replicas); empty = in memory
  /// (ids restart with the process).
  std::string path;
  std::int64_t retainEvents = 100'000;
  std::int64_t retainSeconds = 7 * 24 * 3600;
};

/// The JSON an event is sent as, on the stream and to webhooks: the task event's fields (task id
/// as "id") and its event id as "event_id".
nlohmann::json loggedEventJson(const LoggedEvent& e);

class EventLog {
 public:
  /// Throws std::runtime_error when the file cannot be opened or is not an event log.
  EventLog(EventLogSettings settings, std::shared_ptr<SqliteDb> db);
  /// On any store; a shared one is read for the other replicas' rows on a thread of its own.
  EventLog(EventLogSettings settings, std::unique_ptr<EventStore> store);
  ~EventLog();
  EventLog(const EventLog&) = delete;
  EventLog& operator=(const EventLog&) = delete;
  /// Logs the events not logged before (same task id and seq; seq 0 is always new) in one
  /// transaction, `nowNs` being the wall clock (for retention); returns how many rows the log took
  /// (in a shared store also the other replicas' rows since the last look, which the listener of
  /// onCatchUp gets too).
  std::size_t append(const std::vector<msg::TaskEvent>& events, std::int64_t nowNs);
  /// Up to `limit` events with an id above `after`, oldest first. Served from memory for recent
  /// ids (no disk read: the event stream asks from the HTTP server's I/O thread).
  [[nodiscard]] std::vector<LoggedEvent> after(std::int64_t after, std::size_t limit) const;
  /// The newest id given (0: none yet).
  [[nodiscard]] std::int64_t lastId() const;
  /// The highest id retention has removed (0: none): events after an id below it are partly gone.
  [[nodiscard]] std::int64_t prunedThrough() const;
  /// Waits up to `timeout` for an id above `after`; true when there is one.
  bool waitAfter(std::int64_t after, std::chrono::milliseconds timeout) const;
  /// Wakes every waitAfter (to stop).
  void wakeAll();
  /// Takes the rows other replicas added to a shared store (done by its thread; for tests), and
  /// hands them to the listener.
  void catchUp();
  /// Called with the rows a shared log took (by catchUp, on its thread, or with an append); set
  /// once, before any.
  void onCatchUp(std::function<void(const std::vector<LoggedEvent>&)> listener) {
    listener_ = std::move(listener);
  }
  [[nodiscard]] const EventLogSettings& settings() const { return s_; }
  [[nodiscard]] bool durable() const { return store_->durable(); }
  [[nodiscard]] bool shared() const { return store_->shared(); }

  static constexpr std::size_t kMemoryTail = 4096;

 private:
  void take(const std::vector<LoggedEvent>& rows);  // into the tail, in id order
  void prune(std::int64_t nowNs);                   // writer_ held

  EventLogSettings s_;
  std::unique_ptr<EventStore> store_;
  std::mutex writer_;     // one append, prune or catch-up at a time (the store's ids in order)
  mutable std::mutex m_;  // the tail and the ids below; never held across a disk write
  mutable std::condition_variable cv_;
  std::deque<LoggedEvent> tail_;
  std::int64_t lastId_ = 0;
  std::int64_t prunedThrough_ = 0;
  std::int64_t prunedAtNs_ = 0;
  bool woken_ = false;
  std::function<void(const std::vector<LoggedEvent>&)> listener_;
  std::thread poller_;  // a shared store: the other replicas' rows
};

}  // namespace fleet::wms
