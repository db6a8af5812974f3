#include "http_api.hpp"

#include <spdlog/spdlog.h>

#include <chrono>
#include <cstdlib>
#include <fstream>
#include <random>

#include "fleet/core/ids.hpp"
#include "fleet/fleet/task.hpp"
#include "fleet/service/ops_server.hpp"
#include "fleet/service/task_wire.hpp"

namespace fleet::wms {
namespace {

using nlohmann::json;

/// JSON text; a string that is not UTF-8 (which the edge repairs, so none should arrive) is
/// written with U+FFFD instead of making dump() throw.
std::string dumpJson(const json& j) {
  return j.dump(-1, ' ', false, json::error_handler_t::replace);
}

void reply(httplib::Response& res, int status, const json& body) {
  res.status = status;
  res.set_content(dumpJson(body), "application/json");
}

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
  if (!v.robot.empty()) {
    j["robot"] = v.robot;
  }
  if (!v.reason.empty()) {
    j["reason"] = v.reason;
  }
  if (!v.body.empty()) {
    j["task"] = json::parse(v.body, nullptr, false);
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

ApiSettings readApiSettings(Config& cfg) {
  ApiSettings s;
  auto h = cfg.child("http");
  h.rejectUnknownKeys({"host", "port", "token_file", "max_body_bytes", "max_batch", "ack_timeout_ms",
                       "max_in_flight", "threads"});
  s.host = h.string("host", s.host);
  s.port = static_cast<int>(h.integer("port", s.port, {0, 65535}));
  s.maxBodyBytes = static_cast<std::size_t>(
      h.integer("max_body_bytes", static_cast<std::int64_t>(s.maxBodyBytes), {1024, 256.0 * 1024 * 1024}));
  s.maxBatch =
      static_cast<std::size_t>(h.integer("max_batch", static_cast<std::int64_t>(s.maxBatch), {1, 100000}));
  s.ackTimeoutMs = static_cast<int>(h.integer("ack_timeout_ms", s.ackTimeoutMs, {1, 600000}));
  s.maxInFlight = static_cast<int>(h.integer("max_in_flight", s.maxInFlight, {1, 100000}));
  s.threads = static_cast<int>(h.integer("threads", s.threads, {1, 256}));
  const std::string tokenFile = h.string("token_file", "");
  if (!tokenFile.empty()) {
    std::ifstream in(tokenFile);
    if (!in || !std::getline(in, s.token) || s.token.empty()) {
      h.problem("token_file", "cannot read a token from \"" + tokenFile + "\"");
    }
  } else if (const char* env = std::getenv("FLEET_WMS_TOKEN"); env != nullptr) {
    s.token = env;
  }
  return s;
}

HttpApi::HttpApi(ApiSettings settings, const StationMap& stations, TaskGateway& gateway, FleetView& view,
                 const Clock& clock)
    : settings_(std::move(settings)), stations_(stations), gateway_(gateway), view_(view), clock_(clock) {
  std::random_device rd;
  instance_ = std::to_string(rd() % 1'000'000);
  server_.new_task_queue = [n = settings_.threads] {
    return new httplib::ThreadPool(static_cast<std::size_t>(n));
  };
  server_.set_payload_max_length(settings_.maxBodyBytes);
  service::bindExclusively(server_);  // a second adapter on a taken port fails instead of sharing it
  routes();
}

std::string HttpApi::nextRequestId() {
  return "wms" + instance_ + "-" + std::to_string(++requestCounter_);
}

bool HttpApi::bind() {
  if (settings_.port == 0) {
    port_ = server_.bind_to_any_port(settings_.host);
    return port_ > 0;
  }
  port_ = settings_.port;
  return server_.bind_to_port(settings_.host, settings_.port);
}

void HttpApi::serve() {
  server_.listen_after_bind();
}
void HttpApi::stop() {
  server_.stop();
}

namespace {
// httplib runs a request's pre- and post-routing handlers on the same worker thread.
thread_local std::chrono::steady_clock::time_point requestStart;
}  // namespace

void HttpApi::instrument(metrics::Registry& registry) {
  registry_ = &registry;
  requestSeconds_ = &registry.histogram("wms_adapter_http_request_duration_seconds",
                                        "Time from a request's routing to its response being ready",
                                        metrics::exponentialBuckets(1e-4, 2.0, 18));
}

void HttpApi::routes() {
  dashboard_ = std::make_unique<Dashboard>(
      server_, DashboardDeps{settings_.token, stations_, gateway_, view_, clock_,
                             [this] { return nextRequestId(); }, settings_.ackTimeoutMs});
  server_.set_pre_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    ++counters_.requests;
    requestStart = std::chrono::steady_clock::now();
    // Bearer token or browser session; health and the page's static files need neither.
    return dashboard_->admit(req, res) ? httplib::Server::HandlerResponse::Unhandled
                                       : httplib::Server::HandlerResponse::Handled;
  });
  server_.set_post_routing_handler([this](const httplib::Request& req, httplib::Response& res) {
    if (registry_ != nullptr) {
      const double seconds =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - requestStart).count();
      registry_
          ->counter("wms_adapter_http_responses_total", "HTTP responses of the WMS API, by status code",
                    {{"code", std::to_string(res.status)}})
          .inc();
      requestSeconds_->observe(seconds);
      // The access log: client, method, path (no query string: short lines, nothing a client put
      // there by mistake), status, body bytes, time. Never the Authorization header.
      spdlog::info("access {} {} {} {} {} {:.6f}s", req.remote_addr, req.method, req.path, res.status,
                   res.body.size(), seconds);
    }
    if (res.status >= 500) {
      ++counters_.status5xx;
    } else if (res.status >= 400) {
      ++counters_.status4xx;
    } else {
      ++counters_.status2xx;
    }
  });
  server_.set_error_handler([](const httplib::Request&, httplib::Response& res) {
    if (res.body.empty()) {
      const std::string code = res.status == 413 ? "too_large" : res.status == 404 ? "not_found" : "error";
      reply(res, res.status,
            error(code, code == "too_large" ? "the body is larger than the configured limit"
                                            : "HTTP " + std::to_string(res.status)));
    }
  });
  server_.set_exception_handler([](const httplib::Request&, httplib::Response& res, std::exception_ptr ep) {
    std::string what = "internal error";
    try {
      std::rethrow_exception(ep);
    } catch (const std::exception& e) {
      what = e.what();
    } catch (...) {
    }
    reply(res, 500, error("internal", what));
  });

  server_.Post("/v1/tasks",
               [this](const httplib::Request& req, httplib::Response& res) { postTasks(req, res); });
  server_.Delete(R"(/v1/tasks/([^/]+))",
                 [this](const httplib::Request& req, httplib::Response& res) { deleteTask(req, res); });
  server_.Post(R"(/v1/tasks/([^/]+)/pause)",
               [this](const httplib::Request& req, httplib::Response& res) { controlTask(req, res, true); });
  server_.Post(R"(/v1/tasks/([^/]+)/resume)",
               [this](const httplib::Request& req, httplib::Response& res) { controlTask(req, res, false); });
  server_.Get(R"(/v1/tasks/([^/]+))", [this](const httplib::Request& req, httplib::Response& res) {
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
      reply(res, 404, error("not_found", "no task with id \"" + id + "\""));
      return;
    }
    reply(res, 200, viewJson(*v));
  });
  server_.Get("/v1/tasks", [this](const httplib::Request& req, httplib::Response& res) {
    std::optional<msg::TaskState> state;
    if (req.has_param("state")) {
      msg::TaskState s{};
      if (!msg::parse(req.get_param_value("state"), s)) {
        reply(res, 400,
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
        reply(res, 400,
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
    reply(res, 200, {{"tasks", items}, {"count", items.size()}});
  });
  server_.Get("/v1/robots", [this](const httplib::Request&, httplib::Response& res) {
    json items = json::array();
    for (const auto& r : view_.robots()) {
      items.push_back(robotJson(r));
    }
    reply(res, 200, {{"robots", items}, {"count", items.size()}});
  });
  server_.Get("/v1/health", [this](const httplib::Request&, httplib::Response& res) {
    const bool up = gateway_.managerOnline();
    reply(res, up ? 200 : 503,
          {{"status", up ? "ok" : "degraded"}, {"fleet_manager", up ? "online" : "unreachable"}});
  });
  server_.Get("/v1/metrics", [this](const httplib::Request&, httplib::Response& res) {
    reply(res, 200,
          {{"requests", counters_.requests.load()},
           {"responses",
            {{"2xx", counters_.status2xx.load()},
             {"4xx", counters_.status4xx.load()},
             {"5xx", counters_.status5xx.load()}}},
           {"tasks_accepted", counters_.tasksAccepted.load()},
           {"tasks_duplicate", counters_.tasksDuplicate.load()},
           {"tasks_by_state", view_.countByState()},
           {"robots", view_.robots().size()},
           {"fleet_manager_online", gateway_.managerOnline()},
           {"samples", view_.rejections().toJson()}});
  });
  // Server-sent events: every TaskEvent as `event: task` with the JSON of the event. The stream
  // ends when the client goes away or the server stops.
  server_.Get("/v1/events", [this](const httplib::Request&, httplib::Response& res) {
    auto cursor = std::make_shared<std::uint64_t>(view_.eventCursor());
    res.set_header("Cache-Control", "no-cache");
    res.set_chunked_content_provider(
        "text/event-stream", [this, cursor](std::size_t, httplib::DataSink& sink) {
          std::vector<msg::TaskEvent> evs;
          *cursor = view_.eventsAfter(*cursor, std::chrono::milliseconds(1000), evs);
          std::string chunk;
          for (const auto& e : evs) {
            chunk += "event: task\ndata: " +
                     dumpJson({{"id", e.task_id},
                               {"state", msg::toString(e.state)},
                               {"robot", e.robot_id},
                               {"reason", e.reason},
                               {"stamp_ns", e.stamp_ns},
                               {"seq", e.seq}}) +
                     "\n\n";
          }
          if (chunk.empty()) {
            chunk = ": keep-alive\n\n";
          }
          return sink.write(chunk.data(), chunk.size());
        });
  });
}

void HttpApi::postTasks(const httplib::Request& req, httplib::Response& res) {
  struct InFlight {
    std::atomic<int>& n;
    explicit InFlight(std::atomic<int>& c) : n(c) { ++n; }
    ~InFlight() { --n; }
  } guard(inFlight_);
  if (inFlight_.load() > settings_.maxInFlight) {
    res.set_header("Retry-After", "1");
    reply(res, 429, error("busy", "too many requests in flight; retry"));
    return;
  }
  json body = json::parse(req.body, nullptr, false);
  if (body.is_discarded()) {
    reply(res, 400, {{"error", "invalid_json"}, {"message", "the body is not valid JSON"}});
    return;
  }
  const bool batch = body.is_array() || (body.is_object() && body.contains("tasks"));
  const std::size_t n =
      body.is_array() ? body.size() : (batch && body["tasks"].is_array() ? body["tasks"].size() : 1);
  if (n > settings_.maxBatch) {
    reply(res, 413,
          error("too_large", "batch of " + std::to_string(n) + " tasks, at most " +
                                 std::to_string(settings_.maxBatch) + " allowed"));
    return;
  }
  auto parsed = parseTasks(body, &stations_);
  if (!parsed) {
    reply(res, 400,
          {{"error", "invalid"},
           {"message", parsed.error().message},
           {"fields", fieldsJson(parsed.error().fields)}});
    return;
  }
  if (!gateway_.managerOnline()) {
    res.set_header("Retry-After", "2");
    reply(res, 503, error("unavailable", "the fleet manager is unreachable; nothing was stored"));
    return;
  }
  const std::int64_t now = clock_.nowNs();
  std::vector<msg::Task> requests;
  for (const auto& t : *parsed) {
    requests.push_back(service::toWire(t, nextRequestId(), now));
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
    reply(res, first, results[0]);
    return;
  }
  const bool allOk = std::all_of(results.begin(), results.end(),
                                 [](const json& r) { return r["status"] == 200 || r["status"] == 201; });
  int status = same ? first : (allOk ? 200 : 207);
  reply(res, status, {{"results", results}});
}

bool HttpApi::admitTaskRequest(const std::string& id, const char* verb, httplib::Response& res) {
  if (!isValidId(id)) {
    reply(res, 400,
          {{"error", "invalid"},
           {"fields", json::array({{{"path", "id"}, {"reason", "not a valid task id"}}})}});
    return false;
  }
  if (!gateway_.managerOnline()) {
    res.set_header("Retry-After", "2");
    reply(res, 503,
          error("unavailable", std::string("the fleet manager is unreachable; nothing was ") + verb));
    return false;
  }
  return true;
}

void HttpApi::deleteTask(const httplib::Request& req, httplib::Response& res) {
  const std::string id = req.matches[1];
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
    reply(res, 503, error("unavailable", "the fleet manager did not acknowledge the cancel in time"));
  } else if (a->result == msg::AckResult::Stored) {
    reply(res, 200, {{"id", id}, {"state", "cancelled"}});
  } else if (a->result == msg::AckResult::NotFound) {
    reply(res, 404, error("not_found", "no task with id \"" + id + "\""));
  } else {
    reply(res, 409, error("conflict", a->detail));
  }
}

void HttpApi::controlTask(const httplib::Request& req, httplib::Response& res, bool pause) {
  const std::string id = req.matches[1];
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
    reply(res, 503,
          error("unavailable",
                "the fleet manager did not acknowledge in time; retry (pause and resume "
                "are idempotent)"));
  } else if (a->result == msg::AckResult::Stored) {
    reply(res, 200, {{"id", id}, {"paused", pause}, {"state", msg::toString(a->state)}});
  } else if (a->result == msg::AckResult::NotFound) {
    reply(res, 404, error("not_found", "no task with id \"" + id + "\""));
  } else {
    reply(res, 409, error("conflict", a->detail));
  }
}

}  // namespace fleet::wms
