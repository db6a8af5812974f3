#include "site_check.hpp"

#include <iostream>

#include "fleet/service/site_stations.hpp"
#include "fleet/site/site_report.hpp"

namespace fleet::ctl {

int siteCheck(const std::string& file, double radius, double mapResolution, bool asJson) {
  // Geometry is left to the report, so a site with an unreachable station still shows the rest.
  auto site = service::loadSiteFile(file, false, mapResolution);
  if (!site) {
    std::cerr << site.error().message << "\n";
    return 2;
  }
  const auto report = site::analyseSite(*site, radius);
  if (asJson) {
    std::cout << site::reportJson(report).dump(1) << "\n";
  } else {
    std::cout << site::formatReport(report);
  }
  for (const auto& p : report.problems) {
    std::cerr << site->origin << ": " << p.key << ": " << p.what << "\n";
  }
  return report.problems.empty() ? 0 : 2;
}

}  // namespace fleet::ctl
