#include "station_tally.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/core/percentiles.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {

StationTally::StationTally(const Roadmap& roadmap, double seriesEvery)
    : roadmap_(roadmap),
      every_(seriesEvery),
      lineNodes_(roadmap.graph.size()),
      lastArrival_(roadmap.graph.size(), -1.0),
      queuedAtLeave_(roadmap.graph.size(), 0),
      visits_(roadmap.graph.size(), 0),
      cycles_(roadmap.graph.size()),
      dockedS_(roadmap.graph.size(), 0.0),
      queueS_(roadmap.graph.size(), 0.0),
      bucketS_(roadmap.graph.size(), 0.0),
      queueNow_(roadmap.graph.size(), 0),
      queueMax_(roadmap.graph.size(), 0),
      dockedNow_(roadmap.graph.size(), 0),
      series_(roadmap.graph.size()),
      nextClose_(seriesEvery) {
  for (const auto& s : roadmap.stations) {
    if (s.dock == kNoNode)
      continue;
    auto& nodes = lineNodes_[static_cast<std::size_t>(s.dock)];
    nodes = s.queue;
    if (s.approach != kNoNode)
      nodes.push_back(s.approach);
  }
}

void StationTally::left(NodeId dock, bool nextInLine) {
  queuedAtLeave_[static_cast<std::size_t>(dock)] = nextInLine ? 1 : 0;
}

void StationTally::arrived(NodeId dock, double now) {
  const auto d = static_cast<std::size_t>(dock);
  ++visits_[d];
  if (lastArrival_[d] >= 0.0 && queuedAtLeave_[d] != 0)
    cycles_[d].push_back(now - lastArrival_[d]);
  lastArrival_[d] = now;
  queuedAtLeave_[d] = 0;
}

void StationTally::tick(double now, double dt, const std::vector<NodeId>& standing,
                        const std::vector<NodeId>& queued) {
  for (const NodeId v : standing)
    dockedNow_[static_cast<std::size_t>(v)] = 1;
  for (const NodeId v : queued)
    ++queueNow_[static_cast<std::size_t>(v)];
  ran_ += dt;
  bucketRan_ += dt;
  // A mean closes when the tick reaches the next multiple of every_ (within a thousandth of a tick:
  // the ticks' times are k × dt in floating point).
  const bool closes = now + dt >= nextClose_ - 1e-3 * dt;
  for (const auto& st : roadmap_.stations) {
    if (st.dock == kNoNode)
      continue;
    const auto d = static_cast<std::size_t>(st.dock);
    dockedS_[d] += dockedNow_[d] != 0 ? dt : 0.0;
    const double q = dt * static_cast<double>(queueNow_[d]);
    queueS_[d] += q;
    bucketS_[d] += q;
    queueMax_[d] = std::max(queueMax_[d], queueNow_[d]);
    if (closes) {
      series_[d].push_back(bucketS_[d] / bucketRan_);
      bucketS_[d] = 0.0;
    }
    queueNow_[d] = 0;
  }
  if (closes) {
    bucketRan_ = 0.0;
    while (nextClose_ <= now + dt + 1e-3 * dt)
      nextClose_ += every_;
  }
  for (const NodeId v : standing)
    dockedNow_[static_cast<std::size_t>(v)] = 0;
}

std::vector<VirtualFleetResult::StationLedger> StationTally::ledger() const {
  std::vector<VirtualFleetResult::StationLedger> out;
  for (const auto& st : roadmap_.stations) {
    if (st.dock == kNoNode || visits_[static_cast<std::size_t>(st.dock)] == 0)
      continue;
    const auto d = static_cast<std::size_t>(st.dock);
    const auto& c = cycles_[d];
    VirtualFleetResult::StationLedger l;
    l.name = st.name;
    l.visits = visits_[d];
    l.cycles = c.size();
    const Percentiles pc = percentiles(c);
    l.cycleP50 = pc.p50;
    l.cycleP90 = pc.p90;
    l.utilisation = ran_ > 0.0 ? dockedS_[d] / ran_ : 0.0;  // the loop's own time (a tick over, at times)
    l.queueMean = ran_ > 0.0 ? queueS_[d] / ran_ : 0.0;
    l.queueMax = queueMax_[d];
    l.queueSeries = series_[d];
    if (bucketRan_ > 0.0)
      l.queueSeries.push_back(bucketS_[d] / bucketRan_);  // the last bucket, shorter
    l.seriesEvery = every_;
    out.push_back(std::move(l));
  }
  return out;
}

}  // namespace fleet::traffic
