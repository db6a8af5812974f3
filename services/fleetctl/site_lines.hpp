#pragma once

// `fleetctl site lines`: a site file with each station's line spelled out as the roadmap builds it,
// so the site says where robots enter, wait and leave (docs/algorithms.md, "Traffic: stations as
// servers") and an integrator can read and move them.

#include <nlohmann/json.hpp>
#include <string>

#include "fleet/core/expected.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::ctl {

/// `site` (a site.json document) with, for every pickup, drop-off and charger the roadmap placed:
/// "approach" (the start of its straight last leg; left out when it is entered along its row),
/// "queue" (its waiting points, nearest first) and "exit" (its way out, or "entry" when it is left
/// by its way in), in m, exactly as placed. Other keys and their order are kept. A site built again
/// from the result gives the same roadmap (tests/unit/fleetctl/site_lines_test.cpp).
nlohmann::ordered_json spellOutLines(nlohmann::ordered_json site, const traffic::Roadmap& roadmap);

/// The command: reads `file` (a site.json), builds its roadmap with the default options and the
/// site's robot, and writes the spelled-out site to `out` ("-": stdout). Exit code 0; 2 when the
/// site or its roadmap has a problem (each printed, nothing written).
int siteLines(const std::string& file, const std::string& out);

/// Spells out the lines of the site file `file` in place (generated sites: `fleetctl loadtest
/// --site-for`). Fails naming the site's or its roadmap's problems; the file is left as it was.
Expected<void> spellOutLinesInPlace(const std::string& file);

}  // namespace fleet::ctl
