#pragma once

// A JSON answer, as every route of the adapter sends one.

#include <nlohmann/json.hpp>

#include "http_names.hpp"

namespace fleet::wms {

/// Sets `status` and `body` as application/json. A string that is not UTF-8 (which the edge repairs,
/// so none should arrive) is written with U+FFFD instead of making dump() throw.
inline void replyJson(Response& res, int status, const nlohmann::json& body) {
  res.status = status;
  res.set_content(body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace), "application/json");
}

}  // namespace fleet::wms
