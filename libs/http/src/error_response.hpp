#pragma once

// The answer the server makes itself (413, 429, 503, ...): the API's error body
// {"error": code, "message": text}.

#include <string>

#include "fleet/http/message.hpp"

namespace fleet::http::detail {

Response errorResponse(int status, const std::string& code, const std::string& message);

}  // namespace fleet::http::detail
