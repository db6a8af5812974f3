#include "fleet/traffic/virtual_fleet.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "fleet/core/admission_governor.hpp"
#include "fleet/core/percentiles.hpp"
#include "fleet/traffic/roadmap_travel.hpp"
#include "fleet/traffic/station_book.hpp"
#include "station_tally.hpp"

namespace fleet::traffic {
namespace {

struct Bot {
  NodeId at = kNoNode;     // last node reached
  NodeId to = kNoNode;     // driving towards (kNoNode: standing)
  NodeId prev = kNoNode;   // the node before `at` (for turning)
  double left = 0.0;       // s to go on the current edge
  double total = 0.0;      // s the current edge takes
  double dwellLeft = 0.0;  // s of dwell left at a station
  double stopLeft = 0.0;   // s of a stop (a person in the aisle) left before the edge goes on
  double turnLeft = 0.0;   // s of the edge's turn left (spent first)
  bool dockEdge = false;   // the edge leads into or out of a station's dock or approach node
  int phase = 0;           // 0: to the pickup, 1: to the drop-off
  NodeId pickup = kNoNode;
  NodeId dropoff = kNoNode;
  double taskStart = 0.0;
  double lastProgress = 0.0;
  bool idle = false;        // no admissible task: sent to a parking place
  double nextTry = 0.0;     // s: when an idle robot asks for a task again (once a second)
  double freeFlow = 0.0;    // s: the task's free-flow driving, from where the robot took it
  double driven = 0.0;      // s driven on the task so far (turns and docking included)
  double drivenAway = 0.0;  // s of it on edges that brought the robot no nearer its goal
};

}  // namespace

VirtualFleetResult runVirtualFleet(Roadmap& roadmap, const VirtualFleetOptions& o) {
  if (!(o.dt > 0.0 && std::isfinite(o.dt)))
    throw std::invalid_argument("virtual fleet: dt must be a finite number > 0");
  if (!(o.queueSeriesEvery >= o.dt && std::isfinite(o.queueSeriesEvery)))
    throw std::invalid_argument(
        "virtual fleet: queueSeriesEvery must be a finite number of at least a tick (dt)");
  if (!(o.turnScale >= 0.0 && std::isfinite(o.turnScale)))
    throw std::invalid_argument("virtual fleet: turnScale must be a finite number >= 0");
  const Graph& g = roadmap.graph;
  std::vector<NodeId> pickups, dropoffs, parking;
  const auto chosen = [&](const std::string& name) {
    return o.stations.empty() || std::find(o.stations.begin(), o.stations.end(), name) != o.stations.end();
  };
  for (const auto& s : roadmap.stations) {
    if (s.dock == kNoNode || (s.kind != site::StationKind::Parking && !chosen(s.name)))
      continue;
    if (s.kind == site::StationKind::Pickup)
      pickups.push_back(s.dock);
    if (s.kind == site::StationKind::Dropoff)
      dropoffs.push_back(s.dock);
    if (s.kind == site::StationKind::Parking)
      parking.push_back(s.dock);
  }
  if (pickups.empty() || dropoffs.empty()) {
    throw std::invalid_argument(
        o.stations.empty()
            ? "virtual fleet: the roadmap needs a pickup and a drop-off station"
            : "virtual fleet: the stations chosen hold no pickup or no drop-off on the roadmap");
  }
  for (const auto& t : o.list) {
    if (std::find(pickups.begin(), pickups.end(), t.pickup) == pickups.end() ||
        std::find(dropoffs.begin(), dropoffs.end(), t.dropoff) == dropoffs.end()) {
      throw std::invalid_argument("virtual fleet: list task " + std::to_string(&t - o.list.data()) + " (" +
                                  std::to_string(t.pickup) + " -> " + std::to_string(t.dropoff) +
                                  ") is not from a pickup's dock to a drop-off's on the roadmap");
    }
  }
  // Starts: parking docks, then lane nodes that conflict with nothing taken so far.
  std::vector<NodeId> starts;
  auto fits = [&](NodeId v) {
    return g.isOpen(v) &&
           std::none_of(starts.begin(), starts.end(), [&](NodeId s) { return g.conflicting(s, v); });
  };
  for (NodeId v : parking) {
    if (starts.size() < o.robots && fits(v))
      starts.push_back(v);
  }
  for (NodeId v = 0; static_cast<std::size_t>(v) < g.size() && starts.size() < o.robots; ++v) {
    if (roadmap.kind(v) == NodeKind::Lane && fits(v))
      starts.push_back(v);
  }
  if (starts.size() < o.robots) {
    throw std::invalid_argument("virtual fleet: " + std::to_string(o.robots) +
                                " robots do not fit on the roadmap (" + std::to_string(starts.size()) +
                                " do)");
  }

  VirtualFleetResult res;
  res.starts = starts;
  res.robotTime.resize(o.robots);
  std::mt19937_64 rng(o.seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  TrafficOptions topt = o.traffic;
  topt.pibt.seed = o.seed;
  // The plan kept in time takes each turn on the spot at its real duration.
  topt.turnTime = [&roadmap](NodeId a, NodeId b, NodeId c) { return roadmap.extraTurn(a, b, c); };
  TrafficControl traffic(g, starts, topt);
  if (o.stationLines)
    traffic.setStations(stationLines(roadmap));
  // The station ledger (station_tally.hpp).
  StationTally tally(roadmap, o.queueSeriesEvery);
  std::vector<Bot> bots(o.robots);
  // Whether another robot in the line of the station docked at `dock` stands on one of the line's
  // nodes (its queue places or its approach) as `r` leaves: only then is the next arrival the
  // station's own cycle, not the next robot's drive from afar.
  auto nextStandsInLine = [&](std::size_t r, NodeId dock) {
    const auto& nodes = tally.lineNodes(dock);
    for (std::size_t q : traffic.line(dock)) {
      if (q != r && bots[q].to == kNoNode && std::find(nodes.begin(), nodes.end(), bots[q].at) != nodes.end())
        return true;
    }
    return false;
  };
  // Admission (docs/algorithms.md, "Admission by slots", "Admission by predicted arrival"). By
  // predicted arrival a task is given when its robot gets a place in its pickup's line for the time
  // it will get there, and then in its drop-off's line for the time it will have loaded and driven
  // on. The book is rebuilt from every robot's position once a tick: free-flow times, so a robot
  // held up is booked later.
  std::vector<NodeId> served = pickups;
  served.insert(served.end(), dropoffs.begin(), dropoffs.end());
  // Not owned: the roadmap outlives the run.
  const RoadmapTravel roads(std::shared_ptr<const Roadmap>(&roadmap, [](const Roadmap*) {}));
  StationBook book(roads, served, o.dwell, o.stationSlots);
  double bookedAt = -1.0;
  // Admission by slots: the robots bound for each station now, its pickup until loaded, its
  // drop-off for the whole task.
  std::vector<std::size_t> uses(g.size(), 0);
  // The lines' places scaled by what the traffic did (admission_governor.hpp), as the fleet manager.
  AdmissionGovernor governor;
  bool heldInLine = false;  // a robot asked for work since the last tick and nothing was admissible
  // A fixed number of slots a station (`stationSlots`) is a cap, as a numeric station_capacity in
  // the fleet manager: not scaled.
  const auto hasSlot = [&](NodeId s) {
    const std::size_t places = book.slots(s);
    return uses[static_cast<std::size_t>(s)] < (o.stationSlots > 0 ? places : governor.slots(places));
  };
  // The parking place nearest to robot r that no robot stands on or is sent to.
  auto freeParking = [&](std::size_t r) {
    NodeId best = kNoNode;
    double bestD = std::numeric_limits<double>::infinity();
    for (NodeId v : parking) {
      bool taken = false;
      for (std::size_t q = 0; q < bots.size() && !taken; ++q)
        taken = q != r && (bots[q].at == v || (bots[q].idle && traffic.goal(q) == v));
      const double d = (g.position(v) - g.position(bots[r].at)).norm();
      if (!taken && d < bestD) {
        best = v;
        bestD = d;
      }
    }
    return best;
  };
  // Seconds until robot b gets to `dock` with nobody in its way: from the node it drives to (the
  // rest of its edge first) or the node it stands on (0 at the dock itself).
  auto arrivalAt = [&](const Bot& b, NodeId dock) {
    return b.to != kNoNode ? b.left + book.travel(b.to, dock) : book.travel(b.at, dock);
  };
  auto rebook = [&](double now) {
    if (bookedAt == now)
      return;
    bookedAt = now;
    book.clear();
    std::vector<std::pair<std::size_t, std::size_t>> loading;  // robot, its booking at its pickup
    for (std::size_t q = 0; q < bots.size(); ++q) {
      const Bot& b = bots[q];
      if (b.idle || b.pickup == kNoNode)
        continue;
      if (b.phase == 0)
        loading.emplace_back(q, book.book(b.pickup, arrivalAt(b, b.pickup)));
      else
        book.book(b.dropoff, arrivalAt(b, b.dropoff));
    }
    for (const auto& [q, k] : loading) {
      const Bot& b = bots[q];
      book.book(b.dropoff, book.leave(b.pickup, k) + book.travel(b.pickup, b.dropoff));
    }
  };
  // A task for robot r: without admission any pickup and drop-off; by slots, any with a free slot;
  // by arrival, the pickups in a random order, the first whose line has a place for r's arrival and
  // some drop-off one after it.
  std::size_t listed = 0;  // o.list's tasks given so far
  auto drawTask = [&](const Bot& b, double now) -> std::pair<NodeId, NodeId> {
    if (!o.list.empty()) {
      if (listed == o.list.size())
        return {kNoNode, kNoNode};
      const auto& t = o.list[listed++];
      return {t.pickup, t.dropoff};
    }
    if (o.admission == Admission::None) {
      const NodeId p = pickups[rng() % pickups.size()];
      return {p, dropoffs[rng() % dropoffs.size()]};
    }
    if (o.admission == Admission::Slots) {
      std::vector<NodeId> ps, ds;
      std::copy_if(pickups.begin(), pickups.end(), std::back_inserter(ps), hasSlot);
      std::copy_if(dropoffs.begin(), dropoffs.end(), std::back_inserter(ds), hasSlot);
      if (ps.empty() || ds.empty()) {
        heldInLine = true;
        return {kNoNode, kNoNode};
      }
      const NodeId p = ps[rng() % ps.size()];
      return {p, ds[rng() % ds.size()]};
    }
    rebook(now);
    std::vector<NodeId> order = pickups;
    std::shuffle(order.begin(), order.end(), rng);
    std::vector<NodeId> ds;
    for (NodeId p : order) {
      const SlotOffer atPickup = book.offer(p, arrivalAt(b, p));
      if (!atPickup.admitted)
        continue;
      ds.clear();
      for (NodeId d : dropoffs) {
        if (book.offer(d, atPickup.leave + book.travel(p, d)).admitted)
          ds.push_back(d);
      }
      if (!ds.empty()) {
        const NodeId d = ds[rng() % ds.size()];
        const std::size_t k = book.book(p, arrivalAt(b, p));
        book.book(d, book.leave(p, k) + book.travel(p, d));
        return {p, d};
      }
    }
    return {kNoNode, kNoNode};
  };
  auto newTask = [&](std::size_t r, double now) {
    Bot& b = bots[r];
    if (b.dropoff != kNoNode)
      --uses[static_cast<std::size_t>(b.dropoff)];  // the task just finished frees its drop-off
    b.pickup = b.dropoff = kNoNode;
    const auto [p, d] = drawTask(b, now);
    if (p == kNoNode) {
      if (!b.idle)  // nothing admissible: wait at a parking place
        traffic.setGoal(r, freeParking(r));
      b.idle = true;
      b.nextTry = now + 1.0;
      return;
    }
    b.idle = false;
    b.pickup = p;
    b.dropoff = d;
    ++uses[static_cast<std::size_t>(p)];
    ++uses[static_cast<std::size_t>(d)];
    res.tasks.push_back({b.pickup, b.dropoff});
    b.phase = 0;
    b.freeFlow = arrivalAt(b, p) + book.travel(p, d);
    b.driven = b.drivenAway = 0.0;
    b.taskStart = now;
    b.lastProgress = now;
    traffic.setGoal(r, b.pickup);
  };
  for (std::size_t r = 0; r < o.robots; ++r) {
    bots[r].at = starts[r];
    newTask(r, 0.0);
  }

  res.robots = o.robots;
  res.duration = o.duration;
  res.minSeparation = std::numeric_limits<double>::infinity();
  res.density = static_cast<double>(o.robots) / static_cast<double>(g.size());
  std::vector<double> updateMs, taskTimes;
  const std::vector<std::string> place = waitPlaces(roadmap);
  struct Longest {
    std::size_t robot = 0;
    NodeId at = kNoNode;
    double from = 0.0;
    NodeId goal = kNoNode;
    std::vector<std::size_t> on;
  } longest;
  std::vector<double> waitedAt(g.size(), 0.0);
  const double contact = roadmap.separation.contact - roadmap.separation.margin;
  std::vector<Vec2> where(o.robots);
  double nextFrame = 0.0;
  double tDrive = 0.0, tDwell = 0.0, tWait = 0.0, tStand = 0.0;

  std::vector<NodeId> standing, queued;
  // What robot r, standing with a task, waits on (wait_cause.hpp), as things stood at the start of
  // the tick: the robots before r in the loop have moved on by the time r is filed, and a robot
  // that has just reported its next node is no longer named.
  std::vector<Release> rel(o.robots);
  std::vector<WaitSnapshot> seenAtStart(o.robots);
  auto snapshot = [&]() {
    for (std::size_t q = 0; q < o.robots; ++q) {
      const Bot& b = bots[q];
      auto& w = seenAtStart[q];
      w.at = b.at;
      w.to = b.to;
      w.dwelling = b.dwellLeft > 0.0;
      w.on = o.robots;
      // Whom it waits on only for a robot that can be filed as waiting this tick: standing with a
      // task, not dwelling (the execution's query walks the robot's pending nodes).
      if (b.to == kNoNode && !b.idle && b.pickup != kNoNode && !w.dwelling) {
        if (const auto on = traffic.waitingOn(q); !on.empty())
          w.on = on.front();
      }
    }
  };
  auto waitCause = [&](std::size_t r) { return classifyWait(waitSeen(g, seenAtStart, r, rel[r])); };
  double ranUntil = o.duration;  // a list's run ends when its last task is done
  // Whole ticks: the k-th starts at k × dt (a sum of dt drifts, and ran a tick over at times).
  const auto ticksToRun = static_cast<std::size_t>(std::ceil(o.duration / o.dt - 1e-9));
  ActivityLedger fleetBefore;  // the fleet's robot time up to the last tick (for the governor)
  for (std::size_t tick = 0; tick < ticksToRun; ++tick) {
    const double now = static_cast<double>(tick) * o.dt;
    const auto t0 = std::chrono::steady_clock::now();
    traffic.setNow(now);
    traffic.update();
    for (std::size_t r = 0; r < o.robots; ++r)
      rel[r] = traffic.release(r);
    snapshot();
    updateMs.push_back(
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count());

    for (std::size_t r = 0; r < o.robots; ++r) {
      Bot& b = bots[r];
      if (b.idle && b.dwellLeft <= 0.0 && now >= b.nextTry) {
        newTask(r, now);
        b.lastProgress = now;  // waiting for work is not waiting on traffic
      }
      if (b.dwellLeft > 0.0) {
        tDwell += o.dt;
        res.robotTime[r].add(RobotActivity::Dwelling, o.dt);
        b.dwellLeft -= o.dt;
        if (b.dwellLeft > 0.0)
          continue;
        traffic.setHeld(r, false);
        tally.left(b.at, nextStandsInLine(r, b.at));
        if (b.phase == 0) {
          b.phase = 1;
          --uses[static_cast<std::size_t>(b.pickup)];  // loaded: its pickup slot is free
          traffic.setGoal(r, b.dropoff);
        } else {
          ++res.tasksDone;
          taskTimes.push_back(now - b.taskStart);
          if (std::isfinite(b.freeFlow)) {
            res.taskDriven += b.driven;
            res.taskFreeFlow += b.freeFlow;
            res.taskDrivenAway += b.drivenAway;
            res.taskShare += 1.0;
          }
          newTask(r, now);
        }
        b.lastProgress = now;
        continue;
      }
      // Take the next released node when standing on the release's previous one: at the start
      // of the tick, or (below) the moment an edge ends within it, so a robot drives its released
      // nodes without a stop at each (time left over from an edge goes on into the next).
      const auto takeNext = [&]() {
        const auto& base = rel[r].base;
        const auto it = std::find(base.begin(), base.end(), b.at);
        if (it == base.end() || it + 1 == base.end()) {
          return false;
        }
        b.to = *(it + 1);
        const Edge* e = g.edge(b.at, b.to);
        double d = e != nullptr ? e->duration : 1.0;
        const double turn = b.prev != kNoNode ? o.turnScale * roadmap.extraTurn(b.prev, b.at, b.to) : 0.0;
        const double stretch = 1.0 + o.jitter * unit(rng);
        d = (d + turn) * stretch;
        b.turnLeft = turn * stretch;
        b.stopLeft = unit(rng) < o.stopChance ? o.stopMax * unit(rng) : 0.0;
        const auto docky = [&](NodeId v) {
          return roadmap.kind(v) == NodeKind::Station || roadmap.kind(v) == NodeKind::Approach ||
                 roadmap.kind(v) == NodeKind::Exit;
        };
        b.dockEdge = docky(b.at) && docky(b.to);
        b.left = b.total = d;
        return true;
      };
      if (b.to == kNoNode && !takeNext() && !b.idle && traffic.goal(r) != kNoNode &&
          b.at == traffic.goal(r)) {
        b.dwellLeft = o.dwell;
        traffic.setHeld(r, true);
        tally.arrived(b.at, now);
      }
      if (b.to != kNoNode)
        tDrive += o.dt;
      else if (traffic.execution().pendingNodes(r) > 0)
        tWait += o.dt;
      else
        tStand += o.dt;
      if (b.idle) {
        res.robotTime[r].add(RobotActivity::NoTask, o.dt);  // standing or driving to a parking place
      } else if (b.to != kNoNode && b.stopLeft > 0.0) {
        res.robotTime[r].add(RobotActivity::HeldByPerson, o.dt);
      } else if (b.to != kNoNode) {
        res.robotTime[r].add(
            b.turnLeft > 0.0 || b.dockEdge ? RobotActivity::TurningDocking : RobotActivity::Driving, o.dt);
      } else {
        res.robotTime[r].add(RobotActivity::WaitingOnRobot, o.dt);
        waitedAt[static_cast<std::size_t>(b.at)] += o.dt;
        res.waitCauses[static_cast<std::size_t>(waitCause(r))] += o.dt;
      }
      // Spend the tick: a stop first (the edge goes on once the person has passed), then the edge,
      // then the next released edges.
      double budget = o.dt;
      while (b.to != kNoNode && budget > 1e-12) {
        if (b.stopLeft > 0.0) {
          const double s = std::min(b.stopLeft, budget);
          b.stopLeft -= s;
          budget -= s;
          continue;
        }
        const double s = std::min(b.left, budget);
        if (!b.idle && b.pickup != kNoNode) {  // driving per task: the time on the edge itself
          const NodeId goal = b.phase == 0 ? b.pickup : b.dropoff;
          b.driven += s;
          if (book.travel(b.to, goal) >= book.travel(b.at, goal))
            b.drivenAway += s;
        }
        b.left -= s;
        b.turnLeft -= s;
        budget -= s;
        if (b.left > 1e-12) {
          break;
        }
        b.prev = b.at;
        b.at = b.to;
        b.to = kNoNode;
        // Off its station's line sideways while still in it (a line is one way: it loses its place).
        if (const NodeId dock = traffic.goal(r); dock != kNoNode && b.at != dock) {
          const auto& nodes = tally.lineNodes(dock);
          const auto on = [&](NodeId v) { return std::find(nodes.begin(), nodes.end(), v) != nodes.end(); };
          if (on(b.prev) && !on(b.at)) {
            const auto line = traffic.line(dock);
            res.lineLeaves += std::find(line.begin(), line.end(), r) != line.end() ? 1 : 0;
          }
        }
        traffic.reached(r, b.at);
        b.lastProgress = now;
        takeNext();
      }
      if (now - b.lastProgress > res.longestWait) {
        res.longestWait = now - b.lastProgress;
        if (longest.robot != r || longest.from != b.lastProgress) {
          longest = {r, b.at, b.lastProgress, traffic.goal(r), {}};
        }
        longest.on = traffic.waitingOn(r);  // whom it waits on as the wait goes on
      }
    }
    // The tick's robot time to the admission governor (the fleet-wide ledger's growth), then its step.
    if (o.admission == Admission::Slots && o.stationSlots == 0) {
      ActivityLedger fleetNow;
      for (const auto& rt : res.robotTime)
        fleetNow.add(rt);
      for (std::size_t a = 0; a < kRobotActivities; ++a) {
        const auto act = static_cast<RobotActivity>(a);
        governor.add(act, fleetNow.seconds(act) - fleetBefore.seconds(act));
      }
      fleetBefore = fleetNow;
      governor.tick(o.dt, heldInLine);
      heldInLine = false;
    }
    // What the traffic layer promises.
    for (std::size_t r = 0; r < o.robots; ++r) {
      const Bot& b = bots[r];
      where[r] = b.to == kNoNode
                     ? g.position(b.at)
                     : g.position(b.at) + (g.position(b.to) - g.position(b.at)) * (1.0 - b.left / b.total);
    }
    bool contactNow = false, holdNow = false;
    for (std::size_t a = 0; a < o.robots; ++a) {
      for (std::size_t c = a + 1; c < o.robots; ++c) {
        const double d = (where[a] - where[c]).norm();
        res.minSeparation = std::min(res.minSeparation, d);
        if (d < contact)
          contactNow = true;
        const NodeId ha[2] = {bots[a].at, bots[a].to};
        const NodeId hc[2] = {bots[c].at, bots[c].to};
        for (NodeId x : ha) {
          for (NodeId y : hc) {
            if (x != kNoNode && y != kNoNode && g.conflicting(x, y))
              holdNow = true;
          }
        }
      }
    }
    res.contacts += contactNow ? 1 : 0;
    res.holdViolations += holdNow ? 1 : 0;
    standing.clear();
    queued.clear();
    for (std::size_t r = 0; r < o.robots; ++r) {
      const Bot& b = bots[r];
      if (b.to == kNoNode)
        standing.push_back(b.at);
      if (b.idle || b.pickup == kNoNode)
        continue;
      const NodeId goal = b.phase == 0 ? b.pickup : b.dropoff;
      if (b.to != kNoNode || b.at != goal)
        queued.push_back(goal);
    }
    tally.tick(now, o.dt, standing, queued);
    if (o.recordEvery > 0.0 && now + 1e-9 >= nextFrame) {
      nextFrame += o.recordEvery;
      FleetFrame f;
      f.time = now;
      f.tasksDone = res.tasksDone;
      for (std::size_t r = 0; r < o.robots; ++r) {
        const Bot& b = bots[r];
        f.robots.push_back({where[r], b.phase == 0 ? b.pickup : b.dropoff, b.phase, b.dwellLeft > 0.0,
                            std::move(rel[r].base), std::move(rel[r].horizon)});
      }
      res.frames.push_back(std::move(f));
    }
    if (!o.list.empty() && res.tasksDone == o.list.size()) {
      ranUntil = now + o.dt;
      break;
    }
  }
  // Driving per task counts the tasks under way at the end too, with the free-flow way they have
  // made (their free flow less what is left of it) and that share of a task: a short run would
  // otherwise count only the tasks that went well. (One left with no way to its goal is left out,
  // driving and all: the roadmap's stations are connected, so it does not happen.)
  for (const Bot& b : bots) {
    if (b.idle || b.pickup == kNoNode)
      continue;
    const double left =
        b.phase == 0 ? arrivalAt(b, b.pickup) + book.travel(b.pickup, b.dropoff) : arrivalAt(b, b.dropoff);
    if (std::isfinite(b.freeFlow) && std::isfinite(left)) {
      res.taskDriven += b.driven;
      res.taskDrivenAway += b.drivenAway;
      res.taskFreeFlow += b.freeFlow - left;
      if (b.freeFlow > 0.0)
        res.taskShare += std::clamp((b.freeFlow - left) / b.freeFlow, 0.0, 1.0);
    }
  }
  for (std::size_t r = 0; r < o.robots; ++r) {
    const Bot& b = bots[r];
    if (ranUntil - b.lastProgress < 60.0)
      continue;
    std::ostringstream os;
    os << "robot " << r << " at node " << b.at << " (" << g.position(b.at).x << ", " << g.position(b.at).y
       << ") for " << (ranUntil - b.lastProgress) << " s, goal " << traffic.goal(r) << ", held "
       << traffic.held(r) << ", planned " << traffic.execution().pendingNodes(r)
       << " nodes ahead, released to " << traffic.execution().releasedEnd(r) << ", waiting on";
    for (auto q : traffic.waitingOn(r))
      os << " " << q << "@" << bots[q].at;
    // Where it could go and who stands in the way: what the planner saw.
    os << "; target " << traffic.target(r) << ", ways out:";
    for (const Edge& e : g.edges(b.at)) {
      if (!g.passable(b.at, e))
        continue;
      os << " " << e.to << " " << toString(roadmap.kind(e.to));
      for (std::size_t q = 0; q < o.robots; ++q) {
        if (q != r && g.conflicting(e.to, bots[q].at))
          os << " [" << q << "]";
      }
    }
    res.stalls.push_back(os.str());
  }
  if (longest.at != kNoNode) {
    std::vector<std::pair<std::size_t, NodeId>> on;
    for (const auto q : longest.on)
      on.emplace_back(q, bots[q].at);
    res.longestWaitAt =
        describeWait(roadmap, place, longest.robot, longest.at, longest.from, longest.goal, on);
  }
  res.duration = ranUntil;
  res.tasksPerHour = static_cast<double>(res.tasksDone) * 3600.0 / ranUntil;
  if (const double total = tDrive + tDwell + tWait + tStand; total > 0.0) {
    res.driving = tDrive / total;
    res.dwelling = tDwell / total;
    res.waitingOnOthers = tWait / total;
    res.standingPlanned = tStand / total;
  }
  double sum = 0.0;
  for (double t : taskTimes)
    sum += t;
  res.meanTaskTime = taskTimes.empty() ? 0.0 : sum / static_cast<double>(taskTimes.size());
  res.plannerSteps = traffic.stats().steps;
  res.replans = traffic.stats().replans;
  res.refusedReports = traffic.stats().refusedReports;
  res.evasions = traffic.stats().evasions;
  res.detours = traffic.plannerStats().detours;
  res.escalations = traffic.plannerStats().escalations;
  res.untangles = traffic.plannerStats().untangles;
  res.passes = traffic.stats().passes;
  res.yields = traffic.timedStats().yields;
  res.refuges = traffic.timedStats().refuges;
  res.refusedMoves = traffic.stats().refusedMoves;
  res.search = traffic.searchStats();
  res.lineScale = governor.scale();
  for (std::size_t r = 0; r < traffic.robots(); ++r)
    res.baseEnds += traffic.baseEnds(r);
  res.stations = tally.ledger();
  std::map<std::string, double> waits;
  for (std::size_t v = 0; v < g.size(); ++v) {
    if (waitedAt[v] > 0.0)
      waits[place[v]] += waitedAt[v];
  }
  for (const auto& [p, sec] : waits)
    res.waits.push_back({p, sec});
  std::stable_sort(res.waits.begin(), res.waits.end(),
                   [](const auto& a, const auto& b) { return a.seconds > b.seconds; });
  const Percentiles up = percentiles(std::move(updateMs));
  res.updateP50Ms = up.p50;
  res.updateP99Ms = up.p99;
  if (o.robots < 2)
    res.minSeparation = 0.0;
  return res;
}

std::string formatResult(const VirtualFleetResult& r) {
  std::ostringstream os;
  os.setf(std::ios::fixed);
  os.precision(1);
  os << r.robots << " robots, " << r.duration << " s: " << r.tasksDone << " tasks (" << r.tasksPerHour
     << "/h, mean " << r.meanTaskTime << " s), min separation ";
  os.precision(2);
  os << r.minSeparation << " m, contacts " << r.contacts << ", hold violations " << r.holdViolations
     << ", longest wait ";
  os.precision(1);
  os << r.longestWait << " s, planner steps " << r.plannerSteps << ", replans " << r.replans << ", evasions "
     << r.evasions << ", detours " << r.detours << ", escalations " << r.escalations << ", untangles "
     << r.untangles << ", passes " << r.passes << ", yields " << r.yields << ", refuges " << r.refuges
     << ", refused moves " << r.refusedMoves << ", line leaves " << r.lineLeaves << ", line scale ";
  os.precision(2);
  os << r.lineScale << ", update p50/p99 ";
  os.precision(3);
  os << r.updateP50Ms << "/" << r.updateP99Ms << " ms, density " << r.density;
  os.precision(0);
  os << "; time: driving " << 100.0 * r.driving << " %, dwelling " << 100.0 * r.dwelling
     << " %, waiting on others " << 100.0 * r.waitingOnOthers << " %, planned to stand "
     << 100.0 * r.standingPlanned << " %";
  return os.str();
}

}  // namespace fleet::traffic
