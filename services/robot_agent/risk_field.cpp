#include "risk_field.hpp"

#include <cmath>
#include <string>

#include "fleet/risk/rle.hpp"

namespace fleet::agent {

Expected<std::shared_ptr<const RiskField>> RiskField::fromMessage(const msg::RiskMap& m) {
  if (!(m.resolution > 0.0) || !std::isfinite(m.resolution) || !std::isfinite(m.origin_x) ||
      !std::isfinite(m.origin_y)) {
    return unexpected("bad_risk_map", "RiskMap: resolution must be > 0 and origin finite");
  }
  if (m.levels < 1) {
    return unexpected("bad_risk_map", "RiskMap: levels (K) must be >= 1");
  }
  const std::size_t cells = static_cast<std::size_t>(m.width) * static_cast<std::size_t>(m.height);
  if (m.width == 0 || m.height == 0 || cells > (std::size_t{1} << 26)) {
    return unexpected("bad_risk_map", "RiskMap: width x height must be in 1 .. 2^26 cells, got " +
                                          std::to_string(m.width) + " x " + std::to_string(m.height));
  }
  std::vector<risk::LevelRun> runs;
  runs.reserve(m.runs.size());
  for (const auto& r : m.runs) {
    runs.push_back({r.level, r.count});
  }
  auto levels = risk::decodeRle(runs, cells, m.levels);
  if (!levels) {
    return unexpected(levels.error().code, "RiskMap runs: " + levels.error().message);
  }
  auto f = std::make_shared<RiskField>();
  f->origin_ = {m.origin_x, m.origin_y};
  f->res_ = m.resolution;
  f->w_ = static_cast<int>(m.width);
  f->h_ = static_cast<int>(m.height);
  f->k_ = m.levels;
  f->stamp_ = m.stamp_ns;
  f->level_ = std::move(*levels);
  return std::shared_ptr<const RiskField>(std::move(f));
}

double RiskField::at(Vec2 p) const {
  const double fx = std::floor((p.x - origin_.x) / res_);
  const double fy = std::floor((p.y - origin_.y) / res_);
  if (!(fx >= 0.0 && fy >= 0.0 && fx < w_ && fy < h_)) {
    return 0.0;
  }
  const auto i = static_cast<std::size_t>(fy) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(fx);
  return static_cast<double>(level_[i]) / static_cast<double>(k_);
}

}  // namespace fleet::agent
