#include "dashboard.hpp"

#include <chrono>
#include <memory>
#include <set>

#include "dashboard_problem.hpp"
#include "json_reply.hpp"
#include "web_files.hpp"

namespace fleet::wms {

using dashboard_detail::problem;
using nlohmann::json;

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
}  // namespace fleet::wms
