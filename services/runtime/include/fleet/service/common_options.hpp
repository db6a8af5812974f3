#pragma once

// The options every service has: --version, --log-level, --log-format, --metrics-port/--metrics-host.

#include <CLI/CLI.hpp>
#include <string>

#include "fleet/service/ops_server.hpp"

namespace fleet::service {

struct CommonOptions {
  std::string logLevel = "info";
  std::string logFormat = "text";
  OpsSettings ops;
};

void addCommonOptions(CLI::App& app, CommonOptions& o);
/// Sets up logging; a bad level or format throws ConfigError (exit 2).
void setupLogging(const std::string& service, const CommonOptions& o);

}  // namespace fleet::service
