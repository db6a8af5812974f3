#pragma once

// What every binary's command line shares: --version, the exit codes (0 done, 1 failed at run time,
// 2 bad usage or configuration), --log-level/--log-format, and the ops port options.

#include <CLI/CLI.hpp>
#include <optional>
#include <string>

#include "fleet/service/ops_server.hpp"

namespace fleet::service {

inline constexpr int kExitOk = 0;
inline constexpr int kExitFailed = 1;
inline constexpr int kExitUsage = 2;

/// The project version from CMake.
[[nodiscard]] const char* version();

/// Adds --version to `app`.
void addVersion(CLI::App& app);
/// Adds --metrics-port and --metrics-host.
void addOpsOptions(CLI::App& app, OpsSettings& ops);

/// Parses; nullopt to go on, else the exit code: 0 after --help/--version, 2 on a usage error
/// (CLI11's own message printed; CLI11's codes 106, 109, ... are not passed on).
[[nodiscard]] std::optional<int> parse(CLI::App& app, int argc, char** argv);

}  // namespace fleet::service
