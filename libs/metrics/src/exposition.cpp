#include "fleet/metrics/exposition.hpp"

#include <charconv>
#include <cmath>

namespace fleet::metrics {
namespace {
bool isAlpha(char c) {
  return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || c == '_';
}
bool isDigit(char c) {
  return c >= '0' && c <= '9';
}
}  // namespace

bool validMetricName(std::string_view name) {
  if (name.empty() || !(isAlpha(name[0]) || name[0] == ':')) {
    return false;
  }
  for (char c : name) {
    if (!isAlpha(c) && !isDigit(c) && c != ':') {
      return false;
    }
  }
  return true;
}

bool validLabelName(std::string_view name) {
  if (name.empty() || !isAlpha(name[0]) || name.starts_with("__")) {
    return false;
  }
  for (char c : name) {
    if (!isAlpha(c) && !isDigit(c)) {
      return false;
    }
  }
  return true;
}

std::string formatValue(double v) {
  if (std::isnan(v)) {
    return "NaN";
  }
  if (std::isinf(v)) {
    return v > 0 ? "+Inf" : "-Inf";
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof(buf), v);
  return {buf, r.ptr};
}

namespace {
std::string escape(std::string_view v, bool quote) {
  std::string out;
  out.reserve(v.size());
  for (char c : v) {
    if (c == '\\') {
      out += "\\\\";
    } else if (c == '\n') {
      out += "\\n";
    } else if (quote && c == '"') {
      out += "\\\"";
    } else {
      out += c;
    }
  }
  return out;
}
}  // namespace

std::string escapeLabelValue(std::string_view v) {
  return escape(v, true);
}
std::string escapeHelp(std::string_view v) {
  return escape(v, false);
}

}  // namespace fleet::metrics
