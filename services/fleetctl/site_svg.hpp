#pragma once

#include <string>

#include "fleet/site/site.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::ctl {

/// Map metres to the page's pixels: y flipped, a margin around, a legend band on top.
struct SvgFrame {
  Vec2 origin;
  double height = 0.0;  ///< m
  double scale = 1.0;   ///< px per m
  double pad = 90.0;    ///< room for station names beside docks at the map's edge
  double top = 110.0;   ///< legend band
  double pageW = 0.0;   ///< px
  double pageH = 0.0;
  [[nodiscard]] double x(double mx) const { return pad + (mx - origin.x) * scale; }
  [[nodiscard]] double y(double my) const { return top + (height - (my - origin.y)) * scale; }
  [[nodiscard]] double len(double m) const { return m * scale; }
};

/// The frame siteSvg() draws `site` in (so other layers can be laid over it).
SvgFrame siteSvgFrame(const site::Site& site);

/// `fleetctl site check --svg FILE`: the site's map (obstacles, no-go, speed-limit and one-way
/// cells), its roadmap (edges, one-way ones with arrows, nodes coloured by kind, queue lines) and
/// the stations with their names, as one SVG page in the map's frame (x right, y up), with a legend.
std::string siteSvg(const site::Site& site, const traffic::Roadmap& roadmap);

}  // namespace fleet::ctl
