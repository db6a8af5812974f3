// Stations closed at run time: a waiting task with one is held back with a stated reason.

#include "fleet/fleet/dispatcher.hpp"

namespace fleet {
namespace {
constexpr std::string_view kClosedPrefix = "station ";
constexpr std::string_view kClosedMark = " closed: ";
constexpr std::string_view kReopened = " open again; waiting for a robot";
}  // namespace

const std::string* Dispatcher::closedStationOf(const Task& t) const {
  if (closedStations_.empty()) {
    return nullptr;
  }
  for (const std::string* s : taskStops(t)) {
    if (closedStations_.count(*s) > 0) {
      return s;
    }
  }
  return nullptr;
}

DispatchResult Dispatcher::setClosedStations(std::map<std::string, std::string, std::less<>> closed,
                                             std::int64_t nowNs) {
  closedStations_ = std::move(closed);
  DispatchResult out;
  noteClosedStations(nowNs, out);
  return out;
}

void Dispatcher::noteClosedStations(std::int64_t nowNs, DispatchResult& out) {
  for (auto& [id, r] : open_) {
    if (!isWaiting(r.state) || r.paused) {
      continue;
    }
    std::string why;
    if (const std::string* s = closedStationOf(r.task)) {
      why = std::string(kClosedPrefix) + *s + std::string(kClosedMark) + closedStations_.at(*s);
    } else if (r.reason.starts_with(kClosedPrefix) && r.reason.find(kClosedMark) != std::string::npos) {
      // The station named reopened (or the closure was lifted).
      const auto name =
          r.reason.substr(kClosedPrefix.size(), r.reason.find(kClosedMark) - kClosedPrefix.size());
      why = std::string(kClosedPrefix) + name + std::string(kReopened);
    }
    if (why.empty() || why == r.reason) {
      continue;
    }
    auto res = store_.setWaitReason(id, why.substr(0, 255), nowNs);
    if (!res) {
      out.errors.push_back(res.error());
      continue;
    }
    r.reason = res->reason;
    r.updatedNs = res->updatedNs;
    // Held by a closure: no estimate of when it will be done.
    const std::int64_t eta = closedStationOf(r.task) != nullptr ? 0 : currentEta(r, nowNs);
    out.events.push_back({id, r.state, "", r.reason, nowNs, "", eta});
  }
}

}  // namespace fleet
