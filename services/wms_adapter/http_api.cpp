#include "http_api.hpp"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <random>

#include "closure_request.hpp"
#include "fleet/core/bounded_json.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/core/log_text.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/fleet/task_wire.hpp"
#include "json_reply.hpp"
#include "postgres_event_store.hpp"
#include "rfc3339.hpp"
#include "status_routes.hpp"
#include "task_times.hpp"

namespace fleet::wms {
namespace {

using nlohmann::json;

json error(const std::string& code, const std::string& message) {
  return {{"error", code}, {"message", message}};
}

json fieldsJson(const std::vector<FieldError>& fields) {
  json a = json::array();
  for (const auto& f : fields) {
    a.push_back({{"path", f.path}, {"reason", f.reason}});
  }
  return a;
}

json viewJson(const TaskView& v) {
  json j = {{"id", v.id}, {"state", msg::toString(v.state)}, {"updated_ns", v.updatedNs}};
  if (v.updatedNs > 0) {
    j["updated"] = toRfc3339(v.updatedNs);
  }
  if (!v.robot.empty()) {
    j["robot"] = v.robot;
  }
  if (!v.reason.empty()) {
    j["reason"] = v.reason;
  }
  if (v.etaNs > 0) {
    // When the manager expects the task done, as estimated at its newest transition.
    j["eta_ns"] = v.etaNs;
    j["eta"] = toRfc3339(v.etaNs);
  }
  if (!v.body.empty()) {
    j["task"] = json::parse(v.body, nullptr, false);
  }
  if (j.contains("task")) {
    showTaskTimes(j["task"]);
  }
  if (v.step > 0) {
    // A multi-stop task: the stop its robot is at or driving to, from 1 (the last once done).
    j["step"] = v.step;
  }
  if (!v.station.empty()) {
    // Chosen by the manager for a charge / park task sent without a station.
    j["station"] = v.station;
    j["station_chosen"] = true;
    if (j.contains("task") && j["task"].is_object()) {
      j["task"]["station"] = v.station;
    }
  }
  return j;
}

/// Per-item outcome of a submit as (HTTP status, JSON).
std::pair<int, json> outcome(const Task& t, const std::optional<msg::TaskAck>& a) {
  if (!a) {
    return {503,
            {{"id", t.id},
             {"status", 503},
             {"error", "unavailable"},
             {"message", "the fleet manager did not acknowledge the task in time; retry with the same id"}}};
  }
  switch (a->result) {
    case msg::AckResult::Stored:
      return {201, {{"id", t.id}, {"status", 201}, {"result", "stored"}, {"state", msg::toString(a->state)}}};
    case msg::AckResult::Duplicate:
      return {200,
              {{"id", t.id}, {"status", 200}, {"result", "duplicate"}, {"state", msg::toString(a->state)}}};
    case msg::AckResult::Conflict:
      return {409,
              {{"id", t.id},
               {"status", 409},
               {"error", "conflict"},
               {"message", "a task with this id and a different body exists"}}};
    case msg::AckResult::Invalid: {
      json fields = json::parse(a->detail, nullptr, false);
      return {400,
              {{"id", t.id},
               {"status", 400},
               {"error", "invalid"},
               {"fields", fields.is_discarded() ? json(a->detail) : fields}}};
    }
    default:
      return {503, {{"id", t.id}, {"status", 503}, {"error", "unavailable"}, {"message", a->detail}}};
  }
}

}  // namespace

namespace {
TokenStore tokenStoreOf(const ApiSettings& s) {
  if (!s.tokenFile.empty()) {
    auto t = TokenStore::fromFile(s.tokenFile);
    if (!t) {
      throw ConfigError({"http.token_file: " + t.error().message});
    }
    return std::move(*t);
  }
  return s.token.empty() ? TokenStore() : TokenStore::single("token", s.token);
}
}  // namespace

namespace {

std::vector<msg::TaskEvent> eventsOf(const std::vector<LoggedEvent>& rows) {
  std::vector<msg::TaskEvent> out;
  out.reserve(rows.size());
  for (const auto& r : rows) {
    out.push_back(r.event);
  }
  return out;
}

}  // namespace

HttpApi::HttpApi(ApiSettings settings, const StationMap& stations, TaskGateway& gateway, FleetView& view,
                 const Clock& clock)
    : settings_(std::move(settings)),
      stations_(stations),
      gateway_(gateway),
      view_(view),
      clock_(clock),
      tokens_(tokenStoreOf(settings_)),
      sessions_(tokens_, settings_.tls.enabled()),
      audit_(settings_.auditLog),
      server_(settings_.limits, settings_.tls) {
  std::random_device rd;
  instance_ = std::to_string(rd() % 1'000'000);
  try {
    if (isPostgresUrl(settings_.events.path)) {
      // Shared by the adapter replicas on that database (postgres_event_store.hpp).
      events_ = std::make_unique<EventLog>(settings_.events,
                                           std::make_unique<PostgresEventStore>(settings_.events.path));
      webhooks_ = std::make_unique<Webhooks>(
          settings_.webhooks, std::make_unique<PostgresWebhookStore>(settings_.events.path), *events_);
    } else {
      stateDb_ = std::make_shared<SqliteDb>(settings_.events.path);
      events_ = std::make_unique<EventLog>(settings_.events, stateDb_);
      webhooks_ = std::make_unique<Webhooks>(settings_.webhooks, stateDb_, *events_);
    }
    // The view starts from what the log holds (a restarted adapter lists the tasks it had), and
    // takes what other replicas logged.
    for (std::int64_t at = events_->prunedThrough();;) {
      const auto rows = events_->after(at, 4096);
      if (rows.empty()) {
        break;
      }
      view_.catchUp(eventsOf(rows));
      at = rows.back().id;
    }
    events_->onCatchUp([this](const std::vector<LoggedEvent>& rows) { view_.catchUp(eventsOf(rows)); });
  } catch (const std::runtime_error& e) {
    throw ConfigError({std::string("events.log: ") + e.what()});
  }
  routes();
  view_.setEventLog(events_.get());
}

HttpApi::~HttpApi() {
  view_.dropEventLog(events_.get());
  webhooks_->stop();
}

nlohmann::json HttpApi::eventLogJson() const {
  const auto hooks = webhooks_->list();
  const auto failing =
      std::count_if(hooks.begin(), hooks.end(), [](const auto& w) { return w.state == "failing"; });
  return {{"last_id", events_->lastId()},       {"pruned_through", events_->prunedThrough()},
          {"durable", events_->durable()},      {"append_failures", view_.eventLogFailures()},
          {"problem", view_.eventLogProblem()}, {"webhooks", hooks.size()},
          {"webhooks_failing", failing},        {"stale_epoch_events", view_.staleEpochEvents()}};
}

std::string HttpApi::nextRequestId() {
  return "wms" + instance_ + "-" + std::to_string(++requestCounter_);
}

bool HttpApi::bind() {
  return server_.bind(settings_.host, settings_.port);
}

void HttpApi::serve() {
  server_.serve();
}
void HttpApi::stop() {
  server_.stop();
}

void HttpApi::instrument(metrics::Registry& registry) {
  registry_ = &registry;
  requestSeconds_ = &registry.histogram("wms_adapter_http_request_duration_seconds",
                                        "Time from a request's routing to its response being ready",
                                        metrics::exponentialBuckets(1e-4, 2.0, 18));
}

void HttpApi::observe(const Request& req, const Response& res, double seconds) {
  ++counters_.requests;
  if (registry_ != nullptr) {
    registry_
        ->counter("wms_adapter_http_responses_total", "HTTP responses of the WMS API, by status code",
                  {{"code", std::to_string(res.status)}})
        .inc();
    requestSeconds_->observe(seconds);
    // The access log: client, who, method, path (no query string: short lines, nothing a client
    // put there by mistake), status, body bytes, time. Never the Authorization header. What the
    // client chose is escaped as in the audit log: a decoded %0d%0a cannot start a forged line.
    spdlog::info("access {} {} {} {} {} {} {:.6f}s", req.remote_addr,
                 req.principal.empty() ? "-" : escapeForLog(req.principal), escapeForLog(req.method),
                 escapeForLog(req.path), res.status, res.body.size(), seconds);
  }
  audit_.record(req, res,
                std::chrono::duration_cast<std::chrono::nanoseconds>(
                    std::chrono::system_clock::now().time_since_epoch())
                    .count());
  if (res.status >= 500) {
    ++counters_.status5xx;
  } else if (res.status >= 400) {
    ++counters_.status4xx;
  } else {
    ++counters_.status2xx;
  }
  if (watcher_) {
    watcher_(req, res);
  }
}

void HttpApi::routes() {
  server_.setGate(
      [this](Request& req, Response& res, Scope scope) { return access_.admit(req, res, scope); });
  server_.setObserver([this](const Request& req, const Response& res, double s) { observe(req, res, s); });
  using Run = HttpServer::Run;
  dashboard_ = std::make_unique<Dashboard>(
      server_, DashboardDeps{sessions_, stations_, gateway_, view_, clock_,
                             [this] { return nextRequestId(); }, settings_.ackTimeoutMs});
  server_.limitBody("POST", "/v1/tasks", settings_.maxTaskBodyBytes, "http.max_task_body_bytes");
  server_.route("POST", "/v1/tasks", Scope::Submit,
                [this](const Request& req, Response& res) { postTasks(req, res); });
  server_.route("DELETE", R"(/v1/tasks/([^/]+))", Scope::Submit,
                [this](const Request& req, Response& res) { deleteTask(req, res); });
  // A change of a waiting task's priority and deadline: scoped as a submission (the WMS owns both).
  server_.limitBody("PATCH", R"(/v1/tasks/([^/]+))", 64 * 1024, "the change route's fixed limit");
  server_.route("PATCH", R"(/v1/tasks/([^/]+))", Scope::Submit,
                [this](const Request& req, Response& res) { patchTask(req, res); });
  server_.route("POST", R"(/v1/tasks/([^/]+)/pause)", Scope::Operate,
                [this](const Request& req, Response& res) { controlTask(req, res, true); });
  server_.route("POST", R"(/v1/tasks/([^/]+)/resume)", Scope::Operate,
                [this](const Request& req, Response& res) { controlTask(req, res, false); });
  server_.route("GET", R"(/v1/tasks/([^/]+))", Scope::Read, [this](const Request& req, Response& res) {
    const std::string id = req.matches[1];
    auto v = view_.task(id);
    if (!v && isValidId(id) && gateway_.managerOnline()) {
      // Not in the view (an adapter started after the task's events, or the view forgot it): the
      // manager's store decides.
      const auto a = gateway_.query(id, nextRequestId(), std::chrono::milliseconds(settings_.ackTimeoutMs));
      if (a && a->result == msg::AckResult::Stored) {
        view_.onStored(*a, clock_.nowNs());
        v = view_.task(id);
      }
    }
    if (!v) {
      replyJson(res, 404, error("not_found", "no task with id \"" + id + "\""));
      return;
    }
    replyJson(res, 200, viewJson(*v));
  });
  server_.route("GET", "/v1/tasks", Scope::Read, [this](const Request& req, Response& res) {
    std::optional<msg::TaskState> state;
    if (req.has_param("state")) {
      msg::TaskState s{};
      if (!msg::parse(req.get_param_value("state"), s)) {
        replyJson(
            res, 400,
            {{"error", "invalid"},
             {"fields",
              json::array({{{"path", "state"},
                            {"reason", "unknown task state \"" + req.get_param_value("state") + "\""}}})}});
        return;
      }
      state = s;
    }
    std::size_t limit = 1000;
    if (req.has_param("limit")) {
      const std::string l = req.get_param_value("limit");
      char* end = nullptr;
      const long v = std::strtol(l.c_str(), &end, 10);
      if (l.empty() || *end != '\0' || v < 1 || v > 100000) {
        replyJson(res, 400,
                  {{"error", "invalid"},
                   {"fields",
                    json::array({{{"path", "limit"}, {"reason", "expected an integer in [1, 100000]"}}})}});
        return;
      }
      limit = static_cast<std::size_t>(v);
    }
    json items = json::array();
    for (const auto& v : view_.tasks(state, limit)) {
      items.push_back(viewJson(v));
    }
    replyJson(res, 200, {{"tasks", items}, {"count", items.size()}});
  });
  // Roadmap closures: an operator closes part of the roadmap (a spill, maintenance) and reopens
  // it; the traffic manager plans round it. Accepted (202) once sent: the traffic manager applies
  // it when it reads it (the Roadmap's revision grows and its open flags show it).
  server_.route("GET", "/v1/traffic/closures", Scope::Read, [this](const Request&, Response& res) {
    json items = json::array();
    for (const auto& [id, c] : view_.closures()) {
      items.push_back(closureJson(c));
    }
    const auto [count, roadmap] = view_.roadmap();
    json body = {{"closures", items},
                 {"count", items.size()},
                 {"traffic_manager_online", gateway_.trafficManagerOnline()}};
    if (roadmap) {
      const auto closed =
          static_cast<std::size_t>(std::count(roadmap->open.begin(), roadmap->open.end(), false));
      body["roadmap"] = {
          {"epoch", roadmap->epoch}, {"revision", roadmap->revision}, {"closed_nodes", closed}};
    }
    replyJson(res, 200, body);
  });
  server_.limitBody("PUT", R"(/v1/traffic/closures/([^/]+))", 64 * 1024, "the closure route's fixed limit");
  server_.route("PUT", R"(/v1/traffic/closures/([^/]+))", Scope::Operate,
                [this](const Request& req, Response& res) { putClosure(req, res); });
  server_.route("DELETE", R"(/v1/traffic/closures/([^/]+))", Scope::Operate,
                [this](const Request& req, Response& res) { deleteClosure(req, res); });
  server_.route("GET", "/v1/robots", Scope::Read, [this](const Request&, Response& res) {
    json items = json::array();
    const auto people = view_.allPeopleSeen(steadyNowNs());
    for (const auto& r : view_.robots()) {
      const auto p = people.find(r.robot_id);
      items.push_back(robotJson(r, p != people.end() ? &p->second : nullptr));
    }
    replyJson(res, 200, {{"robots", items}, {"count", items.size()}});
  });
  server_.route("GET", "/v1/fleet/robot-time", Scope::Read, [this](const Request&, Response& res) {
    replyJson(res, 200, robotTimeJson(view_.robotTime()));
  });
  // Health tells nothing secret and a probe carries no token: public, and answered on the I/O
  // thread so that busy workers never make the adapter look dead.
  server_.route(
      "GET", "/v1/health", Scope::Public,
      [this](const Request&, Response& res) {
        const bool up = gateway_.managerOnline();
        replyJson(res, up ? 200 : 503,
                  {{"status", up ? "ok" : "degraded"}, {"fleet_manager", up ? "online" : "unreachable"}});
      },
      Run::Inline);
  server_.route("GET", "/v1/metrics", Scope::Read, [this](const Request&, Response& res) {
    const auto& h = server_.stats();
    replyJson(res, 200,
              {{"requests", counters_.requests.load()},
               {"responses",
                {{"2xx", counters_.status2xx.load()},
                 {"4xx", counters_.status4xx.load()},
                 {"5xx", counters_.status5xx.load()}}},
               {"tasks_accepted", counters_.tasksAccepted.load()},
               {"tasks_duplicate", counters_.tasksDuplicate.load()},
               {"tasks_by_state", view_.countByState()},
               {"robots", view_.robots().size()},
               {"proximity", proximityJson(view_.proximity())},
               {"fleet_manager_online", gateway_.managerOnline()},
               {"event_log", eventLogJson()},
               {"samples", view_.rejections().toJson()},
               {"http",
                {{"open_connections", h.openConnections.load()},
                 {"open_streams", h.openStreams.load()},
                 {"refused_connections", h.refusedConnections.load()},
                 {"refused_streams", h.refusedStreams.load()},
                 {"busy", h.busy.load()},
                 {"rate_limited", h.rateLimited.load()},
                 {"too_large", h.tooLarge.load()},
                 {"timed_out", h.timedOut.load()},
                 {"tls_failures", h.tlsFailures.load()},
                 {"token_reloads", tokens_.reloads()},
                 {"token_file_problem", tokens_.lastProblem()},
                 {"audit_write_failures", audit_.writeFailures()}}}});
  });
  addStatusRoutes(server_, *events_, *webhooks_, [this] { return clock_.nowNs(); });
}

void HttpApi::postTasks(const Request& req, Response& res) {
  // Bounded before any document is built: a task is a handful of values, nested a few levels.
  auto parsed_json = parseBoundedJson(
      req.body,
      {.maxBytes = settings_.maxTaskBodyBytes, .maxDepth = 16, .maxElements = 64 * settings_.maxBatch + 64});
  if (!parsed_json) {
    const bool invalid = parsed_json.error().code == "json.invalid";
    replyJson(res, invalid ? 400 : 413,
              {{"error", invalid ? "invalid_json" : parsed_json.error().code.substr(5)},
               {"message", "the body is not acceptable: " + parsed_json.error().message}});
    return;
  }
  json& body = *parsed_json;
  const bool batch = body.is_array() || (body.is_object() && body.contains("tasks"));
  const std::size_t n =
      body.is_array() ? body.size() : (batch && body["tasks"].is_array() ? body["tasks"].size() : 1);
  if (n > settings_.maxBatch) {
    replyJson(res, 413,
              error("too_large", "batch of " + std::to_string(n) + " tasks, at most " +
                                     std::to_string(settings_.maxBatch) + " allowed"));
    return;
  }
  if (const auto times = acceptTaskTimes(body); !times.empty()) {
    replyJson(res, 400,
              {{"error", "invalid"}, {"message", "a time is not acceptable"}, {"fields", fieldsJson(times)}});
    return;
  }
  auto parsed = parseTasks(body, &stations_);
  if (!parsed) {
    replyJson(res, 400,
              {{"error", "invalid"},
               {"message", parsed.error().message},
               {"fields", fieldsJson(parsed.error().fields)}});
    return;
  }
  if (!gateway_.managerOnline()) {
    res.set_header("Retry-After", "2");
    replyJson(res, 503, error("unavailable", "the fleet manager is unreachable; nothing was stored"));
    return;
  }
  std::vector<std::string> ids;
  for (const auto& t : *parsed) {
    ids.push_back(t.id);
  }
  res.audit = json{{"tasks", ids}}.dump();
  const std::int64_t now = clock_.nowNs();
  std::vector<msg::Task> requests;
  for (const auto& t : *parsed) {
    requests.push_back(fleet::toWire(t, nextRequestId(), now));
  }
  const auto acks = gateway_.submit(requests, std::chrono::milliseconds(settings_.ackTimeoutMs));
  json results = json::array();
  int first = 0;
  bool same = true;
  for (std::size_t i = 0; i < parsed->size(); ++i) {
    auto [status, item] = outcome((*parsed)[i], acks[i]);
    if (status == 201 || status == 200) {
      ++(status == 201 ? counters_.tasksAccepted : counters_.tasksDuplicate);
      view_.onAccepted((*parsed)[i].id, toJson((*parsed)[i]).dump(), acks[i]->state, now);
    }
    if (i == 0) {
      first = status;
    }
    same = same && status == first;
    results.push_back(item);
  }
  if (!batch) {
    if (first == 503) {
      res.set_header("Retry-After", "2");
    }
    replyJson(res, first, results[0]);
    return;
  }
  const bool allOk = std::all_of(results.begin(), results.end(),
                                 [](const json& r) { return r["status"] == 200 || r["status"] == 201; });
  int status = same ? first : (allOk ? 200 : 207);
  replyJson(res, status, {{"results", results}});
}

bool HttpApi::admitTaskRequest(const std::string& id, const char* verb, Response& res) {
  if (!isValidId(id)) {
    replyJson(res, 400,
              {{"error", "invalid"},
               {"fields", json::array({{{"path", "id"}, {"reason", "not a valid task id"}}})}});
    return false;
  }
  if (!gateway_.managerOnline()) {
    res.set_header("Retry-After", "2");
    replyJson(res, 503,
              error("unavailable", std::string("the fleet manager is unreachable; nothing was ") + verb));
    return false;
  }
  return true;
}

void HttpApi::deleteTask(const Request& req, Response& res) {
  const std::string id = req.matches[1];
  res.audit = json{{"task", id}, {"action", "cancel"}}.dump();
  if (!admitTaskRequest(id, "cancelled", res)) {
    return;
  }
  msg::Task m;
  m.task_id = id;
  m.request_id = nextRequestId();
  m.cancel = true;
  const auto acks = gateway_.submit({m}, std::chrono::milliseconds(settings_.ackTimeoutMs));
  const auto& a = acks[0];
  if (!a) {
    replyJson(res, 503, error("unavailable", "the fleet manager did not acknowledge the cancel in time"));
  } else if (a->result == msg::AckResult::Stored) {
    replyJson(res, 200, {{"id", id}, {"state", "cancelled"}});
  } else if (a->result == msg::AckResult::NotFound) {
    replyJson(res, 404, error("not_found", "no task with id \"" + id + "\""));
  } else {
    replyJson(res, 409, error("conflict", a->detail));
  }
}

void HttpApi::controlTask(const Request& req, Response& res, bool pause) {
  const std::string id = req.matches[1];
  res.audit = json{{"task", id}, {"action", pause ? "pause" : "resume"}}.dump();
  if (!admitTaskRequest(id, pause ? "paused" : "resumed", res)) {
    return;
  }
  msg::Task m;
  m.task_id = id;
  m.request_id = nextRequestId();
  m.control = pause ? msg::TaskControl::Pause : msg::TaskControl::Resume;
  const auto acks = gateway_.submit({m}, std::chrono::milliseconds(settings_.ackTimeoutMs));
  const auto& a = acks[0];
  if (!a) {
    res.set_header("Retry-After", "2");
    replyJson(res, 503,
              error("unavailable",
                    "the fleet manager did not acknowledge in time; retry (pause and resume "
                    "are idempotent)"));
  } else if (a->result == msg::AckResult::Stored) {
    replyJson(res, 200, {{"id", id}, {"paused", pause}, {"state", msg::toString(a->state)}});
  } else if (a->result == msg::AckResult::NotFound) {
    replyJson(res, 404, error("not_found", "no task with id \"" + id + "\""));
  } else {
    replyJson(res, 409, error("conflict", a->detail));
  }
}

void HttpApi::putClosure(const Request& req, Response& res) {
  const std::string id = req.matches[1];
  res.audit = json{{"closure", id}, {"action", "close"}}.dump();
  const auto roadmap = view_.roadmap().second;
  auto parsed = parseClosure(id, req.body, roadmap ? std::optional(roadmap->nodes.size()) : std::nullopt,
                             clock_.nowNs());
  if (auto* errors = std::get_if<std::vector<FieldError>>(&parsed)) {
    replyJson(
        res, 400,
        {{"error", "invalid"}, {"message", "the closure was not sent"}, {"fields", fieldsJson(*errors)}});
    return;
  }
  const auto& c = std::get<msg::TrafficClosure>(parsed);
  if (auto why = gateway_.sendClosure(c)) {
    replyJson(res, 503, error("unavailable", *why + "; the closure was not sent"));
    return;
  }
  json body = closureJson(c);
  body["traffic_manager_online"] = gateway_.trafficManagerOnline();
  replyJson(res, 202, body);
}

void HttpApi::deleteClosure(const Request& req, Response& res) {
  const std::string id = req.matches[1];
  res.audit = json{{"closure", id}, {"action", "reopen"}}.dump();
  if (!isValidId(id)) {
    replyJson(res, 400,
              error("invalid", "closure id \"" + id + "\" is not a valid id (1..63 of [A-Za-z0-9_.:-])"));
    return;
  }
  // Sent whether this adapter knows the id or not: a closure made through an adapter that has
  // since restarted is still in force in the traffic manager, and must be possible to reopen.
  const bool known = view_.closures().contains(id);
  msg::TrafficClosure c;
  c.closure_id = id;
  c.active = false;
  c.stamp_ns = clock_.nowNs();
  if (auto why = gateway_.sendClosure(c)) {
    replyJson(res, 503, error("unavailable", *why + "; the reopening was not sent"));
    return;
  }
  replyJson(res, 202,
            {{"id", id},
             {"active", false},
             {"known", known},
             {"traffic_manager_online", gateway_.trafficManagerOnline()}});
}

}  // namespace fleet::wms
