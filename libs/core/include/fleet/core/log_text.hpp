#pragma once

// Text from outside (a request path, a name a client chose) made safe for a log line: control
// characters (CR and LF above all: a forged line), quotes and backslashes are escaped as in a JSON
// string, and invalid UTF-8 is replaced by U+FFFD. The audit log's JSON lines escape the same way.

#include <string>
#include <string_view>

namespace fleet {

/// `text` as the inside of a JSON string: one line, nothing a reader takes for a new entry.
std::string escapeForLog(std::string_view text);

}  // namespace fleet
