#include "fleet/service/common_options.hpp"

#include <stdexcept>

#include "fleet/core/config.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/service/command_line.hpp"

namespace fleet::service {

void addCommonOptions(CLI::App& app, CommonOptions& o) {
  addVersion(app);
  app.add_option("--log-level", o.logLevel, "trace, debug, info, warn, error, critical, off");
  app.add_option("--log-format", o.logFormat, "text (default) or json (one object per line)");
  addOpsOptions(app, o.ops);
}

void setupLogging(const std::string& service, const CommonOptions& o) {
  try {
    logging::setup(service, o.logLevel, o.logFormat);
  } catch (const std::invalid_argument& e) {
    throw ConfigError({e.what()});
  }
}

}  // namespace fleet::service
