#pragma once

#include "fleet/core/vec2.hpp"

namespace fleet::sim {

/// Helbing–Molnár social force, per unit mass (m/s²). A pedestrian relaxes to its desired velocity
/// within tau and is pushed away from others by exponentially decaying, anisotropic repulsion.

/// Per-mass stiffness of the contact term, 1/s². Helbing (2000) uses k = 1.2e5 kg/s² for 80 kg
/// (1500 1/s²), which explicit Euler at dt = 0.1 s cannot integrate (k·dt² must stay below 2); 50 is stable.
inline constexpr double kBodyStiffness = 50.0;

/// (v0·e − v) / τ.
Vec2 drivingForce(Vec2 desiredVelocity, Vec2 velocity, double tau);

/// Push on the agent at `pi` (radius ri, walking along unit `heading`, may be zero) from a body at
/// `pj` (radius rj): A·exp((ri + rj − d)/B)·n, n the unit vector j→i, weighted by
/// λ + (1 − λ)(1 + cos φ)/2 where φ is the angle between the heading and the direction to j, so what is
/// ahead matters more than what is behind. Overlapping bodies add kBodyStiffness·overlap (unweighted).
/// Coincident centres push along +x (a fixed, deterministic choice).
Vec2 bodyRepulsion(double A, double B, double lambda, Vec2 pi, double ri, Vec2 heading, Vec2 pj, double rj);

/// Push from the closest wall point at distance `dist` (from the centre) in unit direction `away`:
/// A·exp((ri − dist)/B)·away.
Vec2 wallRepulsion(double A, double B, double ri, double dist, Vec2 away);

}  // namespace fleet::sim
