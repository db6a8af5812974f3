#pragma once

// Free text on the wire (a robot's error, a task event's reason) ends up in JSON, logs and SQLite,
// all of which need UTF-8: one byte that is not makes nlohmann::json throw on dump.

#include <string>
#include <string_view>

namespace fleet::validation {

/// Well-formed UTF-8 (no overlong forms, no surrogates, at most U+10FFFF).
bool isValidUtf8(std::string_view s);

/// `s` with every byte that does not start a well-formed sequence replaced by U+FFFD; `s` itself when
/// it is valid already.
std::string repairUtf8(std::string_view s);

}  // namespace fleet::validation
