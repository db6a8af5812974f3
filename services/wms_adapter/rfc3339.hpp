#pragma once

// RFC 3339 times for the API's task fields (docs/openapi.yaml): every `*_ns` time of a task is also
// accepted and returned as text, "2026-12-02T14:05:00Z", "2026-12-02T15:05:00.250+01:00". The ns
// are of the fleet clock, which in a deployment is the wall clock (Unix epoch, UTC); under the
// simulator's clock the text is that clock read as if it were one.

#include <cstdint>
#include <optional>
#include <string>

namespace fleet::wms {

/// "YYYY-MM-DDTHH:MM:SS[.fraction]Z", the fraction as long as needed (none, 3, 6 or 9 digits).
std::string toRfc3339(std::int64_t unixNs);

/// ns since the Unix epoch of `text` (date, 'T' / 't' / ' ', time, optional fraction of up to 9
/// digits, 'Z' / 'z' or ±HH:MM), or nothing with why in `why`: malformed, a field out of range (month
/// 13, 24:00, Feb 30), or before 1970 / after 2262 (beyond int64 ns).
std::optional<std::int64_t> parseRfc3339(const std::string& text, std::string* why);

}  // namespace fleet::wms
