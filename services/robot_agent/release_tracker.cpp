#include "release_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace fleet::agent {

double stoppingSpeed(double distance, double accel, double latency) {
  if (!(distance > 0.0) || !(accel > 0.0)) {
    return 0.0;
  }
  const double t = std::max(latency, 0.0);
  return accel * (std::sqrt(t * t + 2.0 * distance / accel) - t);
}

ReleaseVerdict ReleaseTracker::offer(const Release& r, Vec2 here) {
  if (std::any_of(r.base.begin(), r.base.end(), [](const BaseNode& n) { return !n.at.isFinite(); })) {
    ++counts_.malformed;
    return ReleaseVerdict::kMalformed;
  }
  if (have_ && r.epoch == epoch_) {
    if (r.seq <= seq_) {
      ++counts_.stale;
      return ReleaseVerdict::kStale;
    }
    if (!r.base.empty() && r.base.front().id != node_) {
      // Planned from a node the robot has left (or never reached): the next release will start
      // where the robot's latest report put it.
      ++counts_.offNode;
      return ReleaseVerdict::kOffNode;
    }
  } else if (!r.base.empty()) {
    // A new traffic manager (or the first one) knows the robot only from its reports and its pose.
    const bool same = node_ >= 0 && r.base.front().id == node_;
    if (!same && distance(r.base.front().at, here) > p_.placeRadius) {
      ++counts_.offNode;
      return ReleaseVerdict::kOffNode;
    }
  }
  take(r);
  return ReleaseVerdict::kAccepted;
}

void ReleaseTracker::take(const Release& r) {
  // (The next advance() projects the robot on the new base.)
  have_ = true;
  epoch_ = r.epoch;
  seq_ = r.seq;
  ++revision_;
  ++counts_.accepted;
  if (r.base.empty()) {
    hold();
    return;
  }
  base_ = r.base;
  node_ = base_.front().id;
  reached_ = 0;
  arc_.assign(base_.size(), 0.0);
  for (std::size_t i = 1; i < base_.size(); ++i) {
    arc_[i] = arc_[i - 1] + distance(base_[i - 1].at, base_[i].at);
  }
  endsAtGoal_ = r.endsAtGoal;
  progress_ = 0.0;
  beyondEnd_ = 0.0;
}

void ReleaseTracker::hold() {
  endsAtGoal_ = false;
  if (base_.empty()) {
    return;
  }
  base_.resize(reached_ + 1);
  arc_.resize(reached_ + 1);
  progress_ = std::min(progress_, arc_.back());
}

bool ReleaseTracker::advance(Vec2 here) {
  if (!have_ || base_.size() < 2) {
    return false;
  }
  const std::size_t n = base_.size();
  // Not past a node where the base turns back before that node is reached (see turnBack).
  const std::size_t last = firstTurnBack();
  double bestD2 = std::numeric_limits<double>::infinity();
  double bestS = progress_;
  double bestPerp = 0.0;
  double bestBeyond = 0.0;
  for (std::size_t j = 0; j + 1 < n && j < last; ++j) {
    if (arc_[j + 1] < progress_ - 1e-9) {
      continue;  // behind the robot's progress
    }
    if (arc_[j] > progress_ + p_.searchWindow) {
      break;
    }
    const Vec2 a = base_[j].at;
    const Vec2 ab = base_[j + 1].at - a;
    const double len = ab.norm();
    if (len < 1e-9) {
      continue;
    }
    const Vec2 u = ab * (1.0 / len);
    const double along = (here - a).dot(u);
    double t = std::clamp(along, 0.0, len);
    if (arc_[j] + t < progress_) {
      t = progress_ - arc_[j];
    }
    const double d2 = (here - (a + u * t)).squaredNorm();
    if (d2 < bestD2) {
      bestD2 = d2;
      bestS = arc_[j] + t;
      const Vec2 off = here - a;
      bestPerp = std::abs(off.x * u.y - off.y * u.x);
      bestBeyond = j + 2 == n ? std::max(0.0, along - len) : 0.0;  // (j + 1 == last then)
    }
  }
  progress_ = std::max(progress_, bestS);
  const double lateral = std::sqrt(bestD2);
  beyondEnd_ = bestBeyond;
  // The furthest node reached wins: reports may skip nodes, a skipped one was passed.
  for (std::size_t k = last; k > reached_; --k) {
    const bool close = distance(here, base_[k].at) < p_.reachTolerance &&
                       arc_[k] <= progress_ + 2.0 * p_.reachTolerance;  // (not a later visit of the spot)
    const bool passed = k + 1 < n ? progress_ > arc_[k] + 1e-6 && lateral < p_.passLateral
                                  : beyondEnd_ > 0.0 && bestPerp < p_.passLateral;
    if (close || passed) {
      reached_ = k;
      node_ = base_[k].id;
      return true;
    }
  }
  return false;
}

std::optional<Vec2> ReleaseTracker::at() const {
  if (!have_ || base_.empty()) {
    return std::nullopt;
  }
  return base_[reached_].at;
}

std::optional<Vec2> ReleaseTracker::next() const {
  if (!nodesAhead()) {
    return std::nullopt;
  }
  return base_[reached_ + 1].at;
}

std::optional<Vec2> ReleaseTracker::end() const {
  if (base_.empty()) {
    return std::nullopt;
  }
  return base_.back().at;
}

double ReleaseTracker::remaining() const {
  if (base_.size() < 2) {
    return 0.0;
  }
  return arc_.back() - progress_ - beyondEnd_;
}

std::optional<ReleaseTracker::Turn> ReleaseTracker::nextTurn(double angle, double tightAngle,
                                                             const std::function<bool(Vec2)>& tight) const {
  for (std::size_t k = std::max<std::size_t>(reached_, 1); k + 1 < base_.size(); ++k) {
    if (arc_[k] < progress_) {
      continue;  // passed
    }
    const double bend = turnAt(k);
    if (bend > angle || (tight && bend > tightAngle && tight(base_[k].at))) {
      return Turn{arc_[k] - progress_, base_[k].at};
    }
  }
  return std::nullopt;
}

std::vector<Vec2> ReleaseTracker::ahead(Vec2 here) const {
  std::vector<Vec2> pts{here};
  for (std::size_t k = reached_ + 1; k < base_.size(); ++k) {
    // Nodes the projection has already passed are left out (the path would turn back to them);
    // the last one always stays: it is where the robot has to stop.
    if (arc_[k] > progress_ + 0.05 || k + 1 == base_.size()) {
      pts.push_back(base_[k].at);
    }
  }
  return pts;
}

double ReleaseTracker::turnAt(std::size_t k) const {
  const Vec2 in = base_[k].at - base_[k - 1].at;
  const Vec2 out = base_[k + 1].at - base_[k].at;
  if (in.norm() < 1e-9 || out.norm() < 1e-9) {
    return 0.0;
  }
  return std::abs(std::remainder(std::atan2(out.y, out.x) - std::atan2(in.y, in.x), 2.0 * M_PI));
}

std::size_t ReleaseTracker::firstTurnBack() const {
  for (std::size_t k = reached_ + 1; k + 1 < base_.size(); ++k) {
    if (turnAt(k) > p_.turnBack || comesBackTo(k + 1)) {
      return k;
    }
  }
  return base_.empty() ? 0 : base_.size() - 1;
}

bool ReleaseTracker::comesBackTo(std::size_t j) const {
  for (std::size_t i = reached_; i < j; ++i) {
    if (arc_[j] - arc_[i] > 2.0 * p_.comesBack && distance(base_[i].at, base_[j].at) < p_.comesBack) {
      return true;
    }
  }
  return false;
}

ReleaseTracker::Way ReleaseTracker::aheadToTurnBack(Vec2 here) const {
  Way way{ahead(here), std::nullopt};
  if (!nodesAhead()) {
    return way;
  }
  const std::size_t stop = firstTurnBack();
  if (stop + 1 < base_.size()) {
    // ahead() leaves out nodes already passed; the turn-back node is not passed (advance() stops
    // there), so it is in the way: cut after it.
    const Vec2 at = base_[stop].at;
    for (std::size_t i = 1; i < way.points.size(); ++i) {
      if (distance(way.points[i], at) < 1e-9) {
        way.points.resize(i + 1);
        way.turnsBackAt = base_[stop].id;
        break;
      }
    }
  }
  return way;
}

}  // namespace fleet::agent
