#pragma once

#include <string>

// Services only: libraries never log (they return values and typed errors).
namespace fleet::logging {

/// Sets the default spdlog logger for a service: stderr, pattern with time, service name and level.
/// `level` is one of trace, debug, info, warn, error, critical, off; anything else throws
/// std::invalid_argument naming the accepted values.
void setup(const std::string& service, const std::string& level = "info");

}  // namespace fleet::logging
