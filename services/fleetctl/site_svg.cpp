#include "site_svg.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <iomanip>
#include <sstream>

namespace fleet::ctl {

namespace {

using traffic::NodeId;
using traffic::NodeKind;

constexpr std::array<const char*, 7> kKindColour{"#8fa3b8", "#d62728", "#ff8c00", "#9b30d0",
                                                 "#1f5fd6", "#1a9e3a", "#00a6a6"};

const char* colour(NodeKind k) {
  return kKindColour[static_cast<std::size_t>(k)];
}

std::string escape(const std::string& s) {
  std::string out;
  for (const char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

}  // namespace

SvgFrame siteSvgFrame(const site::Site& site) {
  const auto& map = site.map;
  const double res = map.resolution();
  const double w = map.width() * res;
  const double h = map.height() * res;
  SvgFrame f;
  f.origin = map.origin();
  f.height = h;
  // Fit a 1,400 × 1,000 px window (at least 4 px per metre: a large site makes a larger page).
  f.scale = std::clamp(std::min((1400.0 - 2.0 * f.pad) / std::max(w, 1e-3),
                                (1000.0 - f.top - 2.0 * f.pad) / std::max(h, 1e-3)),
                       4.0, 150.0);
  f.pageW = std::max(2.0 * f.pad + f.len(w), 1100.0);
  f.pageH = f.top + 2.0 * f.pad + f.len(h);
  return f;
}

std::string siteSvg(const site::Site& site, const traffic::Roadmap& roadmap) {
  const auto& map = site.map;
  const SvgFrame f = siteSvgFrame(site);
  const double res = map.resolution();
  const double w = map.width() * res;
  const double h = map.height() * res;
  const double pageW = f.pageW;
  const double pageH = f.pageH;
  std::ostringstream os;
  os << std::fixed << std::setprecision(1);
  os << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << pageW << "\" height=\"" << pageH
     << "\" viewBox=\"0 0 " << pageW << " " << pageH
     << "\" font-family=\"DejaVu Sans, Arial, sans-serif\">\n";
  os << "<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"9\" refY=\"5\" markerWidth=\"5\" "
        "markerHeight=\"5\" "
        "orient=\"auto\"><path d=\"M0,0 L10,5 L0,10 z\" fill=\"#1f5fd6\"/></marker></defs>\n";
  os << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n";

  // Cells: obstacles, then the zones' layers, as runs along each row.
  auto runs = [&](const char* fill, const char* opacity, auto&& in) {
    os << "<g fill=\"" << fill << "\" fill-opacity=\"" << opacity << "\">";
    for (int y = 0; y < map.height(); ++y) {
      int x = 0;
      while (x < map.width()) {
        if (!in(planning::Cell{x, y})) {
          ++x;
          continue;
        }
        const int x0 = x;
        while (x < map.width() && in(planning::Cell{x, y})) {
          ++x;
        }
        const double mx = map.origin().x + x0 * res;
        const double my = map.origin().y + (y + 1) * res;
        os << "<rect x=\"" << f.x(mx) << "\" y=\"" << f.y(my) << "\" width=\"" << f.len((x - x0) * res) + 0.3
           << "\" height=\"" << f.len(res) + 0.3 << "\"/>";
      }
    }
    os << "</g>\n";
  };
  auto layer = [&](const auto& v, planning::Cell c, auto&& test) {
    return v.size() == map.size() && test(v[map.index(c)]);
  };
  runs("#3c3c3c", "1", [&](planning::Cell c) { return map.blocked(c); });
  runs("#e53935", "0.35",
       [&](planning::Cell c) { return layer(site.layers.noGo, c, [](auto v) { return v != 0; }); });
  runs("#fbc02d", "0.35", [&](planning::Cell c) {
    return layer(site.layers.speedLimit, c, [](float v) { return std::isfinite(v); });
  });
  runs("#42a5f5", "0.2", [&](planning::Cell c) {
    return layer(site.layers.oneWay, c, [](float v) { return std::isfinite(v); });
  });

  // Edges: two-way lanes grey, one-way lanes blue with an arrow, queue lines purple.
  const auto& g = roadmap.graph;
  const double lane = std::max(0.6, f.len(0.035));
  std::ostringstream twoWay;
  std::ostringstream oneWay;
  std::ostringstream queue;
  twoWay << std::fixed << std::setprecision(1);
  oneWay << std::fixed << std::setprecision(1);
  queue << std::fixed << std::setprecision(1);
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    for (const auto& e : g.edges(v)) {
      const bool back = g.edge(e.to, v) != nullptr;
      if (back && e.to < v) {
        continue;  // drawn once
      }
      const Vec2 a = g.position(v);
      const Vec2 b = g.position(e.to);
      // The line of a queue purple; the ways into and out of it like any lane.
      const bool queueNode = roadmap.kind(v) == NodeKind::Queue || roadmap.kind(e.to) == NodeKind::Queue;
      const bool toLane = roadmap.kind(v) == NodeKind::Lane || roadmap.kind(e.to) == NodeKind::Lane;
      auto& out = queueNode && !toLane ? queue : back || queueNode ? twoWay : oneWay;
      out << "<line x1=\"" << f.x(a.x) << "\" y1=\"" << f.y(a.y) << "\" x2=\"" << f.x(b.x) << "\" y2=\""
          << f.y(b.y) << "\"/>";
    }
  }
  os << "<g stroke=\"#b0bec5\" stroke-width=\"" << lane << "\">" << twoWay.str() << "</g>\n";
  os << "<g stroke=\"#1f5fd6\" stroke-width=\"" << lane * 1.5 << "\" marker-end=\"url(#arrow)\">"
     << oneWay.str() << "</g>\n";
  os << "<g stroke=\"#9b30d0\" stroke-width=\"" << lane * 2.5 << "\">" << queue.str() << "</g>\n";

  // Stations: the robot's disc at the dock, the last leg.
  const double r = roadmap.options.radius;
  for (const auto& s : roadmap.stations) {
    if (s.dock == traffic::kNoNode) {
      continue;
    }
    const Vec2 d = g.position(s.dock);
    os << "<circle cx=\"" << f.x(d.x) << "\" cy=\"" << f.y(d.y) << "\" r=\"" << f.len(r) << "\" fill=\""
       << colour(roadmap.kind(s.dock)) << "\" fill-opacity=\"0.15\" stroke=\"" << colour(roadmap.kind(s.dock))
       << "\" stroke-width=\"1\" stroke-dasharray=\"3 2\"/>\n";
    if (s.approach != traffic::kNoNode) {
      const Vec2 a = g.position(s.approach);
      os << "<line x1=\"" << f.x(a.x) << "\" y1=\"" << f.y(a.y) << "\" x2=\"" << f.x(d.x) << "\" y2=\""
         << f.y(d.y) << "\" stroke=\"#ff8c00\" stroke-width=\"" << lane * 2.5 << "\"/>\n";
    }
  }

  // Nodes by kind; lane nodes small.
  os << "<g>";
  for (NodeId v = 0; v < static_cast<NodeId>(g.size()); ++v) {
    const NodeKind k = roadmap.kind(v);
    const Vec2 p = g.position(v);
    const double rad = k == NodeKind::Lane ? std::max(0.8, f.len(0.05)) : std::max(2.0, f.len(0.11));
    os << "<circle cx=\"" << f.x(p.x) << "\" cy=\"" << f.y(p.y) << "\" r=\"" << rad << "\" fill=\""
       << colour(k) << "\"/>";
  }
  os << "</g>\n";

  // Queue positions numbered from the station, station names beside their docks.
  const double font = std::clamp(f.len(0.32), 8.0, 16.0);
  os << "<g font-size=\"" << font * 0.8
     << "\" fill=\"#5a1a7a\" stroke=\"white\" stroke-width=\"2.5\" "
        "paint-order=\"stroke\" text-anchor=\"middle\">";
  for (const auto& s : roadmap.stations) {
    for (std::size_t q = 0; q < s.queue.size(); ++q) {
      const Vec2 p = g.position(s.queue[q]);
      os << "<text x=\"" << f.x(p.x) << "\" y=\"" << f.y(p.y) - font * 0.45 << "\">" << q + 1 << "</text>";
    }
  }
  os << "</g>\n";
  os << "<g font-size=\"" << font
     << "\" font-weight=\"bold\" fill=\"#222\" stroke=\"white\" stroke-width=\"3\" "
        "paint-order=\"stroke\" dominant-baseline=\"middle\">";
  for (std::size_t i = 0; i < roadmap.stations.size() && i < site.stations.size(); ++i) {
    const auto& s = roadmap.stations[i];
    const auto& st = site.stations[i];
    // The name runs from the dock away from the station's way in (over the shelf or wall behind
    // it, or the page's margin), so it covers neither the last leg nor the queue; never upside down.
    const Vec2 back = -st.pose.heading();
    const Vec2 p = st.pose.position() + back * (r + 0.08);
    double deg = std::atan2(-back.y, back.x) * 180.0 / 3.14159265358979323846;
    const bool flip = deg > 90.0 + 1e-6 || deg < -90.0 - 1e-6;
    deg += flip ? 180.0 : 0.0;
    os << "<text x=\"" << f.x(p.x) << "\" y=\"" << f.y(p.y) << "\" text-anchor=\"" << (flip ? "end" : "start")
       << "\" transform=\"rotate(" << deg << " " << f.x(p.x) << " " << f.y(p.y) << ")\""
       << (s.dock == traffic::kNoNode ? " fill=\"#d00\"" : "") << ">" << escape(s.name) << "</text>";
  }
  os << "</g>\n";

  // Problems: a red ring where each one is.
  for (const auto& p : roadmap.problems) {
    os << "<circle cx=\"" << f.x(p.at.x) << "\" cy=\"" << f.y(p.at.y) << "\" r=\""
       << std::max(8.0, f.len(0.6)) << "\" fill=\"none\" stroke=\""
       << (p.severity == traffic::RoadmapProblem::Severity::Error ? "#d00" : "#e69500")
       << "\" stroke-width=\"3\"><title>" << escape(p.what) << "</title></circle>\n";
  }

  // Legend band.
  std::array<std::size_t, kKindColour.size()> count{};
  for (const auto k : roadmap.kinds) {
    ++count[static_cast<std::size_t>(k)];
  }
  os << "<g font-size=\"15\" fill=\"#222\">";
  os << "<text x=\"20\" y=\"24\" font-weight=\"bold\" font-size=\"18\">" << escape(site.name) << "</text>";
  os << "<text x=\"20\" y=\"46\">" << std::setprecision(0) << w << " × " << h << " m, roadmap: " << g.size()
     << " nodes, " << roadmap.edgeCount() << " edges, " << traffic::conflictPairs(g)
     << " conflicting pairs; lattice " << std::setprecision(2) << roadmap.options.spacing
     << " m; robot radius " << r << " m</text>";
  double x = 20.0;
  for (std::size_t k = 0; k < count.size(); ++k) {
    const auto kind = static_cast<NodeKind>(k);
    os << std::setprecision(1) << "<circle cx=\"" << x + 7 << "\" cy=\"70\" r=\"6\" fill=\"" << colour(kind)
       << "\"/><text x=\"" << x + 18 << "\" y=\"75\">" << traffic::toString(kind) << " " << count[k]
       << "</text>";
    x += 150;
  }
  os << "<line x1=\"" << x << "\" y1=\"70\" x2=\"" << x + 30
     << "\" y2=\"70\" stroke=\"#1f5fd6\" stroke-width=\"2\" "
     << "marker-end=\"url(#arrow)\"/><text x=\"" << x + 38 << "\" y=\"75\">one way</text>";
  os << "</g>\n</svg>\n";
  return os.str();
}

}  // namespace fleet::ctl
