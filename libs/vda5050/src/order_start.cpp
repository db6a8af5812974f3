#include "fleet/vda5050/order_start.hpp"

#include <algorithm>

namespace fleet::vda5050 {

void KnownRoadmap::clear() {
  nodes_.clear();
  edges_.clear();
}

std::optional<ReleaseNode> KnownRoadmap::node(int id) const {
  const auto it = nodes_.find(id);
  if (it == nodes_.end()) {
    return std::nullopt;
  }
  return it->second;
}

Expected<ReleaseInput> startAtVehicle(const ReleaseInput& release, const std::string& last_node_id,
                                      const KnownRoadmap& roadmap) {
  if (release.base.empty()) {
    return unexpected("vda5050.empty_release", "the release has no base node to start an order from");
  }
  ReleaseInput out = release;
  if (last_node_id.empty()) {
    return out;
  }
  const int at = OrderBuilder::roadmapNode(last_node_id);
  const auto first = "n" + std::to_string(release.base.front().node);
  if (at < 0) {
    return unexpected("vda5050.foreign_node", "the vehicle's last node '" + last_node_id +
                                                  "' is not a roadmap node: no order from " + first +
                                                  " can start there");
  }
  const auto here =
      std::find_if(out.base.begin(), out.base.end(), [&](const ReleaseNode& n) { return n.node == at; });
  if (here != out.base.end()) {
    out.base.erase(out.base.begin(), here);  // the nodes it has passed already
    return out;
  }
  const auto pos = roadmap.node(at);
  if (pos && roadmap.hasEdge(at, release.base.front().node)) {
    out.base.assign(1, *pos);
    out.base.insert(out.base.end(), release.base.begin(), release.base.end());
    return out;
  }
  return unexpected("vda5050.start_not_reachable",
                    "the release starts at " + first + ", the vehicle's last node is " + last_node_id +
                        " and " +
                        (pos ? "no roadmap edge leads from it to " + first : "its position is not known"));
}

}  // namespace fleet::vda5050
