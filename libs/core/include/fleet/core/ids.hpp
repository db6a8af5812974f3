#pragma once

#include <cstddef>
#include <string_view>

namespace fleet {

/// Longest id on the wire (robot, task, source, station ids); the IDL bounds match it.
inline constexpr std::size_t kMaxIdLength = 63;

/// Ids are 1..63 characters from [A-Za-z0-9_.:-]: safe in URLs, file names, SQL and log lines.
constexpr bool isValidId(std::string_view id) {
  if (id.empty() || id.size() > kMaxIdLength) {
    return false;
  }
  for (char c : id) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' ||
                    c == '-' || c == '.' || c == ':';
    if (!ok) {
      return false;
    }
  }
  return true;
}

}  // namespace fleet
