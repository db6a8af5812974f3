#include "risk_map_node.hpp"

#include <cmath>

#include "fleet/core/clock.hpp"
#include "fleet/risk/gaussian.hpp"
#include "fleet/risk/overlap_ratio.hpp"
#include "fleet/risk/regions.hpp"
#include "fleet/risk/rle.hpp"

namespace fleet::riskmap {

Settings readSettings(Config& cfg) {
  Settings s;
  cfg.rejectUnknownKeys({"grid", "levels", "dt", "steps", "rate_hz", "model", "gaussian_floor",
                         "gaussian_eval", "stale_after_s", "regions", "human_human", "clock", "lockstep",
                         "tile_size", "site"});
  s.site = cfg.string("site", "");
  auto g = cfg.child("grid");
  if (!s.site.empty()) {
    for (const char* k : {"origin_x", "origin_y", "width", "height"}) {
      if (g.has(k)) {
        g.problem(k, "comes from the site; remove it or the 'site' key");
      }
    }
  }
  g.rejectUnknownKeys({"origin_x", "origin_y", "resolution", "width", "height"});
  s.fusion.grid.originX = g.number("origin_x", 0.0, {-1e5, 1e5});
  s.fusion.grid.originY = g.number("origin_y", 0.0, {-1e5, 1e5});
  s.fusion.grid.resolution = g.number("resolution", 0.1, {0.01, 10.0});
  s.fusion.grid.width = static_cast<int>(g.integer("width", 1000, {1, 20000}));
  s.fusion.grid.height = static_cast<int>(g.integer("height", 500, {1, 20000}));
  s.fusion.levels = static_cast<int>(cfg.integer("levels", 10, {1, 255}));
  s.fusion.dt = cfg.number("dt", 0.1, {0.0, 10.0, true});
  s.fusion.steps = static_cast<int>(cfg.integer("steps", 30, {1, 200}));
  s.fusion.tileSize = static_cast<int>(cfg.integer("tile_size", 32, {4, 1024}));
  s.fusion.policy.humanHuman = cfg.boolean("human_human", false);
  s.model = cfg.string("model", "gaussian", {"gaussian", "overlap"});
  s.gaussianFloor = cfg.number("gaussian_floor", 1e-4, {0.0, 0.5, true});
  s.gaussianEval = cfg.string("gaussian_eval", "fast", {"fast", "exact"});
  s.rateHz = cfg.number("rate_hz", 10.0, {0.0, 1000.0, true});
  s.staleAfterS = cfg.number("stale_after_s", 1.0, {0.0, 3600.0, true});
  s.regions = cfg.boolean("regions", true);
  s.clock = cfg.string("clock", "wall", {"wall", "sim"});
  s.lockstep = cfg.boolean("lockstep", false);
  if (s.lockstep && s.clock != "sim") {
    cfg.problem("lockstep", "requires \"clock\": \"sim\"");
  }
  return s;
}

risk::GridSpec gridOverSite(Vec2 origin, double widthM, double heightM, double resolution) {
  risk::GridSpec g;
  g.originX = origin.x;
  g.originY = origin.y;
  g.resolution = resolution;
  // A hair below a whole cell count is that count (30 m / 0.1 m is 299.99999999999994).
  g.width = static_cast<int>(std::ceil(widthM / resolution - 1e-6));
  g.height = static_cast<int>(std::ceil(heightM / resolution - 1e-6));
  return g;
}

std::shared_ptr<const risk::RiskModel> makeModel(const Settings& s) {
  if (s.model == "overlap") {
    return std::make_shared<risk::OverlapRatio>();
  }
  return std::make_shared<risk::Gaussian>(s.gaussianFloor, s.gaussianEval == "exact"
                                                               ? risk::GaussianEvaluation::kExact
                                                               : risk::GaussianEvaluation::kFast);
}

risk::Source toSource(const msg::PredictedDiscs& m) {
  risk::Source s;
  s.id = m.source_id;
  s.kind = m.kind == msg::SourceKind::Human ? risk::SourceKind::kHuman : risk::SourceKind::kRobot;
  s.t0_ns = m.t0_ns;
  s.dt = static_cast<double>(m.dt);
  s.discs.reserve(m.discs.size());
  for (const auto& d : m.discs) {
    s.discs.push_back({static_cast<double>(d.x), static_cast<double>(d.y), static_cast<double>(d.r),
                       static_cast<double>(d.sigma),
                       risk::Cov2{static_cast<double>(d.cov_xx), static_cast<double>(d.cov_xy),
                                  static_cast<double>(d.cov_yy)}});
  }
  return s;
}

msg::RiskMap toMessage(const risk::FusionResult& r, std::int64_t stamp_ns, std::uint32_t sources,
                       bool regions) {
  msg::RiskMap m;
  const auto& spec = r.levels.spec;
  m.stamp_ns = stamp_ns;
  m.origin_x = spec.originX;
  m.origin_y = spec.originY;
  m.resolution = spec.resolution;
  m.width = static_cast<std::uint32_t>(spec.width);
  m.height = static_cast<std::uint32_t>(spec.height);
  m.levels = static_cast<std::uint8_t>(r.levels.levels);
  m.horizon_s = static_cast<float>(r.time.dt * r.time.steps);
  m.scene_index = static_cast<float>(r.sceneIndex);
  m.sources = sources;
  for (const auto& run : risk::encodeRle(r.levels.level)) {
    m.runs.push_back({run.level, run.length});
  }
  if (regions) {
    for (auto& reg : risk::extractRegions(r.levels)) {
      m.regions.push_back({static_cast<std::uint8_t>(reg.level), std::move(reg.outer), std::move(reg.holes)});
    }
  }
  return m;
}

Expected<RiskMapNode> RiskMapNode::create(const Settings& s) {
  auto engine = risk::FusionEngine::create(s.fusion, makeModel(s));
  if (!engine) {
    return unexpected(engine.error());
  }
  return RiskMapNode(s, std::move(*engine));
}

Expected<void> RiskMapNode::accept(const msg::PredictedDiscs& m, std::int64_t nowNs) {
  auto r = engine_.upsert(toSource(m), nowNs);
  if (!r) {
    ++rejected_;
    ++rejectedBy_[r.error().code];
    return r;
  }
  ++accepted_;
  lastHeard_[m.source_id] = nowNs;
  return {};
}

msg::RiskMap RiskMapNode::fuse(std::int64_t nowNs) {
  const std::int64_t cutoff = nowNs - secToNs(settings_.staleAfterS);
  for (auto it = lastHeard_.begin(); it != lastHeard_.end();) {
    if (it->second < cutoff) {
      engine_.remove(it->first);
      ++staleDropped_;
      it = lastHeard_.erase(it);
    } else {
      ++it;
    }
  }
  const auto& r = engine_.fuse(nowNs);
  return toMessage(r, nowNs, static_cast<std::uint32_t>(engine_.sourceCount()), settings_.regions);
}

}  // namespace fleet::riskmap
