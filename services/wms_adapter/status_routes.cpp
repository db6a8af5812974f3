#include "status_routes.hpp"

#include <algorithm>

#include "fleet/core/bounded_json.hpp"
#include "json_reply.hpp"
#include "webhook_url.hpp"

namespace fleet::wms {
namespace {

using nlohmann::json;

json fieldProblem(const std::string& path, const std::string& reason, const std::string& code = "invalid") {
  return {{"error", code},
          {"message", path + ": " + reason},
          {"fields", json::array({{{"path", path}, {"reason", reason}}})}};
}

/// A stream writes at most this many events per poll (every http stream poll, 100 ms): a client
/// far behind catches up in steps, the I/O thread never builds one huge chunk.
constexpr std::size_t kEventsPerPoll = 1000;

std::string retentionText(const EventLogSettings& s) {
  return "the newest " + std::to_string(s.retainEvents) + " events, none older than " +
         std::to_string(s.retainSeconds) + " s (events.retain_events, events.retain_seconds)";
}

}  // namespace

void readStatusSettings(Config& cfg, EventLogSettings& events, WebhookSettings& webhooks) {
  auto ev = cfg.child("events");
  ev.rejectUnknownKeys({"log", "retain_events", "retain_seconds"});
  events.path = ev.string("log", "");
  events.retainEvents = ev.integer("retain_events", events.retainEvents, {1, 1e9});
  events.retainSeconds = ev.integer("retain_seconds", events.retainSeconds, {1, 10.0 * 365 * 86400});
  auto wh = cfg.child("webhooks");
  wh.rejectUnknownKeys({"allow", "max_subscriptions", "timeout_ms", "max_attempts", "backoff_ms",
                        "backoff_max_ms", "failing_retry_ms", "ca_file"});
  auto& w = webhooks;
  if (const auto* allow = wh.find("allow"); allow != nullptr) {
    if (!allow->is_array()) {
      wh.problem("allow", "expected an array of URL prefixes (\"https://wms.example/hooks\")");
    } else {
      for (const auto& a : *allow) {
        std::string why;
        if (!a.is_string() || !parseWebhookUrl(a.get<std::string>(), &why)) {
          wh.problem("allow",
                     a.is_string() ? "\"" + a.get<std::string>() + "\": " + why : "expected strings");
        } else {
          w.allow.push_back(a.get<std::string>());
        }
      }
    }
  }
  w.maxSubscriptions = static_cast<int>(wh.integer("max_subscriptions", w.maxSubscriptions, {1, 1000}));
  w.timeoutMs = static_cast<int>(wh.integer("timeout_ms", w.timeoutMs, {10, 600000}));
  w.maxAttempts = static_cast<int>(wh.integer("max_attempts", w.maxAttempts, {1, 1000}));
  w.backoffMs = static_cast<int>(wh.integer("backoff_ms", w.backoffMs, {1, 3600000}));
  w.backoffMaxMs = static_cast<int>(wh.integer("backoff_max_ms", w.backoffMaxMs, {1, 86400000}));
  w.failingRetryMs = static_cast<int>(wh.integer("failing_retry_ms", w.failingRetryMs, {1, 86400000}));
  w.caFile = wh.string("ca_file", "");
}

std::optional<std::int64_t> resumePoint(const Request& req, EventLog& log, Response& res) {
  std::string field;
  std::string text;
  if (const auto h = req.get_header_value("Last-Event-ID"); !h.empty()) {
    field = "Last-Event-ID";
    text = h;
  } else if (req.has_param("since")) {
    field = "since";
    text = req.get_param_value("since");
  } else {
    return log.lastId();
  }
  if (text.empty() || text.size() > 18 ||
      !std::all_of(text.begin(), text.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    replyJson(res, 400,
              fieldProblem(field, "\"" + text.substr(0, 40) +
                                      "\" is not an event id (a whole number from an `id:` line)"));
    return std::nullopt;
  }
  const std::int64_t id = std::stoll(text);
  if (log.shared() && id > log.lastId()) {
    // An id another replica gave a moment ago, before this one looked: look now.
    try {
      log.catchUp();
    } catch (const std::exception&) {
      // The database is away: judged on what this replica holds.
    }
  }
  const std::int64_t last = log.lastId();
  const std::int64_t pruned = log.prunedThrough();
  if (id > last) {
    replyJson(
        res, 400,
        fieldProblem(
            field, "event " + text + " is ahead of this adapter's newest event " + std::to_string(last) +
                       (log.durable() ? " (an id from another adapter's log?)"
                                      : " (the log is in memory and began again when the adapter restarted; "
                                        "set events.log to keep it)") +
                       ": reload the tasks (GET /v1/tasks) and follow without it"));
    return std::nullopt;
  }
  if (id < pruned) {
    replyJson(res, 410,
              fieldProblem(
                  field,
                  "the events after " + text + " up to " + std::to_string(pruned) +
                      " are no longer held (retention: " + retentionText(log.settings()) +
                      "); reload the tasks (GET /v1/tasks) and resume with since=" + std::to_string(pruned),
                  "expired"));
    return std::nullopt;
  }
  return id;
}

void addStatusRoutes(HttpServer& server, EventLog& log, Webhooks& webhooks,
                     std::function<std::int64_t()> nowNs) {
  using Run = HttpServer::Run;
  // Server-sent events: every logged task transition as `id: N` and `event: task`. The stream holds
  // no worker: the server polls it (never blocking) from its I/O thread. A client that falls
  // behind the log's retention while connected gets `event: gap` naming what it missed.
  server.route(
      "GET", "/v1/events", Scope::Read,
      [&log](const Request& req, Response& res) {
        const auto start = resumePoint(req, log, res);
        if (!start) {
          return;
        }
        auto cursor = std::make_shared<std::int64_t>(*start);
        res.set_header("Cache-Control", "no-cache");
        res.set_header("X-Accel-Buffering", "no");
        res.setEventStream("text/event-stream", [&log, cursor]() -> std::optional<std::string> {
          std::string chunk;
          if (const auto pruned = log.prunedThrough(); *cursor < pruned) {
            chunk += "id: " + std::to_string(pruned) + "\nevent: gap\ndata: " +
                     json{{"missed_after", *cursor}, {"missed_through", pruned}}.dump() + "\n\n";
            *cursor = pruned;
          }
          std::vector<LoggedEvent> events;
          try {
            events = log.after(*cursor, kEventsPerPoll);
          } catch (const std::exception&) {
            return std::nullopt;  // the log's file cannot be read: end the stream, the client resumes
          }
          for (const auto& e : events) {
            chunk += "id: " + std::to_string(e.id) + "\nevent: task\ndata: " +
                     loggedEventJson(e).dump(-1, ' ', false, json::error_handler_t::replace) + "\n\n";
            *cursor = e.id;
          }
          return chunk;
        });
      },
      Run::Inline);

  server.route("GET", "/v1/webhooks", Scope::Read, [&log, &webhooks](const Request&, Response& res) {
    json items = json::array();
    const auto last = log.lastId();
    for (const auto& w : webhooks.list()) {
      items.push_back(webhookJson(w, last));
    }
    replyJson(res, 200, {{"webhooks", items}, {"count", items.size()}, {"last_event_id", last}});
  });
  server.route(
      "GET", R"(/v1/webhooks/([^/]+))", Scope::Read, [&log, &webhooks](const Request& req, Response& res) {
        const std::string id = req.matches[1];
        const auto w = webhooks.find(id);
        if (!w) {
          replyJson(res, 404,
                    {{"error", "not_found"}, {"message", "no webhook with id \"" + id.substr(0, 80) + "\""}});
          return;
        }
        replyJson(res, 200, webhookJson(*w, log.lastId()));
      });
  server.limitBody("POST", "/v1/webhooks", 16 * 1024, "the webhook route's fixed limit");
  server.route(
      "POST", "/v1/webhooks", Scope::Submit, [&log, &webhooks, nowNs](const Request& req, Response& res) {
        const auto parsed =
            parseBoundedJson(req.body, {.maxBytes = 16 * 1024, .maxDepth = 4, .maxElements = 64});
        if (!parsed || !parsed->is_object()) {
          replyJson(res, 400, fieldProblem("body", "expected a JSON object {\"url\": ..., \"secret\": ...}"));
          return;
        }
        const json& b = *parsed;
        for (const auto& [key, v] : b.items()) {
          if (key != "url" && key != "secret") {
            replyJson(res, 400, fieldProblem(key, "unknown field (expected url and an optional secret)"));
            return;
          }
        }
        if (!b.contains("url") || !b["url"].is_string()) {
          replyJson(res, 400, fieldProblem("url", "required: the http(s) URL to deliver to"));
          return;
        }
        const std::string url = b["url"];
        res.audit = json{{"webhook", "create"}, {"url", url.substr(0, 200)}}.dump(
            -1, ' ', false, json::error_handler_t::replace);
        if (const auto why = refuseWebhookUrl(url, webhooks.settings().allow)) {
          replyJson(res, 400, fieldProblem("url", *why));
          return;
        }
        std::string secret;
        if (b.contains("secret")) {
          if (!b["secret"].is_string() || b["secret"].get<std::string>().size() < 16 ||
              b["secret"].get<std::string>().size() > 256) {
            replyJson(
                res, 400,
                fieldProblem("secret", "expected a string of 16 to 256 characters (or none: one is made)"));
            return;
          }
          secret = b["secret"];
        }
        const auto made = webhooks.create(url, secret, nowNs());
        if (!made) {
          replyJson(res, 409,
                    {{"error", "conflict"},
                     {"message", "already " + std::to_string(webhooks.settings().maxSubscriptions) +
                                     " webhooks (webhooks.max_subscriptions): delete one first"}});
          return;
        }
        json body = webhookJson(made->status, log.lastId());
        body["secret"] = made->secret;
        res.set_header("Location", "/v1/webhooks/" + made->status.id);
        replyJson(res, 201, body);
      });
  server.route(
      "DELETE", R"(/v1/webhooks/([^/]+))", Scope::Submit, [&webhooks](const Request& req, Response& res) {
        const std::string id = req.matches[1];
        res.audit = json{{"webhook", "delete"}, {"id", id.substr(0, 80)}}.dump(
            -1, ' ', false, json::error_handler_t::replace);
        if (!webhooks.remove(id)) {
          replyJson(res, 404,
                    {{"error", "not_found"}, {"message", "no webhook with id \"" + id.substr(0, 80) + "\""}});
          return;
        }
        replyJson(res, 200, {{"id", id}, {"deleted", true}});
      });
}

}  // namespace fleet::wms
