#pragma once

// Who may use the WMS adapter's HTTP API: the one check every request passes before routing.

#include <httplib.h>

#include <cstdint>
#include <string>

#include "browser_session.hpp"

namespace fleet::wms {

/// True when the request may proceed. With a token configured: static files (paths outside /v1/)
/// and /v1/health need nothing; the rest needs `Authorization: Bearer <token>` or a valid session
/// cookie, and a request that changes something with the cookie also needs the session's CSRF
/// token in X-CSRF-Token. Otherwise the 401 (WWW-Authenticate: Bearer) or 403 reply is written.
bool admitRequest(const std::string& token, const BrowserSessions& sessions, const httplib::Request& req,
                  httplib::Response& res, std::int64_t nowS);

}  // namespace fleet::wms
