// fleetctl site check: validate a site or map file and print what it holds; fleetctl site lines:
// spell out each station's line (approach, queue, exit) as the roadmap builds it.

#include <memory>
#include <string>

#include "commands.hpp"
#include "site_check.hpp"
#include "site_lines.hpp"

namespace fleet::ctl {

namespace {

struct SiteCheckOptions {
  std::string file;
  double radius = 0.0;
  double resolution = 1.0;
  bool json = false;
  std::string svg;
};

}  // namespace

void addSiteCommand(CLI::App& app, Commands& commands) {
  auto* site = app.add_subcommand("site", "site files");
  auto* siteCheck = site->add_subcommand("check", "validate a site or map file and print what it holds");
  auto o = std::make_shared<SiteCheckOptions>();
  siteCheck
      ->add_option("file", o->file, "site.json, a scenario naming a site, MovingAI .map or ROS map .yaml")
      ->required();
  siteCheck->add_option("--radius", o->radius, "robot radius in m (default: the site's robot)")
      ->check(CLI::Range(0.0, 10.0));
  siteCheck->add_option("--resolution", o->resolution, "m per cell of a MovingAI .map")
      ->check(CLI::Range(1e-3, 100.0))
      ->capture_default_str();
  siteCheck->add_flag("--json", o->json, "print the report as JSON");
  siteCheck->add_option("--svg", o->svg, "draw the map, the roadmap and the stations into this SVG file");
  auto* siteLines = site->add_subcommand(
      "lines",
      "write the site with each station's approach, queue and exit spelled out as the roadmap builds them");
  auto lines = std::make_shared<std::pair<std::string, std::string>>("", "-");
  siteLines->add_option("file", lines->first, "site.json")->required();
  siteLines->add_option("--out", lines->second, "where to write the site (-: stdout; may be the file itself)")
      ->capture_default_str();
  site->require_subcommand(1);
  commands.push_back(
      {siteCheck, [o] { return fleet::ctl::siteCheck(o->file, o->radius, o->resolution, o->json, o->svg); }});
  commands.push_back({siteLines, [lines] { return fleet::ctl::siteLines(lines->first, lines->second); }});
}

}  // namespace fleet::ctl
