#include "dashboard.hpp"

#include <chrono>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <set>
#include <unordered_map>

#include "fleet/core/bounded_json.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/fleet/site_stations.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/fleet/task_wire.hpp"
#include "json_reply.hpp"
#include "robot_time.hpp"
#include "web_files.hpp"

namespace fleet::wms {
namespace {

using nlohmann::json;

json problem(const std::string& code, const std::string& message) {
  return {{"error", code}, {"message", message}};
}

json invalidField(const std::string& path, const std::string& reason) {
  return {{"error", "invalid"}, {"fields", json::array({{{"path", path}, {"reason", reason}}})}};
}

json kindsOf(const Station& s) {
  json k = json::array();
  for (auto kind : {StationKind::Pickup, StationKind::Dropoff, StationKind::Charging, StationKind::Parking}) {
    if (s.has(kind)) {
      k.push_back(std::string(toString(kind)));
    }
  }
  return k;
}

/// The station of `kind` nearest to `p` in a straight line, or nothing.
const Station* nearest(const StationMap& stations, StationKind kind, Vec2 p) {
  const Station* best = nullptr;
  double bestD = std::numeric_limits<double>::infinity();
  for (const Station* s : stations.ofKind(kind)) {
    const double d = distance(s->pose.position(), p);
    if (d < bestD) {
      bestD = d;
      best = s;
    }
  }
  return best;
}

}  // namespace

json robotJson(const msg::RobotState& r, const msg::PeopleSeen* people) {
  // One number for how well the pose is known: the position's standard deviation (largest axis
  // bound by the trace). A huge one means the robot does not know where it is.
  const double var = r.covariance[0] + r.covariance[4];
  json seen = json::array();
  if (people != nullptr) {
    // To the centimetre: the page draws them, nobody steers by them.
    auto cm = [](float v) { return std::round(static_cast<double>(v) * 100.0) / 100.0; };
    for (const auto& p : people->people) {
      seen.push_back({{"x", cm(p.x)},
                      {"y", cm(p.y)},
                      {"vx", cm(p.vx)},
                      {"vy", cm(p.vy)},
                      {"radius", cm(p.r)},
                      {"velocity_known", p.velocity_known}});
    }
  }
  return {{"id", r.robot_id},
          {"pose", {{"x", r.pose.x}, {"y", r.pose.y}, {"theta", r.pose.theta}}},
          {"heading_deg", r.pose.theta * 180.0 / M_PI},
          {"v", r.v},
          {"w", r.w},
          {"mode", msg::toString(r.mode)},
          {"activity", toString(RobotTimeLedger::activityOf(r))},
          {"fault", r.mode == msg::RobotMode::Fault},
          {"paused", r.paused},
          {"battery", r.battery},
          {"task", r.task_id},
          {"radius", r.radius},
          {"position_sigma", std::isfinite(var) && var >= 0 ? std::sqrt(var) : -1.0},
          {"stamp_ns", r.stamp_ns},
          {"people_seen", seen},
          {"people_seen_stamp_ns", people != nullptr ? json(people->stamp_ns) : json()}};
}

json robotTimeJson(const RobotTimeLedger& ledger) {
  auto shares = [](const ActivityLedger& l) {
    json seconds = json::object();
    json share = json::object();
    for (const auto a : kLedgerActivities) {
      seconds[toString(a)] = l.seconds(a);
      share[toString(a)] = l.share(a);
    }
    return json{{"seconds", l.total()}, {"by_activity_s", seconds}, {"shares", share}};
  };
  json robots = json::array();
  for (const auto& [id, l] : ledger.robots()) {
    json r = shares(l);
    r["id"] = id;
    robots.push_back(std::move(r));
  }
  return {{"fleet", shares(ledger.fleet())}, {"robots", robots}};
}

json proximityJson(const FleetView::Proximity& p) {
  auto counts = [](const ProximityCounts& c) {
    return json{{"contacts", c.contacts},
                {"near_misses", c.nearMisses},
                {"in_contact_now", c.inContact},
                {"close_now", c.close},
                {"min_clearance_m", std::isfinite(c.minClearance) ? json(c.minClearance) : json()}};
  };
  return {{"robot_robot", counts(p.robotRobot)},
          {"robot_person", counts(p.robotPerson)},
          {"near_miss_margin_m", p.params.nearMissMargin},
          {"hysteresis_m", p.params.hysteresis}};
}

json riskJson(const msg::RiskMap& m) {
  if (m.runs.size() > 500'000) {
    return nullptr;
  }
  std::vector<std::uint32_t> runs;
  runs.reserve(2 * m.runs.size());
  for (const auto& r : m.runs) {
    runs.push_back(r.level);
    runs.push_back(r.count);
  }
  return {{"stamp_ns", m.stamp_ns},
          {"origin", {m.origin_x, m.origin_y}},
          {"resolution", m.resolution},
          {"width", m.width},
          {"height", m.height},
          {"levels", m.levels},
          {"runs", runs}};
}

json sitePictureOf(const std::string& path) {
  auto loaded = fleet::loadSiteStations(path);
  if (!loaded) {
    return {{"error", loaded.error().message}};
  }
  json out = {{"name", loaded->site ? loaded->site->name : path}};
  json stations = json::array();
  for (const Station* s : loaded->stations.all()) {
    stations.push_back({{"name", s->name},
                        {"x", s->pose.x},
                        {"y", s->pose.y},
                        {"theta", s->pose.theta},
                        {"kinds", kindsOf(*s)}});
  }
  out["stations"] = stations;
  if (loaded->site) {
    const auto& g = loaded->site->map;
    json rows = json::array();
    for (int y = g.height() - 1; y >= 0; --y) {
      std::string row(static_cast<std::size_t>(g.width()), '.');
      for (int x = 0; x < g.width(); ++x) {
        if (g.blocked({x, y})) {
          row[static_cast<std::size_t>(x)] = '#';
        }
      }
      rows.push_back(std::move(row));
    }
    out["map"] = {{"width", g.width()},
                  {"height", g.height()},
                  {"resolution", g.resolution()},
                  {"origin", {g.origin().x, g.origin().y}},
                  {"rows", rows}};
  }
  // A scenario names each robot's parking place: where "send home" sends it.
  std::ifstream in(path);
  const json doc = json::parse(in, nullptr, false);
  json homes = json::object();
  if (doc.is_object() && doc.contains("robots") && doc["robots"].is_array()) {
    for (const auto& r : doc["robots"]) {
      if (r.is_object() && r.value("id", json()).is_string() &&
          r.value("start_station", json()).is_string()) {
        homes[r["id"].get<std::string>()] = r["start_station"];
      }
    }
  }
  out["homes"] = homes;
  return out;
}

Dashboard::Dashboard(HttpServer& server, DashboardDeps deps) : d_(std::move(deps)) {
  routes(server);
}

std::int64_t Dashboard::nowS() const {
  return std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch())
      .count();
}

void Dashboard::setSite(json site) {
  {
    std::lock_guard lock(siteMutex_);
    homes_.clear();
    if (site.contains("homes")) {
      for (const auto& [robot, station] : site["homes"].items()) {
        homes_[robot] = station.get<std::string>();
      }
    }
    site_ = std::move(site);
  }
  std::lock_guard traffic(trafficMutex_);
  roadmap_ = std::make_shared<RoadmapLayer>();  // queues are named after the site's stations
}

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

void Dashboard::routes(HttpServer& server) {
  using Run = HttpServer::Run;
  server.route(
      "GET", "/", Scope::Public,
      [](const Request&, Response& res) {
        res.status = 302;
        res.set_header("Location", "dashboard/");  // relative: kept under a proxy's path prefix
      },
      Run::Inline);
  // The page's files carry no data: no login (the page asks for the token itself).
  // The page's files are flat: /dashboard/ is index.html, /dashboard/{file} the others.
  const auto serveFile = [](const Request& req, Response& res) {
    const std::string name = req.matches.size() > 1 ? req.matches[1] : "index.html";
    const WebFile* f = webFile(name);
    if (f == nullptr) {
      replyJson(res, 404, problem("not_found", "no file \"" + name + "\" in the dashboard"));
      return;
    }
    res.set_header("Cache-Control", "no-cache");
    res.set_header("X-Content-Type-Options", "nosniff");
    res.set_header("Content-Security-Policy",
                   "default-src 'self'; img-src 'self' data:; style-src 'self'; frame-ancestors 'none'");
    res.set_content(std::string(f->body), std::string(f->type));
  };
  server.route("GET", "/dashboard/", Scope::Public, serveFile, Run::Inline);
  server.route("GET", R"(/dashboard/([^/]+))", Scope::Public, serveFile, Run::Inline);
  // Any token may make a session (it acts with that token's scopes); logging out with the cookie
  // needs the CSRF token like every other change.
  for (const char* method : {"GET", "POST", "DELETE"}) {
    server.route(method, "/v1/session", Scope::Read,
                 [this](const Request& req, Response& res) { session(req, res); });
  }
  server.route("GET", "/v1/site", Scope::Read, [this](const Request&, Response& res) {
    std::lock_guard lock(siteMutex_);
    if (site_.is_null()) {
      replyJson(res, 404, problem("not_found", "this adapter has no site picture"));
      return;
    }
    replyJson(res, 200, site_);
  });
  server.route("GET", "/v1/traffic", Scope::Read,
               [this](const Request&, Response& res) { replyJson(res, 200, trafficSnapshot()); });
  server.route("GET", R"(/v1/robots/([^/]+))", Scope::Read, [this](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    for (const auto& r : d_.view.robots()) {
      if (r.robot_id == id) {
        const auto people = d_.view.peopleSeen(id, steadyNowNs());
        replyJson(res, 200, robotJson(r, people ? &*people : nullptr));
        return;
      }
    }
    replyJson(res, 404, problem("not_found", "no robot with id \"" + id + "\""));
  });
  // Commanding a robot is an operator's: the same scope as pausing a task.
  server.limitBody("POST", R"(/v1/robots/([^/]+)/([^/]+))", 4096, "the robot action route's fixed limit");
  for (const std::string action : {"pause", "resume", "home", "charge"}) {
    server.route("POST", R"(/v1/robots/([^/]+)/)" + action, Scope::Operate,
                 [this, action](const Request& req, Response& res) { robotAction(req, res, action); });
  }
  server.route(
      "GET", "/v1/stream", Scope::Read,
      [this](const Request&, Response& res) {
        res.set_header("Cache-Control", "no-cache");
        res.set_header("X-Accel-Buffering", "no");
        res.setEventStream("text/event-stream", stream());
      },
      Run::Inline);
}

void Dashboard::session(const Request& req, Response& res) {
  // The gate has let this request through: bearer token, a session, or no authentication at all.
  // The page offers only what the caller's scopes allow (the server refuses the rest anyway).
  auto scopesJson = [](const std::set<Scope>& scopes) {
    json out = json::array();
    for (const auto scope : scopes) {
      out.push_back(toString(scope));
    }
    return out;
  };
  if (!d_.sessions.enabled()) {
    replyJson(res, 200,
              {{"auth", "off"},
               {"csrf", ""},
               {"name", req.principal},
               {"scopes", scopesJson({Scope::Read, Scope::Submit, Scope::Operate})}});
    return;
  }
  if (req.method == "DELETE") {
    res.audit = json{{"session", "logout"}}.dump();
    // Ended on the server too: the old cookie is refused from now on, wherever a copy of it is.
    d_.sessions.revoke(cookieValue(req.get_header_value("Cookie"), kSessionCookie), nowS());
    res.set_header("Set-Cookie", d_.sessions.clearCookie());
    replyJson(res, 200, {{"auth", "none"}});
    return;
  }
  if (req.method == "POST") {
    // Made from the bearer token (the login form sends it once, in the header, never in a URL).
    res.audit = json{{"session", "login"}}.dump();
    const auto cookie = d_.sessions.issue(req.principal, nowS());
    const auto s = cookie ? d_.sessions.check(*cookie, nowS()) : std::nullopt;
    if (!s) {
      replyJson(res, 401, problem("unauthorized", "the token \"" + req.principal + "\" is no longer valid"));
      return;
    }
    res.set_header("Set-Cookie", d_.sessions.setCookie(*cookie));
    replyJson(res, 201, {{"auth", "session"}, {"csrf", s->csrf}, {"expires_in_s", d_.sessions.lifetimeS()}});
    return;
  }
  // A request with an Authorization header is the bearer token's, whatever cookie it carries.
  const auto s = req.get_header_value("Authorization").empty()
                     ? d_.sessions.check(cookieValue(req.get_header_value("Cookie"), kSessionCookie), nowS())
                     : std::nullopt;
  const auto who = s ? std::optional<Principal>(s->who) : d_.sessions.principal(req.principal);
  replyJson(res, 200,
            {{"auth", s ? "session" : "bearer"},
             {"csrf", s ? s->csrf : ""},
             {"name", req.principal},
             {"scopes", scopesJson(who ? who->scopes : std::set<Scope>{})}});
}

void Dashboard::robotAction(const Request& req, Response& res, const std::string& action) {
  const std::string id = req.matches[1];
  res.audit = json{{"robot", id}, {"action", action}}.dump(-1, ' ', false, json::error_handler_t::replace);
  if (!isValidId(id)) {
    replyJson(res, 400, invalidField("id", "not a valid robot id (1-63 characters of A-Z a-z 0-9 _ . : -)"));
    return;
  }
  std::optional<msg::RobotState> robot;
  for (auto& r : d_.view.robots()) {
    if (r.robot_id == id) {
      robot = r;
    }
  }
  if (!robot) {
    replyJson(res, 404, problem("not_found", "no robot with id \"" + id + "\""));
    return;
  }
  if (!d_.gateway.managerOnline()) {
    res.set_header("Retry-After", "2");
    replyJson(res, 503, problem("unavailable", "the fleet manager is unreachable; nothing was sent"));
    return;
  }
  if (action == "pause" || action == "resume") {
    hold(id, action == "pause", res);
  } else {
    sendTo(*robot, action, req, res);
  }
}

void Dashboard::hold(const std::string& robot, bool held, Response& res) {
  msg::Task m;
  m.task_id = robot;
  m.robot = robot;
  m.request_id = d_.requestId();
  m.control = held ? msg::TaskControl::HoldRobot : msg::TaskControl::ReleaseRobot;
  const auto a = d_.gateway.submit({m}, std::chrono::milliseconds(d_.ackTimeoutMs))[0];
  if (!a) {
    res.set_header("Retry-After", "2");
    replyJson(
        res, 503,
        problem("unavailable", "the fleet manager did not acknowledge in time; retry (it is idempotent)"));
  } else if (a->result == msg::AckResult::Stored) {
    replyJson(res, 200, {{"robot", robot}, {"paused", held}, {"task", a->detail}});
  } else if (a->result == msg::AckResult::NotFound) {
    replyJson(res, 404, problem("not_found", "the fleet manager knows no robot \"" + robot + "\""));
  } else {
    replyJson(res, 409, problem("conflict", a->detail));
  }
}

void Dashboard::sendTo(const msg::RobotState& robot, const std::string& action, const Request& req,
                       Response& res) {
  const bool home = action == "home";
  std::string station;
  if (!req.body.empty()) {
    const auto parsed = parseBoundedJson(req.body, {.maxBytes = 4096, .maxDepth = 4, .maxElements = 64});
    const json body = parsed ? *parsed : json();
    if (!body.is_object() || (body.contains("station") && !body["station"].is_string())) {
      replyJson(res, 400,
                invalidField("station", "expected a JSON object with an optional string \"station\""));
      return;
    }
    station = body.value("station", "");
  }
  if (station.empty() && home) {
    std::lock_guard lock(siteMutex_);
    const auto it = homes_.find(robot.robot_id);
    station = it != homes_.end() ? it->second : "";
  }
  if (station.empty()) {
    const Station* s =
        nearest(d_.stations, home ? StationKind::Parking : StationKind::Charging, robot.pose.position());
    if (s == nullptr) {
      replyJson(res, 409,
                problem("conflict",
                        std::string("the site has no ") + (home ? "parking" : "charging") + " station"));
      return;
    }
    station = s->name;
  }
  const std::int64_t now = d_.clock.nowNs();
  const std::string id = action + "-" + robot.robot_id + "-" + std::to_string(now / 1'000'000);
  const json taskJson = {{"id", id},
                         {"kind", home ? "park" : "charge"},
                         {"station", station},
                         {"robot", robot.robot_id},
                         {"priority", 100}};
  auto task = parseTask(taskJson, &d_.stations);
  if (!task) {
    json fields = json::array();
    for (const auto& f : task.error().fields) {
      fields.push_back({{"path", f.path}, {"reason", f.reason}});
    }
    replyJson(res, 400, {{"error", "invalid"}, {"message", task.error().message}, {"fields", fields}});
    return;
  }
  const auto a = d_.gateway.submit({fleet::toWire(*task, d_.requestId(), now)},
                                   std::chrono::milliseconds(d_.ackTimeoutMs))[0];
  if (!a) {
    replyJson(res, 503, problem("unavailable", "the fleet manager did not acknowledge the task in time"));
    return;
  }
  if (a->result != msg::AckResult::Stored && a->result != msg::AckResult::Duplicate) {
    replyJson(res, a->result == msg::AckResult::Invalid ? 400 : 409, problem("refused", a->detail));
    return;
  }
  d_.view.onAccepted(id, toJson(*task).dump(), a->state, now);
  replyJson(
      res, 201,
      {{"robot", robot.robot_id}, {"task", id}, {"station", station}, {"state", msg::toString(a->state)}});
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
                         {"eta_ns", t.etaNs}});
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
                    {"station", e.station},   {"eta_ns", e.eta_ns}}
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
