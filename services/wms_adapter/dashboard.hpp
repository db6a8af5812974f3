#pragma once

// The live operator dashboard's side of the WMS adapter (docs/operator-guide.md#dashboard): the
// page's static files (built into the binary), browser sessions, the robot API (snapshot, one
// robot, hold/release, send home or to charge), the site picture and one SSE stream of robot
// states and task events for the page.

#include <httplib.h>

#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <string>

#include "browser_session.hpp"
#include "fleet/core/clock.hpp"
#include "fleet/fleet/station_map.hpp"
#include "gateway.hpp"

namespace fleet::wms {

/// A robot as the API shows it (GET /v1/robots, /v1/robots/{id}, the stream).
nlohmann::json robotJson(const msg::RobotState& r);

/// A risk map for the page: grid, K and the level runs flattened ([level, count, level, count, ...],
/// row-major from the origin); null for a map too large to send (over 500,000 runs).
nlohmann::json riskJson(const msg::RiskMap& m);

/// What the page draws of the site: its map (rows of '#' and '.', top row first), stations and
/// the robots' home parking places (from a scenario), as GET /v1/site returns it.
nlohmann::json sitePictureOf(const std::string& path);

struct DashboardDeps {
  std::string token;  // the API's bearer token (empty: no authentication)
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
  Dashboard(httplib::Server& server, DashboardDeps deps);
  /// The API's authentication check (request_auth.hpp) with this dashboard's sessions.
  bool admit(const httplib::Request& req, httplib::Response& res) const;
  /// The picture GET /v1/site returns (sitePictureOf); before it is set, 404.
  void setSite(nlohmann::json site);

 private:
  void routes(httplib::Server& server);
  void session(const httplib::Request& req, httplib::Response& res);
  void robotAction(const httplib::Request& req, httplib::Response& res);
  void hold(const std::string& robot, bool held, httplib::Response& res);
  void sendTo(const msg::RobotState& robot, const std::string& action, const httplib::Request& req,
              httplib::Response& res);
  void stream(httplib::Response& res);
  [[nodiscard]] std::int64_t nowS() const;

  DashboardDeps d_;
  BrowserSessions sessions_;
  std::mutex siteMutex_;
  nlohmann::json site_;
  std::map<std::string, std::string> homes_;  // robot -> its parking place, from the site picture
};

}  // namespace fleet::wms
