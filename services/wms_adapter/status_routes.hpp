#pragma once

// The API's status push (docs/operator-guide.md#status-push): GET /v1/events, the event stream that
// resumes after an event id, and the webhook subscriptions (/v1/webhooks).

#include <cstdint>
#include <functional>

#include "event_log.hpp"
#include "fleet/core/config.hpp"
#include "http_names.hpp"
#include "webhooks.hpp"

namespace fleet::wms {

/// Reads `events.*` and `webhooks.*` (docs/operator-guide.md#wms_adapter-configuration).
void readStatusSettings(Config& cfg, EventLogSettings& events, WebhookSettings& webhooks);

/// Registers GET /v1/events and the /v1/webhooks routes on `server`. `nowNs` is the wall clock.
void addStatusRoutes(HttpServer& server, EventLog& log, Webhooks& webhooks,
                     std::function<std::int64_t()> nowNs);

/// Where a stream resumes: after the Last-Event-ID header's id, else after ?since=, else after the
/// newest event (only new ones). On a bad or expired id the reply is written and nothing returned.
std::optional<std::int64_t> resumePoint(const Request& req, EventLog& log, Response& res);

}  // namespace fleet::wms
