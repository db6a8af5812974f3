#pragma once

#include <cstdint>
#include <functional>
#include <limits>
#include <span>
#include <vector>

#include "fleet/fleet/robot_registry.hpp"
#include "fleet/fleet/task.hpp"

namespace fleet {

/// Seconds robot `r` needs to drive task `t` (to the pickup and on to the dropoff, or to the
/// target station). +inf (or NaN) means it cannot. The fleet manager plugs the planning
/// library's distance fields in here; tests use straight lines.
using TravelCost = std::function<double(const RobotInfo&, const Task&)>;

/// The fast form: for one task, a function of the robot. Built once per task, so resolving the
/// task's stations (or picking its distance field) happens T times instead of T×R — with a
/// per-pair function over 100 tasks × 1,000 robots, station look-ups cost ten times the solver.
using RobotTravel = std::function<double(const RobotInfo&)>;
using TravelModel = std::function<RobotTravel(const Task&)>;

/// Adapts a per-pair function.
TravelModel perPair(TravelCost f);

inline constexpr double kInfeasible = std::numeric_limits<double>::infinity();

/// How priorities, deadlines and batteries enter the assignment (docs/algorithms.md, "fleet").
struct AllocationPolicy {
  double batteryThreshold = 0.2;   ///< below it a robot takes charge tasks only
  double priorityWeightS = 600.0;  ///< one priority step is worth this many seconds of travel
  double latenessWeight = 10.0;    ///< cost per second of predicted lateness past the deadline
  double deferHorizonS = 60.0;     ///< how much later a task left unassigned now is assumed to start
  /// Seconds of travel one second of waiting is worth: a task waiting longer is served before a
  /// nearer, newer one of its priority once its age outweighs the difference in travel, so no task
  /// starves behind a stream of tasks closer to the robots (docs/algorithms.md, "Allocation").
  double ageWeight = 1.0;
};

/// Whether `r` may take `t` at all: pinned tasks go to their robot only, a robot below the battery
/// threshold takes charge tasks only, a lost or busy robot takes nothing.
bool eligible(const RobotInfo& r, const Task& t, const AllocationPolicy& p);

/// travel + L·late for one pair: what the assignment of `t` to a robot `travelS` away costs,
/// without the per-task skip term (constant per task, so it does not change who gets `t`).
double pairCost(const Task& t, double travelS, const AllocationPolicy& p, std::int64_t nowNs);

/// Rows are tasks, columns robots; +inf marks a pair that must not be assigned.
struct CostMatrix {
  std::size_t rows = 0;
  std::size_t cols = 0;
  std::vector<double> v;

  CostMatrix() = default;
  CostMatrix(std::size_t r, std::size_t c, double fill = 0.0) : rows(r), cols(c), v(r * c, fill) {}
  double& at(std::size_t r, std::size_t c) { return v[r * cols + c]; }
  [[nodiscard]] double at(std::size_t r, std::size_t c) const { return v[r * cols + c]; }
};

/// The matrix both allocators minimise:
///   cost(r, t) = travel(r, t) + L·late(r, t) − skip(t)
///   late(r, t) = max(0, now + travel(r, t) + load + unload − deadline)           (0 without deadline)
///   skip(t)    = W·priority(t) + L·max(0, now + H + minTravel(t) + load + unload − deadline)
///                + A·(now − created(t))
/// skip(t) is what leaving t for later costs; subtracting it makes "serve t now" cheaper the more
/// urgent t is, which only matters when tasks outnumber robots (every robot gets a task, so which
/// tasks to serve is decided by skip), while among robots for one task only travel and lateness
/// count. Ineligible pairs are +inf.
CostMatrix effectiveCosts(std::span<const Task> tasks, std::span<const RobotInfo> robots,
                          const TravelModel& travel, const AllocationPolicy& p, std::int64_t nowNs,
                          CostMatrix* travelOut = nullptr);
inline CostMatrix effectiveCosts(std::span<const Task> tasks, std::span<const RobotInfo> robots,
                                 const TravelCost& travel, const AllocationPolicy& p, std::int64_t nowNs,
                                 CostMatrix* travelOut = nullptr) {
  return effectiveCosts(tasks, robots, perPair(travel), p, nowNs, travelOut);
}

/// Min-cost assignment of a rectangular matrix: as many finite pairs as possible, then the least
/// total cost among those. Returns, for each row, its column or -1. Hungarian method (shortest
/// augmenting paths with potentials), O(k²·K) for k = min(rows, cols), K = max(rows, cols).
std::vector<int> solveHungarian(const CostMatrix& c);

struct Assignment {
  std::size_t task = 0;   ///< index into the tasks given to assign()
  std::size_t robot = 0;  ///< index into the robots given to assign()
  double cost = 0.0;      ///< pairCost: travel + lateness penalty
  double travelS = 0.0;
};

/// assign(open tasks, idle robots, travel cost) → assignments; no task or robot appears twice and
/// every pair is eligible.
class Allocator {
 public:
  virtual ~Allocator() = default;
  [[nodiscard]] virtual std::vector<Assignment> assign(std::span<const Task> tasks,
                                                       std::span<const RobotInfo> robots,
                                                       const TravelModel& travel,
                                                       std::int64_t nowNs) const = 0;
  [[nodiscard]] std::vector<Assignment> assign(std::span<const Task> tasks, std::span<const RobotInfo> robots,
                                               const TravelCost& travel, std::int64_t nowNs) const {
    return assign(tasks, robots, perPair(travel), nowNs);
  }
};

/// Optimal for the effective costs.
class HungarianAllocator final : public Allocator {
 public:
  explicit HungarianAllocator(AllocationPolicy p = {}) : p_(p) {}
  using Allocator::assign;
  [[nodiscard]] std::vector<Assignment> assign(std::span<const Task> tasks, std::span<const RobotInfo> robots,
                                               const TravelModel& travel, std::int64_t nowNs) const override;

 private:
  AllocationPolicy p_;
};

/// For very large batches: tasks in order of priority (highest first), then deadline (earliest
/// first, none last), then age, each takes the free eligible robot of least travel + lateness.
/// O(T·R) cost evaluations, O(R) memory; not optimal.
class GreedyAllocator final : public Allocator {
 public:
  explicit GreedyAllocator(AllocationPolicy p = {}) : p_(p) {}
  using Allocator::assign;
  [[nodiscard]] std::vector<Assignment> assign(std::span<const Task> tasks, std::span<const RobotInfo> robots,
                                               const TravelModel& travel, std::int64_t nowNs) const override;

 private:
  AllocationPolicy p_;
};

}  // namespace fleet
