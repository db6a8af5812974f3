#include "fleet/risk/risk_lookup.hpp"

#include <cmath>
#include <string>

namespace fleet::risk {

Expected<std::shared_ptr<const RiskLookup>> RiskLookup::decode(const EncodedRiskMap& m) {
  if (!(m.resolution > 0.0) || !std::isfinite(m.resolution) || !std::isfinite(m.origin.x) ||
      !std::isfinite(m.origin.y)) {
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
  auto levels = decodeRle(m.runs, cells, m.levels);
  if (!levels) {
    return unexpected(levels.error().code, "RiskMap runs: " + levels.error().message);
  }
  auto f = std::make_shared<RiskLookup>();
  f->origin_ = m.origin;
  f->res_ = m.resolution;
  f->w_ = static_cast<int>(m.width);
  f->h_ = static_cast<int>(m.height);
  f->k_ = m.levels;
  f->stamp_ = m.stampNs;
  f->level_ = std::move(*levels);
  return std::shared_ptr<const RiskLookup>(std::move(f));
}

double RiskLookup::at(Vec2 p) const {
  const double fx = std::floor((p.x - origin_.x) / res_);
  const double fy = std::floor((p.y - origin_.y) / res_);
  if (!(fx >= 0.0 && fy >= 0.0 && fx < w_ && fy < h_)) {
    return 0.0;
  }
  const auto i = static_cast<std::size_t>(fy) * static_cast<std::size_t>(w_) + static_cast<std::size_t>(fx);
  return static_cast<double>(level_[i]) / static_cast<double>(k_);
}

}  // namespace fleet::risk
