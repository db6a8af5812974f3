#pragma once

// JSON from outside (an HTTP body, an MQTT message) parsed without letting its shape decide the
// memory it takes: a streaming (SAX) pass counts nesting depth and values and stops at the first
// limit crossed, before any document is built. A megabyte of '[' costs nothing but the pass; a
// document within the limits is built as nlohmann::json::parse would.

#include <cstddef>
#include <nlohmann/json.hpp>
#include <string_view>

#include "fleet/core/expected.hpp"

namespace fleet {

struct JsonLimits {
  std::size_t maxBytes = 1 << 20;     // the text's size
  std::size_t maxDepth = 32;          // arrays and objects inside each other
  std::size_t maxElements = 100'000;  // values of any kind (the document, members, items) in all
};

/// The document in `text`, or an Error whose code is "json.too_large", "json.too_deep",
/// "json.too_many_elements" (its message naming the limit and its value) or "json.invalid" (where
/// the syntax breaks). Never throws on any input.
Expected<nlohmann::json> parseBoundedJson(std::string_view text, const JsonLimits& limits);

}  // namespace fleet
