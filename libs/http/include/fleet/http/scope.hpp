#pragma once

// What a request may do, as a route requires it and a token grants it (the WMS adapter's tokens:
// docs/operator-guide.md, "Security: HTTP API"). The server exempts Public routes from the rate
// limit and hands the route's scope to its gate.

#include <optional>
#include <string>
#include <string_view>

namespace fleet::http {

enum class Scope {
  Public,   // no token needed (the health probe)
  Read,     // GET: tasks, robots, events, metrics
  Submit,   // create and cancel tasks (what a WMS does)
  Operate,  // pause and resume tasks, command robots (what an operator does)
};

inline const char* toString(Scope s) {
  switch (s) {
    case Scope::Public:
      return "public";
    case Scope::Read:
      return "read";
    case Scope::Submit:
      return "submit";
    case Scope::Operate:
      return "operate";
  }
  return "?";
}

/// "read", "submit" or "operate" (a token never grants "public": every token has it).
inline std::optional<Scope> parseScope(std::string_view s) {
  if (s == "read") {
    return Scope::Read;
  }
  if (s == "submit") {
    return Scope::Submit;
  }
  if (s == "operate") {
    return Scope::Operate;
  }
  return std::nullopt;
}

}  // namespace fleet::http
