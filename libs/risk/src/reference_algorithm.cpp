#include "fleet/risk/reference_algorithm.hpp"

#include <algorithm>
#include <numbers>

#include "fleet/risk/overlap_ratio.hpp"

namespace fleet::risk {

namespace {
std::size_t stepCount(std::span<const AlignedSource> sources) {
  std::size_t steps = 0;
  for (const auto& s : sources) {
    steps = std::max(steps, s.steps.size());
  }
  return steps;
}

const Disc* discAt(const AlignedSource& s, std::size_t k) {
  return (k < s.steps.size() && s.steps[k].has_value()) ? &*s.steps[k] : nullptr;
}
}  // namespace

ProbabilityGrid referenceProbabilityGrid(const GridSpec& spec, std::span<const AlignedSource> sources,
                                         const RiskModel& model, const PairPolicy& policy) {
  ProbabilityGrid out{spec, std::vector<double>(spec.cellCount(), 0.0)};
  const std::size_t steps = stepCount(sources);
  for (std::size_t k = 0; k < steps; ++k) {
    for (std::size_t a = 0; a < sources.size(); ++a) {
      for (std::size_t b = a + 1; b < sources.size(); ++b) {
        const Disc* da = discAt(sources[a], k);
        const Disc* db = discAt(sources[b], k);
        if (da == nullptr || db == nullptr || !pairAllowed(sources[a].kind, sources[b].kind, policy)) {
          continue;
        }
        const double p = model.pair(*da, *db);
        if (!(p > 0.0)) {
          continue;
        }
        for (int j = 0; j < spec.height; ++j) {
          const double cy = spec.cellCentreY(j);
          for (int i = 0; i < spec.width; ++i) {
            const double cx = spec.cellCentreX(i);
            if (cellInsideDisc(cx, cy, *da) || cellInsideDisc(cx, cy, *db)) {
              double& cell = out.p[spec.index(i, j)];
              cell = std::max(cell, p);
            }
          }
        }
      }
    }
  }
  return out;
}

std::vector<double> referenceSceneIndex(std::span<const AlignedSource> sources, const PairPolicy& policy) {
  const std::size_t steps = stepCount(sources);
  std::vector<double> out(steps, 0.0);
  for (std::size_t k = 0; k < steps; ++k) {
    double num = 0.0;
    double den = 0.0;
    for (std::size_t a = 0; a < sources.size(); ++a) {
      for (std::size_t b = 0; b < sources.size(); ++b) {
        const Disc* da = discAt(sources[a], k);
        const Disc* db = discAt(sources[b], k);
        if (a == b || da == nullptr || db == nullptr ||
            !pairAllowed(sources[a].kind, sources[b].kind, policy)) {
          continue;
        }
        const double inter = discIntersectionArea(da->r, db->r, centreDistance(*da, *db));
        num += inter;
        den += std::numbers::pi * (da->r * da->r + db->r * db->r) - inter;
      }
    }
    out[k] = den > 0.0 ? num / den : 0.0;
  }
  return out;
}

std::vector<double> referenceProbabilityGrid3(const GridSpec3& spec,
                                              std::span<const std::vector<Sphere>> tracks) {
  std::vector<double> out(spec.cellCount(), 0.0);
  std::size_t steps = 0;
  for (const auto& t : tracks) {
    steps = std::max(steps, t.size());
  }
  auto inside = [](double x, double y, double z, const Sphere& s) {
    const double dx = x - s.x;
    const double dy = y - s.y;
    const double dz = z - s.z;
    return dx * dx + dy * dy + dz * dz <= s.r * s.r;
  };
  for (std::size_t k = 0; k < steps; ++k) {
    for (std::size_t a = 0; a < tracks.size(); ++a) {
      for (std::size_t b = a + 1; b < tracks.size(); ++b) {
        if (k >= tracks[a].size() || k >= tracks[b].size()) {
          continue;
        }
        const Sphere& sa = tracks[a][k];
        const Sphere& sb = tracks[b][k];
        const double p = sphereOverlapRatio(sa.r, sb.r, centreDistance(sa, sb));
        if (!(p > 0.0)) {
          continue;
        }
        for (int kz = 0; kz < spec.nz; ++kz) {
          const double z = spec.originZ + kz * spec.resolution;
          for (int j = 0; j < spec.ny; ++j) {
            const double y = spec.originY + j * spec.resolution;
            for (int i = 0; i < spec.nx; ++i) {
              const double x = spec.originX + i * spec.resolution;
              if (inside(x, y, z, sa) || inside(x, y, z, sb)) {
                double& cell = out[spec.index(i, j, kz)];
                cell = std::max(cell, p);
              }
            }
          }
        }
      }
    }
  }
  return out;
}

}  // namespace fleet::risk
