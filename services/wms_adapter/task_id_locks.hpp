#pragma once

// Requests on the same task ids, one at a time. The Task topic is keyed by task id with history 1
// (DESIGN.md §3): a second request on an id written before the manager read the first replaces it,
// and the first one's client waits for an acknowledgement that never comes (503 after the ack
// timeout). Holding the ids of a request until its acknowledgement (or timeout) keeps at most one
// request per id on the wire from this adapter; the next one waits for it.

#include <algorithm>
#include <condition_variable>
#include <mutex>
#include <set>
#include <string>
#include <vector>

namespace fleet::wms {

class TaskIdLocks {
 public:
  /// Holds its ids from construction (waiting until no other Hold has any of them) to destruction.
  /// All ids are taken at once, so two batches sharing ids cannot deadlock.
  class Hold {
   public:
    Hold(TaskIdLocks& locks, std::vector<std::string> ids) : locks_(locks), ids_(std::move(ids)) {
      std::unique_lock lock(locks_.m_);
      locks_.cv_.wait(lock, [&] {
        return std::none_of(ids_.begin(), ids_.end(),
                            [&](const std::string& id) { return locks_.held_.count(id); });
      });
      locks_.held_.insert(ids_.begin(), ids_.end());
    }
    ~Hold() {
      {
        std::lock_guard lock(locks_.m_);
        for (const auto& id : ids_) {
          locks_.held_.erase(id);
        }
      }
      locks_.cv_.notify_all();
    }
    Hold(const Hold&) = delete;
    Hold& operator=(const Hold&) = delete;

   private:
    TaskIdLocks& locks_;
    std::vector<std::string> ids_;
  };

 private:
  std::mutex m_;
  std::condition_variable cv_;
  std::set<std::string> held_;
};

}  // namespace fleet::wms
