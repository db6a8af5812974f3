// fleet-probe: asks a service's ops port for /livez or /readyz; exit 0 when it answers 200, 1 when
// it answers otherwise or not at all (within 2 s), 2 on bad usage. For container health checks,
// where no curl is installed.
//   fleet-probe /livez            the port from FLEET_METRICS_PORT (as the service reads it)
//   fleet-probe 9101 /readyz

#include <httplib.h>

#include <charconv>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

#include "fleet/service/command_line.hpp"

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--version") == 0) {
    std::printf("fleet-probe %s\n", fleet::service::version());
    return 0;
  }
  if (argc != 2 && argc != 3) {
    std::fprintf(stderr,
                 "usage: fleet-probe [PORT] /livez|/readyz|/metrics (PORT default: $FLEET_METRICS_PORT)\n");
    return 2;
  }
  const char* portText = argc == 3 ? argv[1] : std::getenv("FLEET_METRICS_PORT");
  const std::string path = argv[argc - 1];
  int port = 0;
  if (portText == nullptr ||
      std::from_chars(portText, portText + std::strlen(portText), port).ptr !=
          portText + std::strlen(portText) ||
      port < 1 || port > 65535 || path.empty() || path[0] != '/') {
    std::fprintf(stderr, "fleet-probe: need a port 1-65535 (argument or FLEET_METRICS_PORT) and a path\n");
    return 2;
  }
  httplib::Client c("127.0.0.1", port);
  c.set_connection_timeout(2, 0);
  c.set_read_timeout(2, 0);
  auto r = c.Get(path);
  if (!r) {
    std::fprintf(stderr, "fleet-probe: no answer on 127.0.0.1:%d%s (%s)\n", port, path.c_str(),
                 httplib::to_string(r.error()).c_str());
    return 1;
  }
  std::fputs(r->body.c_str(), r->status == 200 ? stdout : stderr);
  return r->status == 200 ? 0 : 1;
}
