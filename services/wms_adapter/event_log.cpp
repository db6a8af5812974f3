#include "event_log.hpp"

#include <algorithm>
#include <stdexcept>

#include "rfc3339.hpp"
#include "sqlite_event_store.hpp"

namespace fleet::wms {

nlohmann::json loggedEventJson(const LoggedEvent& l) {
  const auto& e = l.event;
  nlohmann::json j = {{"event_id", l.id},    {"id", e.task_id},     {"state", msg::toString(e.state)},
                      {"robot", e.robot_id}, {"reason", e.reason},  {"stamp_ns", e.stamp_ns},
                      {"seq", e.seq},        {"station", e.station}};
  if (e.changed) {
    // A change of the waiting task's priority and deadline: the values now in force.
    j["changed"] = true;
    j["priority"] = e.priority;
    j["deadline_ns"] = e.deadline_ns;
    if (e.deadline_ns > 0) {
      j["deadline"] = toRfc3339(e.deadline_ns);
    }
  }
  if (e.eta_ns > 0) {
    j["eta_ns"] = e.eta_ns;
    j["eta"] = toRfc3339(e.eta_ns);
  }
  if (e.step > 0) {
    j["step"] = e.step;  // a multi-stop task's stop, from 1
  }
  return j;
}

namespace {

constexpr std::int64_t kPruneEveryNs = 1'000'000'000;
constexpr auto kCatchUpEvery = std::chrono::milliseconds(250);

}  // namespace

EventLog::EventLog(EventLogSettings settings, std::shared_ptr<SqliteDb> db)
    : EventLog(std::move(settings), std::make_unique<SqliteEventStore>(std::move(db))) {}

EventLog::EventLog(EventLogSettings settings, std::unique_ptr<EventStore> store)
    : s_(std::move(settings)), store_(std::move(store)) {
  lastId_ = store_->lastId();
  prunedThrough_ = store_->prunedThrough();
  for (auto& l :
       store_->after(std::max<std::int64_t>(prunedThrough_, lastId_ - static_cast<std::int64_t>(kMemoryTail)),
                     kMemoryTail)) {
    tail_.push_back(std::move(l));
  }
  if (store_->shared()) {
    poller_ = std::thread([this] {
      std::unique_lock lock(m_);
      while (!woken_) {
        cv_.wait_for(lock, kCatchUpEvery, [&] { return woken_; });
        if (woken_) {
          break;
        }
        lock.unlock();
        try {
          catchUp();
        } catch (const std::exception&) {
          // The database is away: the next round tries again (appends report their own errors).
        }
        lock.lock();
      }
    });
  }
}

EventLog::~EventLog() {
  wakeAll();
  if (poller_.joinable()) {
    poller_.join();
  }
}

void EventLog::take(const std::vector<LoggedEvent>& rows) {
  if (rows.empty()) {
    return;
  }
  {
    std::lock_guard lock(m_);
    for (auto& a : rows) {
      if (a.id <= lastId_) {
        continue;  // already taken
      }
      lastId_ = a.id;
      tail_.push_back(a);
    }
    while (tail_.size() > kMemoryTail || (!tail_.empty() && tail_.front().id <= prunedThrough_)) {
      tail_.pop_front();
    }
  }
  cv_.notify_all();
}

std::size_t EventLog::append(const std::vector<msg::TaskEvent>& events, std::int64_t nowNs) {
  std::lock_guard writer(writer_);
  const std::int64_t known = lastId();
  auto rows = store_->append(events, nowNs, known);
  // Those this call added (in a shared store, some rows may be other replicas').
  const std::size_t added = rows.size();
  // By count when 1 % over (one DELETE per many appends), by age once a second.
  const std::int64_t held = (rows.empty() ? known : rows.back().id) - prunedThrough();
  take(rows);
  if (store_->shared() && listener_ && !rows.empty()) {
    listener_(rows);  // other replicas' rows among them: catchUp will not see them again
  }
  if (nowNs - prunedAtNs_ >= kPruneEveryNs || held > s_.retainEvents + s_.retainEvents / 100) {
    prune(nowNs);
  }
  return added;
}

void EventLog::catchUp() {
  std::vector<LoggedEvent> rows;
  {
    std::lock_guard writer(writer_);
    rows = store_->after(lastId(), kMemoryTail);
    take(rows);
  }
  if (!rows.empty() && listener_) {
    listener_(rows);
  }
}

void EventLog::prune(std::int64_t nowNs) {
  prunedAtNs_ = nowNs;
  const std::int64_t through = store_->prune(s_.retainEvents, nowNs - s_.retainSeconds * 1'000'000'000);
  std::lock_guard lock(m_);
  prunedThrough_ = std::max(prunedThrough_, through);
  while (!tail_.empty() && tail_.front().id <= prunedThrough_) {
    tail_.pop_front();
  }
}

std::vector<LoggedEvent> EventLog::after(std::int64_t after, std::size_t limit) const {
  std::vector<LoggedEvent> out;
  {
    std::lock_guard lock(m_);
    after = std::max(after, prunedThrough_);
    if (after >= lastId_) {
      return out;
    }
    if (!tail_.empty() && after >= tail_.front().id - 1) {
      auto it = std::lower_bound(tail_.begin(), tail_.end(), after + 1,
                                 [](const LoggedEvent& l, std::int64_t id) { return l.id < id; });
      for (; it != tail_.end() && out.size() < limit; ++it) {
        out.push_back(*it);
      }
      return out;
    }
  }
  // Older than the memory holds: a client catching up from far back (bounded by `limit`).
  return store_->after(after, limit);
}

std::int64_t EventLog::lastId() const {
  std::lock_guard lock(m_);
  return lastId_;
}

std::int64_t EventLog::prunedThrough() const {
  std::lock_guard lock(m_);
  return prunedThrough_;
}

bool EventLog::waitAfter(std::int64_t after, std::chrono::milliseconds timeout) const {
  std::unique_lock lock(m_);
  return cv_.wait_for(lock, timeout, [&] { return lastId_ > after || woken_; }) && lastId_ > after;
}

void EventLog::wakeAll() {
  {
    std::lock_guard lock(m_);
    woken_ = true;
  }
  cv_.notify_all();
}

}  // namespace fleet::wms
