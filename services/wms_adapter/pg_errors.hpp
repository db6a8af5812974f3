#pragma once

// A PostgreSQL call's error as the exception the adapter's stores throw: the URL (password
// redacted) and what the server or libpq said. Shared by the event log and the webhook store.

#include <stdexcept>
#include <string>
#include <utility>

#include "fleet/core/expected.hpp"
#include "fleet/fleet/pg_connection.hpp"

namespace fleet::wms::pg_errors {

inline std::runtime_error failed(const std::string& url, const Error& e) {
  return std::runtime_error(pg::redacted(url) + ": " + e.message);
}

template <class T>
T orThrow(const std::string& url, Expected<T> r) {
  if (!r) {
    throw failed(url, r.error());
  }
  return std::move(*r);
}

inline void orThrow(const std::string& url, Expected<void> r) {
  if (!r) {
    throw failed(url, r.error());
  }
}

}  // namespace fleet::wms::pg_errors
