#pragma once

// The live operator dashboard's side of the WMS adapter (docs/operator-guide.md#dashboard): the
// page's static files (built into the binary), browser sessions, the robot API (snapshot, one
// robot, hold/release, send home or to charge), the site picture and one SSE stream of robot
// states, task events and the traffic layer for the page. Who may use which route is the API's scope model
// (access_control.hpp): the page's files are public, data needs "read", robot actions "operate".

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <string>

#include "browser_session.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/fleet/station_map.hpp"
#include "gateway.hpp"
#include "http_names.hpp"
#include "traffic_layer.hpp"

namespace fleet::wms {

/// A robot as the API shows it (GET /v1/robots, /v1/robots/{id}, the stream), with the people it
/// sees (`people_seen`: empty when it sees nobody or its list is stale or missing).
nlohmann::json robotJson(const msg::RobotState& r, const msg::PeopleSeen* people = nullptr);

/// Contacts and near misses as /v1/metrics and the stream's `proximity` event show them.
nlohmann::json proximityJson(const FleetView::Proximity& p);
/// GET /v1/fleet/robot-time: the fleet's ledger and each robot's, seconds and shares per category.
nlohmann::json robotTimeJson(const RobotTimeLedger& ledger);

/// A risk map for the page: grid, K and the level runs flattened ([level, count, level, count, ...],
/// row-major from the origin); null for a map too large to send (over 500,000 runs).
nlohmann::json riskJson(const msg::RiskMap& m);

/// What the page draws of the site: its map (rows of '#' and '.', top row first), stations and
/// the robots' home parking places (from a scenario), as GET /v1/site returns it.
nlohmann::json sitePictureOf(const std::string& path);

struct DashboardDeps {
  BrowserSessions& sessions;  // the API's (AccessControl admits their cookies)
  const StationMap& stations;
  TaskGateway& gateway;
  FleetView& view;
  const Clock& clock;
  std::function<std::string()> requestId;
  int ackTimeoutMs = 5000;
  int streamPeriodMs = 250;  // robot updates at most this often per stream
};

class Dashboard {
 public:
  /// Registers the dashboard's routes on `server`.
  Dashboard(HttpServer& server, DashboardDeps deps);
  /// The picture GET /v1/site returns (sitePictureOf); before it is set, 404.
  void setSite(nlohmann::json site);
  /// What GET /v1/traffic returns: the roadmap (null before there is one, or too large to draw),
  /// every robot's release and the station queues now.
  [[nodiscard]] nlohmann::json trafficSnapshot();

 private:
  void routes(HttpServer& server);
  void session(const Request& req, Response& res);
  /// POST /v1/robots/{id}/{action}: pause, resume, home or charge.
  void robotAction(const Request& req, Response& res, const std::string& action);
  void hold(const std::string& robot, bool held, Response& res);
  void sendTo(const msg::RobotState& robot, const std::string& action, const Request& req, Response& res);
  /// The page's event stream; polled by the server from its I/O thread, so it never blocks.
  [[nodiscard]] EventSource stream();
  [[nodiscard]] std::int64_t nowS() const;

  /// The current roadmap as the page gets it (made once per roadmap, shared by every stream) and
  /// its station queues; the view's roadmap count it was made from (0: none yet).
  struct RoadmapLayer {
    std::uint64_t count = 0;
    std::shared_ptr<const msg::Roadmap> map;
    std::string json;  // the `roadmap` event's data
    std::vector<StationQueue> queues;
  };
  [[nodiscard]] std::shared_ptr<const RoadmapLayer> roadmapLayer();
  /// Who waits in each station queue (queuesJson), made at most every streamPeriodMs for all
  /// streams; empty without a roadmap.
  [[nodiscard]] std::string queuesText();

  DashboardDeps d_;
  std::mutex trafficMutex_;
  std::shared_ptr<const RoadmapLayer> roadmap_ = std::make_shared<RoadmapLayer>();
  std::string queuesText_;
  std::chrono::steady_clock::time_point queuesAt_;
  std::uint64_t queuesFor_ = 0;  // the roadmap count queuesText_ was made for
  std::mutex siteMutex_;
  nlohmann::json site_;
  std::map<std::string, std::string> homes_;  // robot -> its parking place, from the site picture
};

}  // namespace fleet::wms
