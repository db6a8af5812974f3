#include "fleet/estimation/line_matching.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include <Eigen/Eigenvalues>

#include "fleet/core/angles.hpp"

namespace fleet::estimation {

MapLine lineOf(const MapSegment& s) {
  const Vec2 n = s.normal / s.normal.norm();
  double rho = n.x * s.a.x + n.y * s.a.y;
  double beta = std::atan2(n.y, n.x);
  if (rho < 0.0) {
    rho = -rho;
    beta += kPi;
  }
  return {rho, wrapAngle(beta)};
}

namespace {

struct Candidate {
  std::size_t segment = 0;
  double d2 = 0.0;
  MapLine line;
};

bool sameLine(const MapLine& p, const MapLine& q, const LineGate& g) {
  return std::abs(p.rho - q.rho) <= g.sameLineRho && std::abs(angleDiff(p.beta, q.beta)) <= g.sameLineBeta;
}

double distanceToSegment(Vec2 p, const MapSegment& s) {
  const Vec2 ab = s.b - s.a;
  const double len2 = ab.dot(ab);
  const double t = len2 > 0.0 ? std::clamp((p - s.a).dot(ab) / len2, 0.0, 1.0) : 0.0;
  return distance(p, s.a + ab * t);
}

/// Further than `range` from p: the bounding-box test first, since it rejects most walls of a site.
bool outOfRange(Vec2 p, const MapSegment& s, double range) {
  if (range <= 0.0) {
    return false;
  }
  if (std::min(s.a.x, s.b.x) - range > p.x || std::max(s.a.x, s.b.x) + range < p.x ||
      std::min(s.a.y, s.b.y) - range > p.y || std::max(s.a.y, s.b.y) + range < p.y) {
    return true;
  }
  return distanceToSegment(p, s) > range;
}

double ellipseExcess(Vec2 e, const MapSegment& s) {
  return distance(e, s.a) + distance(e, s.b) - distance(s.a, s.b);
}

}  // namespace

LineMatchResult matchLines(const Pose2& pose, const Eigen::Matrix3d& P, std::span<const MapSegment> map,
                           std::span<const ExtractedLine> observed, const LineGate& gate) {
  LineMatchResult out;
  // The end-point test is on the estimate, so it must allow for how far off the estimate may be.
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eig(P.topLeftCorner<2, 2>());
  const double sigmaPos = std::sqrt(std::max(0.0, eig.eigenvalues().maxCoeff()));
  const double tolerance = gate.endpointTolerance + 6.0 * sigmaPos;
  std::vector<Candidate> candidates;
  for (std::size_t i = 0; i < observed.size(); ++i) {
    const ExtractedLine& obs = observed[i];
    Eigen::Matrix2d R;
    R << obs.line.varR, obs.line.covRPsi, obs.line.covRPsi, obs.line.varPsi;
    const Vec2 first = pose.transform(obs.first);
    const Vec2 last = pose.transform(obs.last);
    bool facing = false;
    bool gated = false;
    candidates.clear();
    for (std::size_t j = 0; j < map.size(); ++j) {
      const MapSegment& s = map[j];
      const Vec2 n = s.normal / s.normal.norm();
      if (outOfRange(pose.position(), s, gate.maxRange) ||
          (pose.position() - s.a).dot(n) < gate.minDistance) {
        continue;  // behind the face, on it, or out of the scanner's reach
      }
      facing = true;
      const MapLine line = lineOf(s);
      const LinePrediction p = predictLine(pose, line);
      const Eigen::Vector2d innov(obs.line.r - p.r, angleDiff(obs.line.psi, p.psi));
      const Eigen::Matrix2d S = p.H * P * p.H.transpose() + R;
      const double det = S.determinant();
      if (!(det > 0.0)) {
        continue;
      }
      const double d2 = innov.dot(S.inverse() * innov);
      if (!(d2 <= gate.mahalanobis)) {
        continue;
      }
      gated = true;
      if (ellipseExcess(first, s) >= tolerance || ellipseExcess(last, s) >= tolerance) {
        continue;
      }
      candidates.push_back({j, d2, line});
    }
    if (candidates.empty()) {
      ++(!facing ? out.noWallFacing : (!gated ? out.outsideGate : out.noOverlap));
      continue;
    }
    const auto best = std::min_element(candidates.begin(), candidates.end(),
                                       [](const Candidate& x, const Candidate& y) { return x.d2 < y.d2; });
    const bool ambiguous = std::any_of(candidates.begin(), candidates.end(), [&](const Candidate& c) {
      return !sameLine(c.line, best->line, gate);
    });
    if (ambiguous) {
      ++out.ambiguous;
      continue;
    }
    out.matches.push_back({i, best->segment, best->d2, best->line});
  }
  return out;
}

}  // namespace fleet::estimation
