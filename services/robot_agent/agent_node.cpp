#include "agent_node.hpp"

#include <algorithm>
#include <cmath>
#include <functional>
#include <thread>

#include "fleet/control/cruise.hpp"
#include "fleet/core/ids.hpp"
#include "fleet/core/logging.hpp"
#include "fleet/risk/risk_lookup_of.hpp"
#include "fleet/site/wall_segments.hpp"
#include "fleet/validation/sample_checks.hpp"

namespace fleet::agent {

Expected<std::unique_ptr<AgentNode>> AgentNode::create(const World& world, const Settings& s,
                                                       const SavedPoses& resume) {
  MapFacts facts;
  // Robots keep clear of the map with the site's no-go zones blocked; the walls the localizer
  // matches its scan lines against come from the map itself (a zone is no wall).
  std::shared_ptr<const planning::OccupancyGrid> raw = world.map;
  std::function<double(Vec2)> speedLimit;
  if (world.site) {
    const auto& noGo = world.site->layers.noGo;
    if (std::any_of(noGo.begin(), noGo.end(), [](std::uint8_t c) { return c != 0; })) {
      raw = std::make_shared<const planning::OccupancyGrid>(world.site->drivable());
    }
    const auto& limits = world.site->layers.speedLimit;
    if (std::any_of(limits.begin(), limits.end(), [](float v) { return std::isfinite(v); })) {
      speedLimit = [st = world.site](Vec2 p) { return st->speedLimitAt(p); };
    }
    facts.siteName = world.site->name;
    facts.zones = world.site->zones.size();
    facts.speedLimits = static_cast<bool>(speedLimit);
  }
  // The walls every localizer matches its scan lines against: faces of 0.5 m and more (the line
  // extractor keeps nothing shorter).
  auto walls = std::make_shared<std::vector<estimation::MapSegment>>();
  for (const auto& w : site::wallSegments(*world.map, agentLineExtraction().minLength)) {
    walls->push_back({w.a, w.b, w.normal});
  }
  facts.wallFaces = walls->size();

  std::vector<std::unique_ptr<Agent>> agents;
  for (const auto& r : world.robots) {
    if (!s.only.empty() && std::find(s.only.begin(), s.only.end(), r.id) == s.only.end()) {
      continue;
    }
    AgentParams p;
    p.id = r.id;
    p.start = r.start;
    if (const auto it = resume.find(r.id); it != resume.end()) {
      p.resumeAt = it->second.pose;
      p.resumeWheels = it->second.wheels;
    }
    p.radius = r.radius;
    p.wheelBase = r.wheelBase;
    p.vMax = control::agentCruiseSpeed(r.limits);
    p.wMax = r.limits.omegaMax;
    p.localPlanner = s.localPlanner;
    p.dwa = s.dwa;
    p.riskStepping = s.riskStepping;
    p.safety = s.safety;
    p.sensorTimeoutS = s.sensorTimeoutS;
    p.returnHomeS = s.returnHomeS;
    p.speedLimit = speedLimit;
    p.limits = r.limits;
    p.limits.vMax = p.vMax;
    p.landmarks = world.landmarks;
    p.walls = walls;
    p.lineUpdates = s.lineUpdates;
    p.progress = s.progress;
    agents.push_back(std::make_unique<Agent>(p, raw));
  }
  if (agents.empty()) {
    return unexpected("no_robots", "none of the requested robots is in the scenario");
  }
  const unsigned threads =
      std::max(1u, std::min(s.threads == 0 ? std::thread::hardware_concurrency() : s.threads,
                            static_cast<unsigned>(agents.size())));
  std::unique_ptr<AgentNode> node(new AgentNode(s, threads));
  node->facts_ = std::move(facts);
  node->agents_ = std::move(agents);
  for (auto& a : node->agents_) {
    node->byId_[a->id()] = a.get();
  }
  node->outs_.resize(node->agents_.size());
  for (std::size_t i = 0; i < node->agents_.size(); ++i) {
    const auto n = static_cast<std::int64_t>(node->agents_.size());
    node->peopleReports_.emplace_back(kPeopleSeenPeriodNs,
                                      kPeopleSeenPeriodNs * static_cast<std::int64_t>(i) / n);
  }
  return node;
}

Agent* AgentNode::hosted(const std::string& id) {
  const auto it = byId_.find(id);
  return it == byId_.end() ? nullptr : it->second;
}

const Agent* AgentNode::find(const std::string& id) const {
  const auto it = byId_.find(id);
  return it == byId_.end() ? nullptr : it->second;
}

template <class T>
std::optional<validation::Rejection> AgentNode::refused(T& sample) {
  validation::Rejection why;
  if (validation::admit(sample, rejections_, &why)) {
    return std::nullopt;
  }
  refusals_.push_back({why.topic + ":" + why.reason, "refused " + why.topic + ": " + why.detail});
  return why;
}

template <class T>
std::vector<T> AgentNode::admitted(std::vector<T> samples) {
  std::erase_if(samples, [&](T& s) { return refused(s).has_value(); });
  return samples;
}

void AgentNode::onFrames(std::vector<msg::SensorFrame> frames) {
  for (const auto& f : admitted(std::move(frames))) {
    if (Agent* a = hosted(f.robot_id)) {
      a->onFrame(f);
    }
  }
}

void AgentNode::onRobotStates(std::vector<msg::RobotState> states) {
  for (const auto& s : admitted(std::move(states))) {
    if (byId_.count(s.robot_id) != 0) {
      continue;  // hosted here: handed over in-process after the step
    }
    if (const auto o = Agent::otherOf(s)) {
      const std::size_t slot = slotOf(s.robot_id);
      for (auto& a : agents_) {
        a->onOtherRobot(slot, *o);
      }
    }
  }
}

void AgentNode::onAssignments(std::vector<msg::TaskAssignment> assignments) {
  for (auto& a : assignments) {
    Agent* robot = hosted(a.robot_id);
    const auto why = refused(a);
    if (!why && !managerEpoch_.admit(a.epoch)) {
      // Sent by a fleet manager whose lease has passed to another: never acted on or answered.
      if (robot != nullptr) {
        refusals_.push_back({"TaskAssignment:stale_epoch", "ignored TaskAssignment for " + a.robot_id +
                                                               " of manager epoch " +
                                                               std::to_string(a.epoch) + " (newest " +
                                                               std::to_string(managerEpoch_.newest()) + ")"});
      }
      continue;
    }
    if (!why) {
      if (robot != nullptr) {
        robot->onAssignment(a);
      }
    } else if (robot != nullptr && isValidId(a.task_id)) {
      robot->refuseAssignment(a, why->detail);  // the manager hears why and retries elsewhere
    }
  }
}

void AgentNode::onReleases(std::vector<msg::TrafficRelease> releases) {
  for (const auto& r : admitted(std::move(releases))) {
    if (Agent* a = hosted(r.robot_id)) {
      a->onRelease(r);
    }
  }
}

void AgentNode::onRiskMaps(std::vector<msg::RiskMap> maps) {
  maps = admitted(std::move(maps));
  if (maps.empty() || !settings_.useRisk) {
    return;
  }
  if (auto field = risk::riskLookupOf(maps.back())) {
    for (auto& a : agents_) {
      a->onRiskMap(*field);
    }
  } else {
    refusals_.push_back({"risk_map", "RiskMap ignored: " + field.error().message});
  }
}

const std::vector<AgentOutput>& AgentNode::step(std::int64_t nowNs, double dt) {
  // Each agent touches only its own state and the const shared maps.
  pool_.forEach(agents_.size(), [&](std::size_t i) {
    logging::ScopedField robotField("robot", agents_[i]->id());  // on whatever a step logs
    outs_[i] = agents_[i]->step(nowNs, dt);
    outs_[i].command.seq = static_cast<std::uint32_t>(cycles_);
    outs_[i].people =
        peopleReports_[i].due(agents_[i]->id(), nowNs, agents_[i]->perception(), agents_[i]->sensorLost());
  });
  others_.resize(agents_.size());
  for (std::size_t i = 0; i < agents_.size(); ++i) {
    others_[i] = Agent::otherOf(outs_[i].state);
    if (hostedSlot_.size() <= i) {
      hostedSlot_.push_back(slotOf(agents_[i]->id()));
    }
  }
  pool_.forEach(agents_.size(), [&](std::size_t j) {
    for (std::size_t i = 0; i < agents_.size(); ++i) {
      if (i != j && others_[i]) {
        agents_[j]->onOtherRobot(hostedSlot_[i], *others_[i]);
      }
    }
  });
  ++cycles_;
  return outs_;
}

std::vector<Refusal> AgentNode::takeRefusals() {
  std::vector<Refusal> r;
  r.swap(refusals_);
  return r;
}

Agent::Conduct AgentNode::conduct() const {
  Agent::Conduct c;
  for (const auto& a : agents_) {
    c.plannerRecoveries += a->conduct().plannerRecoveries;
    c.rejoins += a->conduct().rejoins;
  }
  return c;
}

LineStats AgentNode::lineStats() const {
  LineStats ls;
  for (const auto& a : agents_) {
    const auto& l = a->lineStats();
    ls.scans += l.scans;
    ls.scansNoLines += l.scansNoLines;
    ls.extracted += l.extracted;
    ls.matched += l.matched;
    ls.accepted += l.accepted;
    ls.rejectedByFilter += l.rejectedByFilter;
    ls.noWallFacing += l.noWallFacing;
    ls.outsideGate += l.outsideGate;
    ls.noOverlap += l.noOverlap;
    ls.ambiguous += l.ambiguous;
  }
  return ls;
}

std::uint64_t AgentNode::poseDoubts() const {
  std::uint64_t n = 0;
  for (const auto& a : agents_) {
    n += a->poseWatch().doubts();
  }
  return n;
}

std::uint64_t AgentNode::resumeTotalsRefused() const {
  return static_cast<std::uint64_t>(
      std::count_if(agents_.begin(), agents_.end(), [](const auto& a) { return a->resumeTotalsRefused(); }));
}

std::uint64_t AgentNode::driverRestarts() const {
  std::uint64_t n = 0;
  for (const auto& a : agents_) {
    n += a->driverRestarts();
  }
  return n;
}

ReleaseCounts AgentNode::releaseCounts() const {
  ReleaseCounts rc;
  for (const auto& a : agents_) {
    rc.accepted += a->releases().accepted;
    rc.foreign += a->releases().foreign;
    rc.stale += a->releases().stale;
    rc.offNode += a->releases().offNode;
    rc.malformed += a->releases().malformed;
  }
  return rc;
}

nlohmann::json AgentNode::statsJson() const {
  const auto c = conduct();
  const auto ls = lineStats();
  const auto rc = releaseCounts();
  nlohmann::json m;
  m["samples"] = rejections_.toJson();
  m["conduct"] = {{"planner_recoveries", c.plannerRecoveries}, {"rejoins", c.rejoins}};
  m["localization"] = {{"line_updates", settings_.lineUpdates},
                       {"scans", ls.scans},
                       {"skipped_no_lines", ls.scansNoLines},
                       {"lines_extracted", ls.extracted},
                       {"lines_matched", ls.matched},
                       {"lines_accepted", ls.accepted},
                       {"lines_rejected_by_filter", ls.rejectedByFilter},
                       {"unmatched_no_wall_facing", ls.noWallFacing},
                       {"unmatched_outside_gate", ls.outsideGate},
                       {"unmatched_no_overlap", ls.noOverlap},
                       {"unmatched_ambiguous", ls.ambiguous},
                       {"pose_doubts", poseDoubts()},
                       {"resume_totals_refused", resumeTotalsRefused()},
                       {"driver_restarts", driverRestarts()}};
  m["traffic"] = {{"releases_taken", rc.accepted},
                  {"ignored_foreign", rc.foreign},
                  {"ignored_stale", rc.stale},
                  {"ignored_off_node", rc.offNode},
                  {"ignored_malformed", rc.malformed}};
  return m;
}

}  // namespace fleet::agent
