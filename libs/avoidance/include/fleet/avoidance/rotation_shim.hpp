#pragma once

#include <memory>

#include "fleet/avoidance/local_planner.hpp"

namespace fleet::avoidance {

struct RotationShimParams {
  double startAngle = 0.785;  ///< |heading error to the path| that makes the robot turn in place [rad]
  double stopAngle = 0.2;     ///< ... until it is below this (hysteresis) [rad]
  double lookahead = 1.0;     ///< the path point the heading error is measured to [m]
  double omega = 1.0;         ///< turning rate, capped by the limits [rad/s]

  [[nodiscard]] Expected<void> validate() const;
};

/// Turns the robot in place towards the path before the wrapped planner drives, as Nav2's Rotation
/// Shim Controller does: sampling planners such as DWA only see arcs reachable within their
/// acceleration window, and at a sharp bend (a 1.5 m aisle off a band) every such arc ends in a
/// wall, so they circle instead of turning. Near the goal the wrapped planner decides alone.
class RotationShim final : public LocalPlanner {
 public:
  explicit RotationShim(std::unique_ptr<LocalPlanner> inner, RotationShimParams params = {})
      : inner_(std::move(inner)), params_(params) {}
  Command plan(const LocalView& view) override;
  [[nodiscard]] std::string_view name() const override { return inner_->name(); }
  void reset() override {
    rotating_ = false;
    inner_->reset();
  }
  [[nodiscard]] bool rotating() const { return rotating_; }

 private:
  std::unique_ptr<LocalPlanner> inner_;
  RotationShimParams params_;
  bool rotating_ = false;
};

}  // namespace fleet::avoidance
