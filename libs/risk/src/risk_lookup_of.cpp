#include "fleet/risk/risk_lookup_of.hpp"

namespace fleet::risk {

Expected<std::shared_ptr<const risk::RiskLookup>> riskLookupOf(const msg::RiskMap& m) {
  risk::EncodedRiskMap e;
  e.origin = {m.origin_x, m.origin_y};
  e.resolution = m.resolution;
  e.width = m.width;
  e.height = m.height;
  e.levels = m.levels;
  e.stampNs = m.stamp_ns;
  e.runs.reserve(m.runs.size());
  for (const auto& r : m.runs) {
    e.runs.push_back({r.level, r.count});
  }
  return risk::RiskLookup::decode(e);
}

}  // namespace fleet::risk
