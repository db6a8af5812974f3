#include "svg_writer.hpp"

#include <cstdio>
#include <fstream>

#include "colormap.hpp"

namespace fleet::risk_render {

bool writeRegionsSvg(const std::string& path, const fleet::risk::GridSpec& spec, int levels,
                     const std::vector<fleet::risk::Region>& regions) {
  std::ofstream f(path);
  const double w = spec.width * spec.resolution;
  const double h = spec.height * spec.resolution;
  const double scale = 600.0 / std::max(w, h);
  f << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << w * scale << "\" height=\"" << h * scale
    << "\">\n";
  f << "<rect width=\"100%\" height=\"100%\" fill=\"#ffffff\"/>\n";
  auto px = [&](fleet::Vec2 p) {
    char buf[64];
    std::snprintf(buf, sizeof buf, "%.2f,%.2f", (p.x - spec.originX) * scale,
                  (spec.originY + h - p.y) * scale);
    return std::string(buf);
  };
  for (const auto& r : regions) {
    const Rgb c = viridis(static_cast<double>(r.level) / levels);
    char fill[16];
    std::snprintf(fill, sizeof fill, "#%02x%02x%02x", c.r, c.g, c.b);
    f << "<path fill-rule=\"evenodd\" fill=\"" << fill << "\" stroke=\"#222\" stroke-width=\"0.5\" d=\"";
    auto ring = [&](const fleet::risk::Ring& ringPts) {
      for (std::size_t k = 0; k < ringPts.size(); ++k) {
        f << (k == 0 ? "M" : "L") << px(ringPts[k]) << ' ';
      }
      f << "Z ";
    };
    ring(r.outer);
    for (const auto& hole : r.holes) {
      ring(hole);
    }
    f << "\"><title>level " << r.level << ", " << r.cells << " cells</title></path>\n";
  }
  f << "</svg>\n";
  return static_cast<bool>(f);
}

}  // namespace fleet::risk_render
