// Equivalence check for refactors of the robot agent: steps 20 agents in-process on the small
// warehouse with ideal kinematics, the other robots' states, a risk map that moves with the robots,
// the traffic manager's node in-process (their releases from their progress reports, as over DDS)
// and a few operator actions (pause, resume, cancel, a second order), and prints a hash of every
// output. Built from two commits, equal hashes mean the agent computed the same thing (how the
// agent's parts were shown to be pure moves: docs/architecture.md).
//
//   agent_trace [LOCAL_PLANNER [STEPS]]     default: dwa 3000
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <memory>
#include <string>
#include <vector>

#include "agent.hpp"
#include "fleet/risk/risk_lookup_of.hpp"
#include "fleet/risk/rle.hpp"
#include "fleet/site/site_loader.hpp"
#include "traffic_node.hpp"

using namespace fleet;

static std::uint64_t h = 1469598103934665603ULL;
static void mix(const void* p, std::size_t n) {
  const auto* b = static_cast<const unsigned char*>(p);
  for (std::size_t i = 0; i < n; ++i) {
    h = (h ^ b[i]) * 1099511628211ULL;
  }
}
static void mixd(double d) {
  mix(&d, sizeof d);
}

int main(int argc, char** argv) {
  const std::string planner = argc > 1 ? argv[1] : "dwa";
  const int steps = argc > 2 ? std::atoi(argv[2]) : 3000;
  const auto st = site::loadSite(FLEET_SOURCE_DIR "/sim/scenarios/small_warehouse.site.json");
  auto raw = std::make_shared<const planning::OccupancyGrid>(st.map);
  trafficmgr::Settings ts;
  ts.clock = "sim";
  ts.lockstep = true;
  trafficmgr::TrafficNode traffic(st, ts, 1);
  std::vector<std::unique_ptr<agent::Agent>> agents;
  std::vector<Pose2> truth;
  const auto pickups = st.ofKind(site::StationKind::Pickup);
  const auto drops = st.ofKind(site::StationKind::Dropoff);
  for (int i = 0; i < 20; ++i) {
    const auto* park = st.station("PARK-" + std::to_string(i + 1));
    agent::AgentParams p;
    p.id = "r" + std::to_string(i + 1);
    p.start = park->pose;
    p.localPlanner = planner;
    p.lineUpdates = false;
    agents.push_back(std::make_unique<agent::Agent>(p, raw));
    truth.push_back(park->pose);
    msg::TaskAssignment a;
    a.robot_id = p.id;
    a.task_id = "t" + std::to_string(i);
    a.revision = 1;
    const auto* pk = pickups[static_cast<std::size_t>(i) % pickups.size()];
    const auto* dr = drops[static_cast<std::size_t>(i * 7 + 3) % drops.size()];
    a.goals.push_back({pk->pose, pk->name, msg::GoalAction::Load, 2.0});
    a.goals.push_back({dr->pose, dr->name, msg::GoalAction::Unload, 2.0});
    agents.back()->onAssignment(a);
  }
  std::vector<agent::AgentOutput> outs(agents.size());
  int plansDone = 0;
  for (int k = 0; k < steps; ++k) {
    // Risk: a level per cell from the distance to the other robots' true positions (K = 10).
    if (k % 10 == 0) {
      const int w = raw->width(), hh = raw->height();
      std::vector<std::uint8_t> lv(static_cast<std::size_t>(w * hh), 0);
      for (int y = 0; y < hh; ++y) {
        for (int x = 0; x < w; ++x) {
          const Vec2 c = raw->cellCenter({x, y});
          double best = 1e9;
          for (const auto& t : truth) {
            best = std::min(best, distance(c, t.position()));
          }
          lv[static_cast<std::size_t>(y * w + x)] =
              static_cast<std::uint8_t>(std::clamp(10.0 - 4.0 * best, 0.0, 10.0));
        }
      }
      msg::RiskMap m;
      m.origin_x = raw->origin().x;
      m.origin_y = raw->origin().y;
      m.resolution = raw->resolution();
      m.width = static_cast<std::uint32_t>(w);
      m.height = static_cast<std::uint32_t>(hh);
      m.levels = 10;
      m.stamp_ns = k * 100'000'000LL;
      for (const auto& r : risk::encodeRle(lv)) {
        m.runs.push_back({r.level, r.length});
      }
      auto f = risk::riskLookupOf(m);
      for (auto& a : agents) {
        a->onRiskMap(*f);
      }
      (void)traffic.onRiskMap(**f, m.stamp_ns);
    }
    // Operator actions: pause r3 at 50 s and resume at 80 s, cancel r5 at 60 s, a second order for
    // r7 at 200 s.
    auto order = [&](int robot, std::uint32_t rev, bool paused, bool cancel, int variant) {
      msg::TaskAssignment a;
      a.robot_id = "r" + std::to_string(robot);
      a.task_id = cancel ? "" : "t" + std::to_string(robot - 1) + (variant ? "b" : "");
      a.revision = rev;
      a.paused = paused;
      if (!cancel) {
        const auto* pk = pickups[static_cast<std::size_t>(robot - 1 + variant) % pickups.size()];
        const auto* dr = drops[static_cast<std::size_t>((robot - 1) * 7 + 3) % drops.size()];
        a.goals.push_back({pk->pose, pk->name, msg::GoalAction::Load, 2.0});
        a.goals.push_back({dr->pose, dr->name, msg::GoalAction::Unload, 2.0});
      }
      agents[static_cast<std::size_t>(robot - 1)]->onAssignment(a);
    };
    if (k == 500)
      order(3, 2, true, false, 0);
    if (k == 800)
      order(3, 3, false, false, 0);
    if (k == 600)
      order(5, 2, false, true, 0);
    if (k == 2000)
      order(7, 2, false, false, 1);
    for (std::size_t i = 0; i < agents.size(); ++i) {
      // Ideal kinematics: the last command moves the true pose; odometry reports it exactly.
      const double v = outs[i].command.v, wv = outs[i].command.w;
      Pose2& t = truth[i];
      t.x += v * 0.1 * std::cos(t.theta);
      t.y += v * 0.1 * std::sin(t.theta);
      t.theta += wv * 0.1;
      msg::SensorFrame f;
      f.robot_id = agents[i]->id();
      f.stamp_ns = k * 100'000'000LL;
      f.ds_left = v * 0.1 - wv * 0.1 * 0.2;
      f.ds_right = v * 0.1 + wv * 0.1 * 0.2;
      f.range_max = 8.0f;
      agents[i]->onFrame(f);
      for (std::size_t j = 0; j < agents.size(); ++j) {
        if (j != i && k > 0) {
          agents[i]->onOtherRobot(outs[j].state);
        }
      }
    }
    for (std::size_t i = 0; i < agents.size(); ++i) {
      outs[i] = agents[i]->step(k * 100'000'000LL, 0.1);
      const auto& o = outs[i];
      mixd(o.command.v);
      mixd(o.command.w);
      mixd(o.state.pose.x);
      mixd(o.state.pose.y);
      mixd(o.state.pose.theta);
      mix(&o.state.mode, sizeof o.state.mode);
      for (const auto& d : o.discs.discs) {
        mixd(d.x);
        mixd(d.y);
      }
      if (o.traffic) {
        (void)traffic.onProgress(*o.traffic, k * 100'000'000LL);
      }
      if (o.status) {
        ++plansDone;
        mix(o.status->task_id.data(), o.status->task_id.size());
        mix(&o.status->state, sizeof o.status->state);
        mix(o.status->error.data(), o.status->error.size());
      }
    }
    for (const auto& r : traffic.tick(k * 100'000'000LL)) {
      for (auto& a : agents) {
        if (a->id() == r.robot_id) {
          a->onRelease(r);
        }
      }
      for (const auto& n : r.base) {
        mix(&n.node, sizeof n.node);
      }
    }
  }
  std::printf("planner=%s steps=%d statuses=%d hash=%016llx\n", planner.c_str(), steps, plansDone,
              static_cast<unsigned long long>(h));
  for (std::size_t i = 0; i < agents.size(); i += 5) {
    std::printf("  %s at (%.3f, %.3f) busy=%d node=%d rejoins=%llu\n", agents[i]->id().c_str(),
                agents[i]->pose().x, agents[i]->pose().y, agents[i]->busy() ? 1 : 0, agents[i]->trafficNode(),
                static_cast<unsigned long long>(agents[i]->conduct().rejoins));
  }
  return 0;
}
