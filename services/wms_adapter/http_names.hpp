#pragma once

// The HTTP server's types (libs/http) by the short names the adapter's code uses.

#include "fleet/http/server.hpp"

namespace fleet::wms {

using http::EventSource;
using http::HttpServer;
using http::parseScope;
using http::Request;
using http::Response;
using http::Scope;
using http::ServerLimits;
using http::ServerStats;
using http::TlsFiles;
using http::toString;

}  // namespace fleet::wms
