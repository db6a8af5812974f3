#pragma once

// How a robot takes a bend of its route, shared by the agent that drives it
// (services/robot_agent/release_follower.cpp) and the traffic layer that times it
// (libs/traffic Roadmap::bendTime): the plan's turn times are the agent's own.

namespace fleet::bends {

/// Bends up to this angle [rad] (the roadmap lattice's 45° between an axis and a diagonal) the robot
/// drives round without stopping; sharper ones are corners: it drives onto the node and turns there
/// on the spot.
inline constexpr double kDrivenRound = 0.9;
/// Where the disc keeps less than kTightClearance [m] of free space beyond its radius, bends of more
/// than kTight [rad] are corners too: rounded, the outside of the bend swings towards the shelf.
inline constexpr double kTight = 0.3;
inline constexpr double kTightClearance = 0.2;

}  // namespace fleet::bends
