#include "closed_stations.hpp"

#include <algorithm>

namespace fleet::manager {

ClosedStations::ClosedStations(traffic::Roadmap roadmap) : roadmap_(std::move(roadmap)) {
  for (auto& s : traffic::connectedStations(roadmap_)) {
    connectedAtStart_.insert(std::move(s));
  }
}

std::optional<std::string> ClosedStations::apply(const msg::TrafficClosure& c) {
  std::vector<std::pair<traffic::NodeId, traffic::NodeId>> lanes;
  for (const auto& e : c.lanes) {
    lanes.emplace_back(e.from, e.to);
  }
  if (auto problem =
          traffic::closureProblem(roadmap_, c.closure_id, {c.nodes.begin(), c.nodes.end()}, lanes)) {
    return problem;
  }
  if (c.active && c.area.empty() && c.nodes.empty() && c.lanes.empty()) {
    return "closure \"" + c.closure_id + "\": closes nothing (no area, nodes or lanes)";
  }
  if (auto it = inForce_.find(c.closure_id); it != inForce_.end()) {
    for (const auto& part : it->second.parts) {
      roadmap_.reopen(part);
    }
    inForce_.erase(it);
  }
  if (c.active) {
    InForce f;
    f.reason = c.reason.empty() ? "no reason given" : c.reason;
    if (!c.area.empty()) {
      f.parts.push_back(roadmap_.closeArea(c.area));
    }
    if (!c.nodes.empty()) {
      f.parts.push_back(roadmap_.closeNodes({c.nodes.begin(), c.nodes.end()}));
    }
    if (!lanes.empty()) {
      f.parts.push_back(roadmap_.closeEdges(lanes));
    }
    inForce_.emplace(c.closure_id, std::move(f));
  }
  return std::nullopt;
}

std::map<std::string, std::string, std::less<>> ClosedStations::closed() const {
  std::map<std::string, std::string, std::less<>> out;
  if (inForce_.empty()) {
    return out;
  }
  std::string why;
  for (const auto& [id, f] : inForce_) {
    why += (why.empty() ? "closure '" : "; closure '") + id + "': " + f.reason;
  }
  const auto now = traffic::connectedStations(roadmap_);
  const std::set<std::string, std::less<>> open(now.begin(), now.end());
  for (const auto& s : connectedAtStart_) {
    if (open.count(s) == 0) {
      out.emplace(s, why);
    }
  }
  return out;
}

}  // namespace fleet::manager
