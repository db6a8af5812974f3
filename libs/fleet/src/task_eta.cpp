#include "fleet/fleet/task_eta.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace fleet {
namespace {

constexpr double kNsPerS = 1e9;

bool usable(double s) {
  return std::isfinite(s) && s >= 0.0;
}

std::int64_t after(std::int64_t nowNs, double seconds) {
  return nowNs + static_cast<std::int64_t>(std::llround(seconds * kNsPerS));
}

}  // namespace

std::int64_t TaskEta::assigned(const std::string& taskId, std::int64_t nowNs, double predictedS) {
  if (!usable(predictedS)) {
    running_.erase(taskId);
    return 0;
  }
  running_[taskId] = {nowNs, predictedS};
  predictions_.push_back(predictedS);
  while (predictions_.size() > options_.window) {
    predictions_.pop_front();
  }
  return after(nowNs, pace() * predictedS);
}

std::int64_t TaskEta::active(const std::string& taskId, std::int64_t nowNs) const {
  const auto it = running_.find(taskId);
  if (it == running_.end()) {
    return 0;
  }
  return std::max(nowNs, after(it->second.startNs, pace() * it->second.predictedS));
}

void TaskEta::ended(const std::string& taskId, std::int64_t nowNs, bool done) {
  const auto it = running_.find(taskId);
  if (done) {
    completions_.push_back(nowNs);
    while (completions_.size() > options_.window + 1) {
      completions_.pop_front();
    }
    if (it != running_.end() && nowNs > it->second.startNs && it->second.predictedS > 0.0) {
      const double took = static_cast<double>(nowNs - it->second.startNs) / kNsPerS;
      paces_.push_back(std::clamp(took / it->second.predictedS, options_.minPace, options_.maxPace));
      while (paces_.size() > options_.window) {
        paces_.pop_front();
      }
    }
  }
  if (it != running_.end()) {
    running_.erase(it);
  }
}

double TaskEta::pace() const {
  if (paces_.empty()) {
    return 1.0;
  }
  return std::accumulate(paces_.begin(), paces_.end(), 0.0) / static_cast<double>(paces_.size());
}

double TaskEta::typical() const {
  if (predictions_.empty()) {
    return 0.0;
  }
  return std::accumulate(predictions_.begin(), predictions_.end(), 0.0) /
         static_cast<double>(predictions_.size());
}

double TaskEta::rate() const {
  if (completions_.size() < 2 || completions_.back() <= completions_.front()) {
    return 0.0;
  }
  return static_cast<double>(completions_.size() - 1) /
         (static_cast<double>(completions_.back() - completions_.front()) / kNsPerS);
}

std::int64_t TaskEta::waiting(std::int64_t nowNs, std::size_t ahead, std::size_t robots,
                              double predictedS) const {
  if (!usable(predictedS) || robots == 0) {
    return 0;
  }
  const double own = pace() * predictedS;
  // Assigned at once when a robot is free for it; otherwise once `ahead` more tasks than there are
  // free robots have left the queue and one more robot has finished.
  double r = rate();
  if (r <= 0.0 && own > 0.0) {
    r = static_cast<double>(robots) / own;
  }
  const std::size_t idle = robots > running_.size() ? robots - running_.size() : 0;
  const double wait = ahead < idle || r <= 0.0 ? 0.0 : static_cast<double>(ahead - idle + 1) / r;
  return after(nowNs, wait + own);
}

}  // namespace fleet
