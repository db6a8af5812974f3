#include "fleet/service/command_line.hpp"

namespace fleet::service {

const char* version() {
  return FLEET_VERSION;
}

void addVersion(CLI::App& app) {
  app.set_version_flag("--version",
                       std::string(app.get_name().empty() ? "" : app.get_name() + " ") + FLEET_VERSION,
                       "print the version and exit");
}

void addOpsOptions(CLI::App& app, OpsSettings& ops) {
  app.add_option("--metrics-port", ops.port,
                 "serve /metrics, /livez and /readyz on this port (0 = any free port; off by default)")
      ->envname("FLEET_METRICS_PORT");
  app.add_option("--metrics-host", ops.host, "address of the metrics port (default 127.0.0.1)")
      ->envname("FLEET_METRICS_HOST");
}

std::optional<int> parse(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    const int code = app.exit(e);
    return code == 0 ? kExitOk : kExitUsage;
  }
  return std::nullopt;
}

}  // namespace fleet::service
