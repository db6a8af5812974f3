#pragma once

// What the HTTP server makes of the bytes a client sends: the request target split into a
// percent-decoded path and query parameters, and (for the fuzz target, tests/fuzz/http_request.cpp)
// a whole request read from bytes with the server's limits, through the same Beast parser the
// server runs.

#include <cstddef>
#include <string>
#include <string_view>

#include "fleet/http/server.hpp"

namespace fleet::http {

/// %XX decoded (a malformed escape stays as it is); in a query, '+' is a space.
std::string percentDecode(std::string_view s, bool plusIsSpace);
/// Sets req.path (decoded, without the query) and req.params from a request target.
void parseTarget(std::string_view target, Request& req);

struct ParsedRequest {
  enum class Outcome { Complete, Incomplete, TooLarge, Malformed };
  Outcome outcome = Outcome::Incomplete;
  Request request;    // as far as it was read
  std::string error;  // why, when TooLarge or Malformed
};

/// One request from `bytes` with the limits of `limits` (head, body).
ParsedRequest parseRequestBytes(std::string_view bytes, const ServerLimits& limits);

}  // namespace fleet::http
