#pragma once

#include <cmath>

namespace fleet {

/// Plain 2D vector. Libraries that do linear algebra use Eigen; this is for poses and messages.
struct Vec2 {
  double x = 0.0;
  double y = 0.0;

  constexpr Vec2 operator+(Vec2 o) const { return {x + o.x, y + o.y}; }
  constexpr Vec2 operator-(Vec2 o) const { return {x - o.x, y - o.y}; }
  constexpr Vec2 operator-() const { return {-x, -y}; }
  constexpr Vec2 operator*(double s) const { return {x * s, y * s}; }
  constexpr Vec2 operator/(double s) const { return {x / s, y / s}; }
  constexpr Vec2& operator+=(Vec2 o) {
    x += o.x;
    y += o.y;
    return *this;
  }
  constexpr Vec2& operator-=(Vec2 o) {
    x -= o.x;
    y -= o.y;
    return *this;
  }
  constexpr Vec2& operator*=(double s) {
    x *= s;
    y *= s;
    return *this;
  }
  constexpr bool operator==(const Vec2&) const = default;

  [[nodiscard]] constexpr double dot(Vec2 o) const { return x * o.x + y * o.y; }
  /// z component of the 3D cross product.
  [[nodiscard]] constexpr double cross(Vec2 o) const { return x * o.y - y * o.x; }
  [[nodiscard]] constexpr double squaredNorm() const { return x * x + y * y; }
  [[nodiscard]] double norm() const { return std::hypot(x, y); }
  [[nodiscard]] Vec2 normalized() const {
    const double n = norm();
    return n > 0.0 ? Vec2{x / n, y / n} : Vec2{};
  }
  [[nodiscard]] constexpr Vec2 perp() const { return {-y, x}; }
  [[nodiscard]] bool isFinite() const { return std::isfinite(x) && std::isfinite(y); }
};

constexpr Vec2 operator*(double s, Vec2 v) {
  return v * s;
}

inline double distance(Vec2 a, Vec2 b) {
  return (a - b).norm();
}

}  // namespace fleet
