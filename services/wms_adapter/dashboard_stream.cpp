// The dashboard's live stream (server-sent events) and the traffic layer it sends.

#include "dashboard.hpp"

#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>
#include <unordered_map>
#include <vector>

namespace fleet::wms {

using nlohmann::json;

std::shared_ptr<const Dashboard::RoadmapLayer> Dashboard::roadmapLayer() {
  const auto [count, map] = d_.view.roadmap();
  std::lock_guard lock(trafficMutex_);
  if (!map || count == roadmap_->count) {
    return roadmap_;
  }
  // Once per roadmap (the traffic manager sends one per incarnation and per closure), on whichever
  // thread asks first.
  json stations = json::array();
  {
    std::lock_guard site(siteMutex_);
    if (site_.is_object() && site_.contains("stations")) {
      stations = site_["stations"];
    }
  }
  auto layer = std::make_shared<RoadmapLayer>();
  layer->count = count;
  layer->map = map;
  layer->queues = stationQueues(*map, stations);
  const json j = roadmapJson(*map, layer->queues);
  layer->json = (j.is_null() ? json{{"too_large", true},
                                    {"epoch", map->epoch},
                                    {"node_count", map->nodes.size()},
                                    {"edge_count", map->edges.size()}}
                             : j)
                    .dump(-1, ' ', false, json::error_handler_t::replace);
  roadmap_ = std::move(layer);
  return roadmap_;
}

std::string Dashboard::queuesText() {
  const auto layer = roadmapLayer();
  if (!layer->map || layer->queues.empty()) {
    return {};
  }
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard lock(trafficMutex_);
  if (queuesFor_ != layer->count || now - queuesAt_ >= std::chrono::milliseconds(d_.streamPeriodMs)) {
    queuesText_ = json{{"queues", queuesJson(layer->queues, *layer->map, d_.view.robots())}}.dump(
        -1, ' ', false, json::error_handler_t::replace);
    queuesAt_ = now;
    queuesFor_ = layer->count;
  }
  return queuesText_;
}

json Dashboard::trafficSnapshot() {
  const auto layer = roadmapLayer();
  json releases = json::array();
  for (const auto& [robot, r] : d_.view.releases().second) {
    releases.push_back(releaseJson(*r));
  }
  const std::string queues = queuesText();
  return {{"roadmap", layer->map ? json::parse(layer->json) : json()},
          {"releases", releases},
          {"queues", queues.empty() ? json::array() : json::parse(queues)["queues"]}};
}
EventSource Dashboard::stream() {
  // One stream for the page: a snapshot first (robots, recent tasks), then robot states that
  // changed (at most every streamPeriodMs) and every task event. A page that reconnects gets a
  // new snapshot, so it catches up after a lost connection or an adapter restart. The server
  // asks for the next text every poll interval from its I/O thread: nothing here waits, and the
  // server sends keep-alives when there is nothing to say.
  struct Cursor {
    bool sentSnapshot = false;
    std::uint64_t events = 0;
    std::unordered_map<std::string, std::int64_t> sent;  // robot -> stamp sent last
    std::chrono::steady_clock::time_point robotsSentAt;
    std::uint64_t risk = 0;  // risk maps sent: the view's count
    std::chrono::steady_clock::time_point riskSentAt;
    std::uint64_t roadmap = 0;   // the roadmap sent: the view's count
    std::uint64_t releases = 0;  // the view's release count when they were last looked at
    FleetView::Releases releasesSent;
    std::chrono::steady_clock::time_point releasesSentAt;
    std::string queues;           // the queues event's data sent last
    std::uint64_t proximity = 0;  // the proximity figures' version sent last
    std::chrono::steady_clock::time_point proximitySentAt;
  };
  auto cur = std::make_shared<Cursor>();
  cur->events = d_.view.eventCursor();
  return [this, cur]() -> std::optional<std::string> {
    const auto now = std::chrono::steady_clock::now();
    auto robotsJson = [&](bool all) {
      json items = json::array();
      const auto people = d_.view.allPeopleSeen(steadyNowNs());
      for (const auto& r : d_.view.robots()) {
        auto& last = cur->sent[r.robot_id];
        if (all || r.stamp_ns != last) {
          last = r.stamp_ns;
          const auto p = people.find(r.robot_id);
          items.push_back(robotJson(r, p != people.end() ? &p->second : nullptr));
        }
      }
      cur->robotsSentAt = now;
      return items;
    };
    // The risk map at most once a second: it is the largest message and changes least visibly.
    auto riskEvent = [&](bool force) -> std::string {
      const auto [count, map] = d_.view.risk();
      if (!map || count == cur->risk || (!force && now - cur->riskSentAt < std::chrono::seconds(1))) {
        return {};
      }
      cur->risk = count;
      cur->riskSentAt = now;
      const json j = riskJson(*map);
      return j.is_null() ? std::string() : "event: risk\ndata: " + j.dump() + "\n\n";
    };
    // The traffic layer: the roadmap once (and again when it changes), then the releases that
    // changed (all of them after a new roadmap: the page replaces its set when "all" is true), the
    // station queues when who waits in them changes.
    auto roadmapEvent = [&]() -> std::string {
      const auto layer = roadmapLayer();
      if (!layer->map || layer->count == cur->roadmap) {
        return {};
      }
      cur->roadmap = layer->count;
      cur->releasesSent.clear();
      cur->releases = 0;
      return "event: roadmap\ndata: " + layer->json + "\n\n";
    };
    auto releasesEvent = [&](bool force) -> std::string {
      if (!force && now - cur->releasesSentAt < std::chrono::milliseconds(d_.streamPeriodMs)) {
        return {};
      }
      auto [count, current] = d_.view.releases();
      if (count == cur->releases) {
        return {};
      }
      const bool all = cur->releasesSent.empty();
      cur->releases = count;
      cur->releasesSentAt = now;
      json changed = json::array();
      json removed = json::array();
      for (const auto& [robot, r] : current) {
        const auto it = cur->releasesSent.find(robot);
        if (it == cur->releasesSent.end() || it->second != r) {
          changed.push_back(releaseJson(*r));
        }
      }
      for (const auto& [robot, r] : cur->releasesSent) {
        if (!current.contains(robot)) {
          removed.push_back(robot);
        }
      }
      cur->releasesSent = std::move(current);
      if (!all && changed.empty() && removed.empty()) {
        return {};
      }
      return "event: releases\ndata: " +
             json{{"all", all}, {"releases", changed}, {"removed", removed}}.dump(
                 -1, ' ', false, json::error_handler_t::replace) +
             "\n\n";
    };
    // Contacts and near misses whenever a figure changed, at most every streamPeriodMs.
    auto proximityEvent = [&](bool force) -> std::string {
      if (!force && now - cur->proximitySentAt < std::chrono::milliseconds(d_.streamPeriodMs)) {
        return {};
      }
      const auto p = d_.view.proximity();
      if (!force && p.version == cur->proximity) {
        return {};
      }
      cur->proximity = p.version;
      cur->proximitySentAt = now;
      return "event: proximity\ndata: " + proximityJson(p).dump() + "\n\n";
    };
    auto queuesEvent = [&]() -> std::string {
      std::string q = queuesText();
      if (q.empty() || q == cur->queues) {
        return {};
      }
      cur->queues = q;
      return "event: queues\ndata: " + q + "\n\n";
    };
    const char* manager = d_.gateway.managerOnline() ? "online" : "unreachable";
    if (!cur->sentSnapshot) {
      cur->sentSnapshot = true;
      json tasks = json::array();
      for (const auto& t : d_.view.tasks(std::nullopt, 500)) {
        tasks.push_back({{"id", t.id},
                         {"state", msg::toString(t.state)},
                         {"robot", t.robot},
                         {"reason", t.reason},
                         {"stamp_ns", t.updatedNs},
                         {"eta_ns", t.etaNs},
                         {"step", t.step}});
      }
      std::string snapshot =
          "retry: 1000\nevent: snapshot\ndata: " +
          json{{"robots", robotsJson(true)}, {"tasks", tasks}, {"fleet_manager", manager}}.dump(
              -1, ' ', false, json::error_handler_t::replace) +
          "\n\n";
      // One after the other (the operands of + are not sequenced): the roadmap before the releases.
      snapshot += roadmapEvent();
      snapshot += releasesEvent(true);
      snapshot += queuesEvent();
      snapshot += proximityEvent(true);
      return snapshot + riskEvent(true);
    }
    std::string chunk;
    std::vector<msg::TaskEvent> evs;
    cur->events = d_.view.eventsAfter(cur->events, std::chrono::milliseconds(0), evs);
    for (const auto& e : evs) {
      chunk += "event: task\ndata: " +
               json{{"id", e.task_id},        {"state", msg::toString(e.state)},
                    {"robot", e.robot_id},    {"reason", e.reason},
                    {"stamp_ns", e.stamp_ns}, {"seq", e.seq},
                    {"station", e.station},   {"eta_ns", e.eta_ns},
                    {"step", e.step}}
                   .dump(-1, ' ', false, json::error_handler_t::replace) +
               "\n\n";
    }
    if (now - cur->robotsSentAt >= std::chrono::milliseconds(d_.streamPeriodMs)) {
      const json robots = robotsJson(false);
      if (!robots.empty()) {
        chunk += "event: robots\ndata: " +
                 json{{"robots", robots}, {"fleet_manager", manager}}.dump(-1, ' ', false,
                                                                           json::error_handler_t::replace) +
                 "\n\n";
      }
    }
    chunk += roadmapEvent();
    chunk += releasesEvent(false);
    chunk += queuesEvent();
    chunk += proximityEvent(false);
    return chunk + riskEvent(false);
  };
}

}  // namespace fleet::wms
