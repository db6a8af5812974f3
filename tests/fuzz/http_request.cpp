// The HTTP server (libs/http, the WMS adapter's API) as a client meets it: the bytes of a request through the
// same Beast parser and limits the server runs (request line, headers, Content-Length or chunked body) and
// its target decoding (path, query parameters). Properties besides "no crash":
//  - a complete request's body is within the body limit, its head within the head limit;
//  - the decoded path and method, escaped for the access log, never hold a line break.

#include <cstddef>
#include <cstdint>
#include <string_view>

#include "fleet/core/log_text.hpp"
#include "fleet/http/request_parse.hpp"
#include "fuzz_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fleet::http::ServerLimits limits;
  limits.maxBodyBytes = 4096;  // small, so that the fuzzer reaches the limit
  limits.maxHeaderBytes = 2048;
  const std::string_view bytes(reinterpret_cast<const char*>(data), size);
  const auto parsed = fleet::http::parseRequestBytes(bytes, limits);
  using Outcome = fleet::http::ParsedRequest::Outcome;
  if (parsed.outcome == Outcome::Complete) {
    fleet::fuzz::require(parsed.request.body.size() <= limits.maxBodyBytes, "a body past the limit was read");
  }
  if (parsed.outcome == Outcome::TooLarge || parsed.outcome == Outcome::Malformed) {
    fleet::fuzz::require(!parsed.error.empty(), "a refusal says why");
  }
  for (const auto& text : {parsed.request.path, parsed.request.method}) {
    const auto logged = fleet::escapeForLog(text);
    fleet::fuzz::require(logged.find('\n') == std::string::npos && logged.find('\r') == std::string::npos,
                         "an access-log field holds a line break");
  }
  return 0;
}
