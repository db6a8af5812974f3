#include "fleet/vda5050/order_builder.hpp"

#include <algorithm>
#include <charconv>

namespace fleet::vda5050 {

int OrderBuilder::roadmapNode(const std::string& node_id) {
  int v = -1;
  if (node_id.size() < 2 || node_id[0] != 'n') {
    return -1;
  }
  const auto* end = node_id.data() + node_id.size();
  const auto r = std::from_chars(node_id.data() + 1, end, v);
  return r.ec == std::errc() && r.ptr == end && v >= 0 ? v : -1;
}

Node OrderBuilder::makeNode(const ReleaseNode& n, std::uint32_t seq, bool released,
                            const ReleaseInput& release) {
  Node node;
  node.nodeId = "n" + std::to_string(n.node);
  node.sequenceId = seq;
  node.released = released;
  node.nodePosition = NodePosition{n.x, n.y, {}, options_.allowedDeviationXY, {}, options_.mapId};
  if (released) {
    for (const auto& [at, action] : release.actions) {
      if (at == n.node &&
          std::find(sent_actions_.begin(), sent_actions_.end(), action.actionId) == sent_actions_.end()) {
        sent_actions_.push_back(action.actionId);
        node.actions.push_back(action);
      }
    }
  }
  return node;
}

Order OrderBuilder::assemble(std::vector<Node> nodes, std::int64_t stamp_ns) {
  Order o;
  o.header = {header_id_++, isoTimestamp(stamp_ns), kVersion, options_.manufacturer, options_.serial};
  o.orderId = order_id_;
  o.orderUpdateId = update_id_;
  for (std::size_t i = 1; i < nodes.size(); ++i) {
    Edge e;
    e.edgeId = nodes[i - 1].nodeId + "-" + nodes[i].nodeId;
    e.sequenceId = nodes[i - 1].sequenceId + 1;
    e.released = nodes[i].released;
    e.startNodeId = nodes[i - 1].nodeId;
    e.endNodeId = nodes[i].nodeId;
    o.edges.push_back(std::move(e));
  }
  o.nodes = std::move(nodes);
  return o;
}

Expected<Order> OrderBuilder::start(const std::string& order_id, const ReleaseInput& release,
                                    std::int64_t stamp_ns) {
  if (release.base.empty()) {
    return unexpected("vda5050.empty_release",
                      "release for '" + options_.serial + "' has no base node to start from");
  }
  order_id_ = order_id;
  update_id_ = 0;
  base_.clear();
  sent_actions_.clear();
  std::vector<Node> nodes;
  std::uint32_t seq = 0;
  for (const auto& n : release.base) {
    nodes.push_back(makeNode(n, seq, true, release));
    base_.push_back(nodes.back());
    seq += 2;
  }
  for (const auto& n : release.horizon) {
    nodes.push_back(makeNode(n, seq, false, release));
    seq += 2;
  }
  sent_ = {{update_id_, base_.size(), sent_actions_.size()}};
  return assemble(std::move(nodes), stamp_ns);
}

bool OrderBuilder::rollbackTo(std::uint32_t update_id) {
  const auto it =
      std::find_if(sent_.begin(), sent_.end(), [&](const Sent& s) { return s.update_id == update_id; });
  if (it == sent_.end()) {
    return false;
  }
  base_.resize(it->base_size);
  sent_actions_.resize(it->actions_size);
  sent_.erase(it + 1, sent_.end());
  return true;
}

Expected<std::optional<Order>> OrderBuilder::extend(const ReleaseInput& release,
                                                    std::uint32_t last_sequence_id, std::int64_t stamp_ns) {
  if (base_.empty()) {
    return unexpected("vda5050.no_order", "no order to extend for '" + options_.serial + "'");
  }
  // The sent base from the node the vehicle last passed: the new base must begin with it.
  auto from = std::find_if(base_.begin(), base_.end(),
                           [&](const Node& n) { return n.sequenceId >= last_sequence_id; });
  if (from == base_.end()) {
    return unexpected("vda5050.bad_progress", "'" + options_.serial + "' reports sequenceId " +
                                                  std::to_string(last_sequence_id) +
                                                  ", beyond the base sent");
  }
  const auto sent = static_cast<std::size_t>(base_.end() - from);
  // The release starts at the node last reported to the traffic layer. That node usually lags
  // behind the vehicle: the release passes the vehicle's last node (at k). It can be ahead of it
  // too, at a later node of the sent base (at j): a new order that began at the vehicle's last node
  // put in front of the release (startAtVehicle) runs through the release's first node.
  const auto sentNode = [&](std::size_t i) { return from[static_cast<std::ptrdiff_t>(i)]; };
  const int first = roadmapNode(from->nodeId);
  std::size_t k = 0;
  while (k < release.base.size() && release.base[k].node != first) {
    ++k;
  }
  std::size_t j = 0;
  if (k == release.base.size()) {
    k = 0;
    j = 1;
    while (j < sent && roadmapNode(sentNode(j).nodeId) != release.base.front().node) {
      ++j;
    }
    if (j == sent) {
      return unexpected("vda5050.cannot_stitch", "release for '" + options_.serial + "' does not pass node " +
                                                     from->nodeId +
                                                     " where the vehicle is: cancel and start a new order");
    }
  }
  const std::size_t overlap = sent - j;  // the sent nodes the release must repeat
  if (release.base.size() - k < overlap) {
    return std::optional<Order>{};  // the release is behind what was sent: nothing new
  }
  for (std::size_t i = 0; i < overlap; ++i) {
    if (release.base[k + i].node != roadmapNode(sentNode(j + i).nodeId)) {
      return unexpected("vda5050.cannot_stitch",
                        "release for '" + options_.serial + "' leaves the sent base at node " +
                            sentNode(j + i).nodeId + " (release has n" +
                            std::to_string(release.base[k + i].node) + "): cancel and start a new order");
    }
  }
  if (release.base.size() - k == overlap) {
    return std::optional<Order>{};  // the base did not grow; a horizon change alone is not worth an update
  }
  ++update_id_;
  std::vector<Node> nodes;
  Node stitch = base_.back();
  stitch.actions.clear();  // sent already with the node
  nodes.push_back(stitch);
  std::uint32_t seq = stitch.sequenceId + 2;
  for (std::size_t i = k + overlap; i < release.base.size(); ++i) {
    nodes.push_back(makeNode(release.base[i], seq, true, release));
    base_.push_back(nodes.back());
    seq += 2;
  }
  for (const auto& n : release.horizon) {
    nodes.push_back(makeNode(n, seq, false, release));
    seq += 2;
  }
  sent_.push_back({update_id_, base_.size(), sent_actions_.size()});
  return std::optional<Order>(assemble(std::move(nodes), stamp_ns));
}

}  // namespace fleet::vda5050
