#include "traffic_node.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include "fleet/core/clock.hpp"
#include "fleet/traffic/roadmap_config.hpp"

namespace fleet::trafficmgr {

using traffic::kNoNode;
using traffic::NodeId;

namespace {
/// s a robot reports itself blocked on its node (by a person or something the map does not show: a
/// robot ahead is waited on, not reported) before it gives back the node after its own. Its agent
/// reports after 3 s held.
constexpr double kGiveBackAfterS = 10.0;
}  // namespace

Settings readSettings(Config& cfg) {
  Settings s;
  cfg.rejectUnknownKeys({"site",          "rate_hz",     "settle_s",     "robot_timeout_s", "place_tolerance",
                         "clock",         "lockstep",    "max_lag",      "base_ahead",      "max_base_nodes",
                         "horizon_nodes", "seed",        "detour_after", "detour_penalty",  "occupied_cost_s",
                         "station_lines", "let_pass",    "roadmap",      "risk_cost_s",     "risk_period_s",
                         "yield_after_s", "yield_for_s", "yield_cost_s", "summary_file",    "core"});
  s.site = cfg.string("site", "");
  s.summaryFile = cfg.string("summary_file", "");
  s.rateHz = cfg.number("rate_hz", 10.0, {0.0, 1000.0, true});
  s.settleS = cfg.number("settle_s", 3.0, {0.0, 600.0});
  s.robotTimeoutS = cfg.number("robot_timeout_s", 5.0, {0.0, 3600.0, true});
  s.placeTolerance = cfg.number("place_tolerance", 0.5, {0.0, 10.0, true});
  s.clock = cfg.string("clock", "wall", {"wall", "sim"});
  s.lockstep = cfg.boolean("lockstep", false);
  s.stationLines = cfg.boolean("station_lines", s.stationLines);
  if (s.lockstep && s.clock != "sim")
    cfg.problem("lockstep", "requires \"clock\": \"sim\"");
  s.traffic.core =
      *traffic::plannerCoreFrom(cfg.string("core", traffic::toString(s.traffic.core), {"pibt", "sipp"}));
  s.traffic.maxLag = cfg.integer("max_lag", s.traffic.maxLag, {1, 100000});
  s.traffic.letPassBehind = cfg.integer("let_pass", s.traffic.letPassBehind, {0, 100000});
  s.traffic.release.baseAhead = cfg.number("base_ahead", s.traffic.release.baseAhead, {0.0, 100.0});
  s.traffic.release.maxBaseNodes = static_cast<std::size_t>(
      cfg.integer("max_base_nodes", static_cast<std::int64_t>(s.traffic.release.maxBaseNodes), {1, 63}));
  s.traffic.release.horizonNodes = static_cast<std::size_t>(
      cfg.integer("horizon_nodes", static_cast<std::int64_t>(s.traffic.release.horizonNodes), {0, 32}));
  s.traffic.pibt.seed = static_cast<std::uint64_t>(cfg.integer("seed", 1, {0, 1e15}));
  s.traffic.pibt.detourAfter =
      static_cast<int>(cfg.integer("detour_after", s.traffic.pibt.detourAfter, {0, 100000}));
  s.traffic.pibt.detourPenalty =
      static_cast<float>(cfg.number("detour_penalty", s.traffic.pibt.detourPenalty, {0.0, 1e6}));
  s.traffic.pibt.occupiedCost =
      static_cast<float>(cfg.number("occupied_cost_s", s.traffic.pibt.occupiedCost, {0.0, 600.0}));
  s.riskCostS = cfg.number("risk_cost_s", s.riskCostS, {0.0, 3600.0});
  s.riskPeriodS = cfg.number("risk_period_s", s.riskPeriodS, {0.0, 3600.0});
  s.yieldAfterS = cfg.number("yield_after_s", s.yieldAfterS, {0.0, 3600.0});
  s.yieldForS = cfg.number("yield_for_s", s.yieldForS, {0.0, 3600.0});
  s.yieldCostS = cfg.number("yield_cost_s", s.yieldCostS, {0.0, 3600.0});
  s.roadmap = traffic::readRoadmapOptions(cfg.child("roadmap"));
  return s;
}

TrafficNode::TrafficNode(const site::Site& site, Settings settings, std::uint32_t epoch)
    : settings_(std::move(settings)),
      epoch_(epoch),
      roadmap_(traffic::buildRoadmap(site, settings_.roadmap)),
      reach_(roadmap_.graph, std::size_t{64} << 20) {
  traffic::TrafficOptions options = settings_.traffic;
  // The plan kept in time takes each turn on the spot at its real duration.
  options.turnTime = [this](NodeId a, NodeId b, NodeId c) { return roadmap_.extraTurn(a, b, c); };
  control_ =
      std::make_unique<traffic::TrafficControl>(roadmap_.graph, std::vector<NodeId>{}, std::move(options));
  if (settings_.stationLines)
    control_->setStations(traffic::stationLines(roadmap_));
}

bool TrafficNode::onRiskMap(const risk::RiskLookup& risk, std::int64_t nowNs) {
  if (settings_.riskCostS <= 0.0 || (riskNs_ >= 0 && nowNs - riskNs_ < secToNs(settings_.riskPeriodS)))
    return false;
  riskNs_ = nowNs;
  riskCost_.resize(roadmap_.graph.size());
  for (std::size_t v = 0; v < riskCost_.size(); ++v)
    riskCost_[v] =
        static_cast<float>(settings_.riskCostS * risk.at(roadmap_.graph.position(static_cast<NodeId>(v))));
  applyNodeCost();
  ++counters_.riskUpdates;
  return true;
}

void TrafficNode::applyNodeCost() {
  std::vector<float> cost = riskCost_;
  for (const auto& [id, r] : robots_) {
    if (r.yieldNodes.empty())
      continue;
    cost.resize(roadmap_.graph.size(), 0.0F);
    for (const auto v : r.yieldNodes)
      cost[static_cast<std::size_t>(v)] += static_cast<float>(settings_.yieldCostS);
  }
  control_->setNodeCost(std::move(cost));
}

bool TrafficNode::updateYield(Robot& r, std::int64_t nowNs, bool timedOut) {
  // Only a robot that follows its releases, is heard from, not docking or paused, and stands on
  // the node it last reported may yield: taking back its release gives away the node it might
  // otherwise be driving into.
  const NodeId reported = control_->at(static_cast<std::size_t>(r.index));
  constexpr double kOnNodeM = 0.2;  // well short of the next node (lattice spacing 0.5 m)
  const bool onNode =
      roadmap_.graph.valid(reported) &&
      (roadmap_.graph.position(reported) - Vec2{r.last.pose.x, r.last.pose.y}).norm() <= kOnNodeM;
  const bool mayYield = r.last.follows && !r.last.holding && !timedOut && onNode;
  if (!r.last.blocked || !mayYield) {
    r.blockedSinceNs = -1;
    r.blockedAhead.clear();
  } else if (r.blockedSinceNs < 0) {
    // What holds it stands on the nodes just ahead on its way: taken now, before holding it
    // retracts its release to where it stands.
    r.blockedSinceNs = nowNs;
    r.blockedAhead.clear();
    for (std::size_t i = 1; i < r.sent.base.size() && r.blockedAhead.size() < 3; ++i) {
      const auto& n = r.sent.base[i];
      if (n.node != reported && (Vec2{n.x, n.y} - Vec2{r.last.pose.x, r.last.pose.y}).norm() <= 1.5)
        r.blockedAhead.push_back(n.node);
    }
  }
  if (r.blockedSinceNs < 0) {
    r.gaveBack = false;
  } else if (!r.gaveBack && r.yieldUntilNs < 0 &&
             static_cast<double>(nowNs - r.blockedSinceNs) * 1e-9 >= kGiveBackAfterS) {
    // Held, it keeps the node after its own (TrafficControl::setHeld), so the plan places it there
    // and the robots behind it and across its way wait on a step it cannot make (a robot waited
    // 180 s behind one held by a person in a 40-robot run). Blocked on its node this long, it gives
    // that node back and stays held where it stands; unlike yielding, it is not planned meanwhile,
    // so it does not shuttle back and forth while the person stays.
    control_->retractStanding(static_cast<std::size_t>(r.index));
    r.gaveBack = true;
    ++counters_.gaveBack;
  }
  bool changed = false;
  if (r.yieldUntilNs >= 0 && nowNs >= r.yieldUntilNs) {
    r.yieldUntilNs = -1;
    r.blockedSinceNs = r.last.blocked ? nowNs : -1;  // still blocked: yield again after a while
    changed = !r.yieldNodes.empty();
    r.yieldNodes.clear();
  }
  if (settings_.yieldAfterS > 0.0 && r.yieldUntilNs < 0 && r.blockedSinceNs >= 0 &&
      static_cast<double>(nowNs - r.blockedSinceNs) * 1e-9 >= settings_.yieldAfterS) {
    // Those nodes cost more for a while, so the plan takes it back or round when that is shorter
    // (and others keep off them meanwhile).
    r.yieldNodes = r.blockedAhead;
    control_->retractStanding(static_cast<std::size_t>(r.index));
    r.yieldUntilNs = nowNs + secToNs(settings_.yieldForS);
    ++counters_.yields;
    changed = changed || !r.yieldNodes.empty();
  }
  return changed;
}

TrafficNode::ClosureResult TrafficNode::onClosure(const msg::TrafficClosure& c) {
  ClosureResult out;
  std::vector<std::pair<NodeId, NodeId>> lanes;
  for (const auto& e : c.lanes) {
    lanes.emplace_back(e.from, e.to);
  }
  if (auto problem =
          traffic::closureProblem(roadmap_, c.closure_id, {c.nodes.begin(), c.nodes.end()}, lanes)) {
    out.error = std::move(*problem);
    return out;
  }
  if (c.active && c.area.empty() && c.nodes.empty() && c.lanes.empty()) {
    out.error = "closure \"" + c.closure_id + "\": closes nothing (no area, nodes or lanes)";
    return out;
  }
  if (auto it = closures_.find(c.closure_id); it != closures_.end()) {
    // The same closure again (a reader that joins late, a repeated sample) changes nothing.
    const auto& said = it->second.said;
    if (c.active && said.area == c.area && said.nodes == c.nodes && said.lanes == c.lanes)
      return out;
    for (const auto& part : it->second.parts)
      roadmap_.reopen(part);
    closures_.erase(it);
    out.changed = true;
  }
  if (c.active) {
    std::vector<traffic::Closure> parts;
    if (!c.area.empty())
      parts.push_back(roadmap_.closeArea(c.area));
    if (!c.nodes.empty())
      parts.push_back(roadmap_.closeNodes({c.nodes.begin(), c.nodes.end()}));
    if (!lanes.empty())
      parts.push_back(roadmap_.closeEdges(lanes));
    for (const auto& part : parts) {
      out.nodes += part.nodes.size();
      out.edges += part.edges.size();
      out.cutOff.insert(out.cutOff.end(), part.cutOff.begin(), part.cutOff.end());
    }
    std::sort(out.cutOff.begin(), out.cutOff.end());
    out.cutOff.erase(std::unique(out.cutOff.begin(), out.cutOff.end()), out.cutOff.end());
    closures_[c.closure_id] = InForce{c, std::move(parts)};
    out.changed = true;
  }
  if (out.changed) {
    ++revision_;
    reach_.invalidate();
    control_->graphChanged();
  }
  return out;
}

std::vector<std::string> TrafficNode::closures() const {
  std::vector<std::string> ids;
  for (const auto& [id, inForce] : closures_)
    ids.push_back(id);
  return ids;
}

msg::Roadmap TrafficNode::roadmapMessage(std::int64_t nowNs) const {
  msg::Roadmap m;
  m.epoch = epoch_;
  m.revision = revision_;
  m.stamp_ns = nowNs;
  m.robot_radius = roadmap_.options.radius;
  const auto& g = roadmap_.graph;
  for (NodeId v = 0; static_cast<std::size_t>(v) < g.size(); ++v) {
    m.nodes.push_back({v, g.position(v).x, g.position(v).y});
    m.kinds.push_back(static_cast<std::uint8_t>(roadmap_.kind(v)));
    m.open.push_back(g.isOpen(v));
    for (const auto& e : g.edges(v)) {
      m.edges.push_back({v, e.to, static_cast<float>(e.duration), e.open});
    }
  }
  return m;
}

std::map<std::string, traffic::BaseEnds> TrafficNode::baseEnds() const {
  std::map<std::string, traffic::BaseEnds> out;
  for (const auto& [id, r] : robots_) {
    if (r.index >= 0 && control_ && static_cast<std::size_t>(r.index) < control_->robots())
      out[id] = control_->baseEnds(static_cast<std::size_t>(r.index));
  }
  return out;
}

int TrafficNode::indexOf(const std::string& robot) const {
  auto it = robots_.find(robot);
  return it == robots_.end() ? -1 : it->second.index;
}

std::size_t TrafficNode::robotsPlaced() const {
  return byIndex_.size();
}

NodeId TrafficNode::goalNode(const msg::TrafficProgress& p, std::string& why) const {
  if (!p.has_goal)
    return kNoNode;
  // A goal the roadmap does not connect to where the robot is: refused and logged, the robot held
  // where it is, instead of standing with a goal the planner can never bring it to.
  auto reachable = [&](NodeId goal, const std::string& what) {
    const NodeId from = placeNode(p);
    if (from == kNoNode ||
        reach_.to(goal)[static_cast<std::size_t>(from)] != traffic::DistanceTable::kUnreachable)
      return goal;
    why = what + " cannot be reached on the roadmap from node " + std::to_string(from) +
          " (the roadmap does not connect them: see the traffic manager's roadmap problems at start)";
    return kNoNode;
  };
  if (!p.goal_station.empty()) {
    const auto* s = roadmap_.station(p.goal_station);
    if (s != nullptr && s->dock != kNoNode)
      return reachable(s->dock, "goal station \"" + p.goal_station + "\"");
    if (s == nullptr) {
      why = "goal station \"" + p.goal_station + "\" is not on the site";
    } else {
      why = "goal station \"" + p.goal_station + "\" has no roadmap node (the robot does not fit there)";
    }
    return kNoNode;
  }
  const Vec2 g{p.goal.x, p.goal.y};
  const NodeId v = roadmap_.nearest(g);
  if (v == kNoNode || (roadmap_.graph.position(v) - g).norm() > settings_.placeTolerance) {
    std::ostringstream os;
    os << "goal (" << p.goal.x << ", " << p.goal.y << ") is more than " << settings_.placeTolerance
       << " m from the roadmap";
    why = os.str();
    return kNoNode;
  }
  std::ostringstream os;
  os << "goal (" << p.goal.x << ", " << p.goal.y << ")";
  return reachable(v, os.str());
}

NodeId TrafficNode::placeNode(const msg::TrafficProgress& p) const {
  const Vec2 at{p.pose.x, p.pose.y};
  const auto& g = roadmap_.graph;
  if (p.node >= 0 && g.valid(p.node) && (g.position(p.node) - at).norm() <= settings_.placeTolerance)
    return p.node;
  const NodeId v = roadmap_.nearest(at);
  if (v == kNoNode || (g.position(v) - at).norm() > settings_.placeTolerance)
    return kNoNode;
  return v;
}

std::optional<std::string> TrafficNode::onProgress(const msg::TrafficProgress& p, std::int64_t nowNs) {
  ++counters_.reports;
  if (startNs_ < 0)
    startNs_ = nowNs;  // the settling time runs from the first thing heard
  auto refuse = [&](const std::string& what) -> std::optional<std::string> {
    ++counters_.refused;
    return "progress from \"" + p.robot_id + "\": " + what;
  };
  if (p.robot_id.empty())
    return refuse("no robot id");
  if (!std::isfinite(p.pose.x) || !std::isfinite(p.pose.y) || !std::isfinite(p.goal.x) ||
      !std::isfinite(p.goal.y)) {
    return refuse("a pose is not finite");
  }
  const auto& g = roadmap_.graph;
  if (p.node < -1 || (p.node >= 0 && !g.valid(p.node))) {
    return refuse("node " + std::to_string(p.node) + " is not on the roadmap (0.." +
                  std::to_string(g.size() - 1) + ")");
  }
  if (counters_.releases == 0 && p.epoch >= epoch_) {
    epoch_ = p.epoch + 1;  // a robot follows a later incarnation's releases (a seeded epoch restarted)
  }
  Robot& r = robots_[p.robot_id];
  r.last = p;
  r.heardNs = nowNs;
  if (p.node != r.lastNode || r.movedNs == 0) {
    r.lastNode = p.node;
    r.movedNs = nowNs;
  }
  std::optional<std::string> problem;
  if (r.index >= 0) {
    const auto idx = static_cast<std::size_t>(r.index);
    if (p.epoch == epoch_ && p.node >= 0) {
      const auto rep = control_->reached(idx, p.node);
      if (rep == traffic::Report::NotReleased) {
        ++counters_.refused;
        problem = "progress from \"" + p.robot_id + "\": node " + std::to_string(p.node) +
                  " was not released to it (held at node " + std::to_string(control_->at(idx)) + ")";
      }
    }
    apply(r, nowNs);
  }
  std::string why;
  if (goalNode(p, why) == kNoNode && !why.empty() && !problem) {
    ++counters_.refused;
    problem = "progress from \"" + p.robot_id + "\": " + why;
  }
  return problem;
}

void TrafficNode::apply(Robot& r, std::int64_t nowNs) {
  const auto idx = static_cast<std::size_t>(r.index);
  const bool timedOut = static_cast<double>(nowNs - r.heardNs) * 1e-9 > settings_.robotTimeoutS;
  if (updateYield(r, nowNs, timedOut))
    applyNodeCost();
  const bool yielding = r.yieldUntilNs >= 0;
  const bool held = r.last.holding || (r.last.blocked && !yielding) || !r.last.follows || timedOut;
  control_->setHeld(idx, held);
  std::string why;
  const NodeId goal = goalNode(r.last, why);
  if (goal != r.goal || r.last.priority != r.priority) {
    if (!control_->setGoal(idx, goal, r.last.priority))
      control_->setGoal(idx, kNoNode);
    r.goal = goal;
    r.priority = r.last.priority;
  }
}

void TrafficNode::place(std::int64_t nowNs) {
  for (auto& [id, r] : robots_) {
    if (r.index >= 0)
      continue;
    const NodeId v = placeNode(r.last);
    if (v == kNoNode)
      continue;
    try {
      r.index = static_cast<int>(control_->addRobot(v));
    } catch (const traffic::PlanStepError&) {
      continue;  // a robot holds a conflicting node: try again next tick
    }
    byIndex_.push_back(id);
    r.sent = msg::TrafficRelease{};
    apply(r, nowNs);
  }
}

msg::TrafficRelease TrafficNode::toMessage(const std::string& id, const traffic::Release& rel,
                                           const Robot& r) const {
  msg::TrafficRelease m;
  m.robot_id = id;
  m.epoch = epoch_;
  const auto& g = roadmap_.graph;
  for (std::size_t i = 0; i < rel.base.size() && i < 64; ++i) {
    m.base.push_back({rel.base[i], g.position(rel.base[i]).x, g.position(rel.base[i]).y});
  }
  for (std::size_t i = 0; i < rel.horizon.size() && i < 32; ++i) {
    m.horizon.push_back({rel.horizon[i], g.position(rel.horizon[i]).x, g.position(rel.horizon[i]).y});
  }
  m.ends_at_goal = r.goal != kNoNode && !rel.base.empty() && rel.base.back() == r.goal;
  return m;
}

std::vector<msg::TrafficRelease> TrafficNode::tick(std::int64_t nowNs) {
  std::vector<msg::TrafficRelease> out;
  if (startNs_ < 0)
    startNs_ = nowNs;
  if (static_cast<double>(nowNs - startNs_) * 1e-9 < settings_.settleS)
    return out;
  const auto t0 = std::chrono::steady_clock::now();
  for (auto& [id, r] : robots_) {
    if (r.index >= 0)
      apply(r, nowNs);  // time-outs
  }
  place(nowNs);
  counters_.plannedSteps += static_cast<std::uint64_t>(control_->update());
  counters_.replans = control_->stats().replans;
  for (auto& [id, r] : robots_) {
    if (r.index < 0 || !r.last.follows)
      continue;
    auto m = toMessage(id, control_->release(static_cast<std::size_t>(r.index)), r);
    if (m.base == r.sent.base && m.horizon == r.sent.horizon && m.ends_at_goal == r.sent.ends_at_goal)
      continue;
    m.seq = r.sent.seq + 1;
    m.stamp_ns = nowNs;
    r.sent = m;
    out.push_back(m);
    ++counters_.releases;
  }
  counters_.lastTickMs =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  counters_.maxTickMs = std::max(counters_.maxTickMs, counters_.lastTickMs);
  return out;
}

std::vector<msg::TrafficRelease> TrafficNode::allReleases() const {
  std::vector<msg::TrafficRelease> out;
  for (const auto& [id, r] : robots_) {
    if (r.index >= 0 && r.sent.seq > 0)
      out.push_back(r.sent);
  }
  return out;
}

std::vector<std::string> TrafficNode::stalled(std::int64_t nowNs, double minS) const {
  std::vector<std::string> out;
  for (const auto& [id, r] : robots_) {
    if (r.index < 0 || r.goal == kNoNode || control_->arrived(static_cast<std::size_t>(r.index)))
      continue;
    const double still = static_cast<double>(nowNs - r.movedNs) * 1e-9;
    if (still < minS)
      continue;
    std::ostringstream os;
    os << "robot \"" << id << "\" (index " << r.index << ") reached no new node for "
       << static_cast<int>(still) << " s: " << control_->explain(static_cast<std::size_t>(r.index));
    if (r.last.blocked)
      os << "; it reports itself blocked";
    if (r.last.holding)
      os << "; it reports itself holding (docking, dwelling, paused or lost)";
    if (const double silentS = static_cast<double>(nowNs - r.heardNs) * 1e-9;
        silentS > settings_.robotTimeoutS)
      os << "; not heard from for " << static_cast<int>(silentS) << " s";
    if (!r.last.follows)
      os << "; it does not follow releases";
    out.push_back(os.str());
  }
  return out;
}

}  // namespace fleet::trafficmgr
