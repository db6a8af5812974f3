#include "fleet/planning/distance_field_cache.hpp"

#include <cmath>
#include <exception>
#include <limits>
#include <utility>

namespace fleet::planning {

DistanceFieldCache::DistanceFieldCache(std::shared_ptr<const OccupancyGrid> grid, Connectivity conn,
                                       std::size_t capacity)
    : grid_(std::move(grid)), conn_(conn), capacity_(capacity == 0 ? 1 : capacity) {}

std::shared_ptr<const DistanceField> DistanceFieldCache::field(Cell goal) {
  if (!grid_->inside(goal)) {
    auto f = std::make_shared<DistanceField>();
    f->width = grid_->width();
    f->height = grid_->height();
    f->goal = goal;
    f->conn = conn_;
    f->cost.assign(grid_->size(), std::numeric_limits<double>::infinity());
    return f;
  }
  const std::size_t key = grid_->index(goal);
  std::promise<FieldPtr> promise;
  std::shared_future<FieldPtr> future;
  bool mustCompute = false;
  {
    std::unique_lock lock(mu_);
    const auto it = entries_.find(key);
    if (it != entries_.end()) {
      lru_.splice(lru_.begin(), lru_, it->second.lru);
      future = it->second.future;
    } else {
      future = promise.get_future().share();
      lru_.push_front(key);
      entries_.emplace(key, Entry{future, lru_.begin()});
      ++computations_;
      mustCompute = true;
      while (entries_.size() > capacity_) {
        entries_.erase(lru_.back());  // holders of an evicted field keep their shared_ptr
        lru_.pop_back();
      }
    }
  }
  if (mustCompute) {
    // Computed outside the lock: other goals are served meanwhile, and requests for this goal wait
    // on the future instead of computing it again.
    try {
      promise.set_value(std::make_shared<const DistanceField>(computeDistanceField(*grid_, goal, conn_)));
    } catch (...) {
      // Waiters must not block forever; drop the entry so a later request retries.
      promise.set_exception(std::current_exception());
      std::lock_guard lock(mu_);
      const auto it = entries_.find(key);
      if (it != entries_.end()) {
        lru_.erase(it->second.lru);
        entries_.erase(it);
      }
    }
  }
  return future.get();
}

double DistanceFieldCache::travelCost(Cell from, Cell goal) {
  return field(goal)->at(from);
}

double DistanceFieldCache::travelDistance(Vec2 from, Vec2 to) {
  const auto a = grid_->cellAt(from);
  const auto b = grid_->cellAt(to);
  if (!a || !b) {
    return std::numeric_limits<double>::infinity();
  }
  return travelCost(*a, *b) * grid_->resolution();
}

std::size_t DistanceFieldCache::computations() const {
  std::lock_guard lock(mu_);
  return computations_;
}

}  // namespace fleet::planning
