#pragma once

// Where the adapter's event log (event_log.hpp) keeps its events: a SQLite file of the adapter's
// own (or memory), or a PostgreSQL database that adapter replicas share. The log keeps the recent
// events in memory and the ids in order; a store gives the ids, keeps the rows and prunes them.

#include <cstdint>
#include <string>
#include <vector>

#include "fleet/messages/messages.hpp"

namespace fleet::wms {

struct LoggedEvent {
  std::int64_t id = 0;
  msg::TaskEvent event;
};

class EventStore {
 public:
  virtual ~EventStore() = default;
  /// Logs the events not logged before (same task id and seq; seq 0 is always new), `nowNs` being
  /// the wall clock (for retention), in one transaction, and returns every row with an id above
  /// `known`, oldest first: the ones just added and, in a shared store, those other replicas
  /// added. Throws std::runtime_error when the store refuses (a disk or connection error).
  virtual std::vector<LoggedEvent> append(const std::vector<msg::TaskEvent>& events, std::int64_t nowNs,
                                          std::int64_t known) = 0;
  /// Up to `limit` rows with an id above `after`, oldest first. Throws on a read error.
  [[nodiscard]] virtual std::vector<LoggedEvent> after(std::int64_t after, std::size_t limit) const = 0;
  /// The newest id given (0: none yet).
  [[nodiscard]] virtual std::int64_t lastId() const = 0;
  /// The highest id removed by retention (0: none): the row below the oldest held, or the newest
  /// id when none is held.
  [[nodiscard]] virtual std::int64_t prunedThrough() const = 0;
  /// Removes all but the newest `keep` events and those logged before `beforeNs`; returns the
  /// highest id removed so far (0: none).
  virtual std::int64_t prune(std::int64_t keep, std::int64_t beforeNs) = 0;
  /// Whether an event logged survives the adapter's restart.
  [[nodiscard]] virtual bool durable() const = 0;
  /// Whether other adapters add to it too (the log then looks for their rows now and then).
  [[nodiscard]] virtual bool shared() const { return false; }
};

}  // namespace fleet::wms
