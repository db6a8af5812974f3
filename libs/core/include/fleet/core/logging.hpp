#pragma once

#include <string>

// Services only: libraries never log (they return values and typed errors).
namespace fleet::logging {

/// Sets the default spdlog logger for a service: stderr, one line per message.
/// `level` is one of trace, debug, info, warn, error, critical, off; `format` is "text" (time,
/// service, level, message) or "json" (one object per line: time, level, service, msg, and the
/// fields set with setField). Anything else throws std::invalid_argument naming the accepted values.
void setup(const std::string& service, const std::string& level = "info", const std::string& format = "text");

/// A field every later JSON line carries (e.g. "robot" for an agent process driving one robot).
/// Call before logging starts on other threads. Ignored by the text format.
void setField(const std::string& key, const std::string& value);

/// A field (e.g. "task", "robot") on the JSON lines this thread logs while the object lives, for a
/// message about one task or robot. Nests; the innermost value of a key wins.
class ScopedField {
 public:
  ScopedField(std::string key, std::string value);
  ~ScopedField();
  ScopedField(const ScopedField&) = delete;
  ScopedField& operator=(const ScopedField&) = delete;
};

/// `s` as a JSON string literal (quotes included); newlines and control characters escaped, so a
/// multi-line message stays one line.
std::string jsonString(const std::string& s);

}  // namespace fleet::logging
