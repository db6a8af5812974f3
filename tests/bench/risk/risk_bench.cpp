// risk_bench: pair models, warehouse-scale fusion (+ levels, regions, RLE), engine vs the thesis grid
// loop in the same run, and growth with sources / horizon / grid size. Figures: docs/benchmarks.md.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <ctime>
#include <memory>
#include <random>
#include <vector>

#include "fleet/risk/fusion_engine.hpp"
#include "fleet/risk/gaussian.hpp"
#include "fleet/risk/overlap_ratio.hpp"
#include "fleet/risk/reference_algorithm.hpp"
#include "fleet/risk/regions.hpp"
#include "fleet/risk/rle.hpp"

namespace {

using namespace fleet::risk;

// ---------------------------------------------------------------- pair models
struct PairSet {
  std::vector<Disc> a, b;
};

PairSet makePairs(double sigmaMax) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> ur(0.3, 0.6), ud(0.0, 1.6), ua(0.0, 6.283), us(0.03, sigmaMax);
  PairSet s;
  for (int i = 0; i < 1024; ++i) {
    const double d = ud(rng), th = ua(rng);
    s.a.push_back({0, 0, ur(rng), us(rng)});
    s.b.push_back({d * std::cos(th), d * std::sin(th), ur(rng), us(rng)});
  }
  return s;
}

void BM_PairOverlapRatio(benchmark::State& state) {
  const auto s = makePairs(0.3);
  const OverlapRatio m;
  std::size_t i = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(m.pair(s.a[i & 1023], s.b[i & 1023]));
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_PairOverlapRatio);

void BM_PairGaussianIsotropic(benchmark::State& state) {
  const auto s = makePairs(0.3);
  std::size_t i = 0;
  for (auto _ : state) {
    const Disc& a = s.a[i & 1023];
    const Disc& b = s.b[i & 1023];
    benchmark::DoNotOptimize(gaussianCollisionProbability(centreDistance(a, b), a.r + b.r,
                                                          std::sqrt(a.sigma * a.sigma + b.sigma * b.sigma)));
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_PairGaussianIsotropic);

// The same pairs by the fast path's table (the risk map service's default).
void BM_PairGaussianIsotropicFast(benchmark::State& state) {
  const auto s = makePairs(0.3);
  warmGaussianTable();
  std::size_t i = 0;
  for (auto _ : state) {
    const Disc& a = s.a[i & 1023];
    const Disc& b = s.b[i & 1023];
    benchmark::DoNotOptimize(gaussianCollisionProbabilityTabulated(
        centreDistance(a, b), a.r + b.r, std::sqrt(a.sigma * a.sigma + b.sigma * b.sigma)));
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_PairGaussianIsotropicFast);

// Relative positions and covariances for the anisotropic model: the isotropic pair set with the summed
// variance as the major eigenvalue, the minor one `minRatio`…1 times that (log-uniform below 0.2,
// uniform 0.2–1 as in the recorded figures), random orientation.
struct AnisoSet {
  std::vector<fleet::Vec2> mean;
  std::vector<Cov2> cov;
  std::vector<double> R;
};

AnisoSet anisotropicPairs(double minRatio) {
  const auto s = makePairs(0.3);
  std::mt19937_64 rng(2);
  std::uniform_real_distribution<double> ue(0.2, 1.0), ua(0.0, 3.1416), ul(std::log(minRatio), 0.0);
  AnisoSet out;
  for (std::size_t i = 0; i < 1024; ++i) {
    const double s2 = s.a[i].sigma * s.a[i].sigma + s.b[i].sigma * s.b[i].sigma;
    const double ratio = minRatio >= 0.2 ? ue(rng) : std::exp(ul(rng));
    const double l1 = s2, l2 = s2 * ratio, th = ua(rng), c = std::cos(th), sn = std::sin(th);
    out.cov.push_back({c * c * l1 + sn * sn * l2, c * sn * (l1 - l2), sn * sn * l1 + c * c * l2});
    out.mean.push_back({s.b[i].x - s.a[i].x, s.b[i].y - s.a[i].y});
    out.R.push_back(s.a[i].r + s.b[i].r);
  }
  return out;
}

void BM_PairGaussianAnisotropic(benchmark::State& state) {
  const auto p = anisotropicPairs(0.2);
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i & 1023;
    benchmark::DoNotOptimize(gaussianCollisionProbability(p.mean[k], p.cov[k], p.R[k]));
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_PairGaussianAnisotropic);

void BM_PairGaussianAnisotropicFast(benchmark::State& state) {
  const auto p = anisotropicPairs(0.2);
  std::size_t i = 0;
  for (auto _ : state) {
    const std::size_t k = i & 1023;
    benchmark::DoNotOptimize(gaussianCollisionProbabilityFast(p.mean[k], p.cov[k], p.R[k]));
    ++i;
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_PairGaussianAnisotropicFast);

// ---------------------------------------------------------------- warehouse scenes
// Robots (80 %) drive along aisles (horizontal every 3 m, vertical every 5 m) at 0.5–1.5 m/s, humans
// (20 %) walk in random directions at 0.5–1.4 m/s; radius 0.3–0.6 m (humans 0.3–0.4 m); sigma grows
// with the prediction step (robots 0.05 + 0.01 k m, humans 0.1 + 0.03 k m). With `anisotropic`, robots'
// discs carry a covariance instead: that sigma along their motion, half of it across (people stay
// isotropic), so the reaches and candidate pairs are those of the isotropic scene.
std::vector<Source> warehouse(int sources, int steps, double w, double h, std::uint64_t seed,
                              bool anisotropic = false) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u01(0.0, 1.0);
  std::vector<Source> out;
  for (int s = 0; s < sources; ++s) {
    Source src;
    src.id = "s";
    src.id += std::to_string(s);
    src.dt = 0.1;
    const bool human = u01(rng) < 0.2;
    src.kind = human ? SourceKind::kHuman : SourceKind::kRobot;
    double x, y, vx, vy, r;
    const double speed = human ? 0.5 + 0.9 * u01(rng) : 0.5 + u01(rng);
    const double sign = u01(rng) < 0.5 ? -1.0 : 1.0;
    if (human) {
      x = w * u01(rng);
      y = h * u01(rng);
      const double th = 6.283185 * u01(rng);
      vx = speed * std::cos(th);
      vy = speed * std::sin(th);
      r = 0.3 + 0.1 * u01(rng);
    } else if (u01(rng) < 0.5) {
      const int aisles = std::max(1, static_cast<int>(h / 3.0));
      y = 1.5 + 3.0 * std::floor(u01(rng) * aisles);
      x = w * u01(rng);
      vx = sign * speed;
      vy = 0;
      r = 0.3 + 0.3 * u01(rng);
    } else {
      const int aisles = std::max(1, static_cast<int>(w / 5.0));
      x = 2.5 + 5.0 * std::floor(u01(rng) * aisles);
      y = h * u01(rng);
      vx = 0;
      vy = sign * speed;
      r = 0.3 + 0.3 * u01(rng);
    }
    for (int k = 0; k < steps; ++k) {
      const double t = 0.1 * k;
      src.discs.push_back({x + vx * t, y + vy * t, r, human ? 0.1 + 0.03 * k : 0.05 + 0.01 * k});
      if (anisotropic && !human) {
        const double along = 0.05 + 0.01 * k, across = 0.5 * along;
        const double a2 = along * along, c2 = across * across;
        src.discs.back().cov = vx != 0.0 ? Cov2{a2, 0.0, c2} : Cov2{c2, 0.0, a2};
      }
    }
    out.push_back(std::move(src));
  }
  return out;
}

FusionConfig warehouseConfig(double w, double h, double res, int steps) {
  FusionConfig c;
  c.grid =
      GridSpec{0.0, 0.0, res, static_cast<int>(std::lround(w / res)), static_cast<int>(std::lround(h / res))};
  c.levels = 10;
  c.dt = 0.1;
  c.steps = steps;
  return c;
}

// 0 the overlap ratio, 1 the Gaussian as the risk map service runs it (fast path), 3 the exact Gaussian;
// 5 and 6 the fast path with the service's `gaussian_floor` raised to 1e-3 and 1e-2 (what a higher
// floor buys: fewer pairs and less painted, at the price of a map that shows no risk below it).
std::shared_ptr<const RiskModel> modelOf(int which) {
  if (which == 0) {
    return std::make_shared<OverlapRatio>();
  }
  const double floor = which == 5 ? 1e-3 : (which == 6 ? 1e-2 : 1e-4);
  return std::make_shared<Gaussian>(floor,
                                    which == 3 ? GaussianEvaluation::kExact : GaussianEvaluation::kFast);
}

FusionEngine loaded(const FusionConfig& cfg, const std::vector<Source>& scene, int model) {
  auto engine = FusionEngine::create(cfg, modelOf(model));
  for (const auto& s : scene) {
    (void)engine->upsert(s);
  }
  return std::move(engine.value());
}

// Full fusion + levels + regions + RLE of the 100 m × 50 m warehouse at 0.1 m, K = 10.
// Args: sources, steps, model (0 overlap ratio, 1 Gaussian as the service runs it, 2 the same with the
// robots' discs anisotropic, 3 the exact Gaussian, 4 the exact Gaussian with anisotropic robots, 5 and
// 6 as 1 with the floor at 1e-3 and 1e-2).
void BM_FuseWarehouse(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int steps = static_cast<int>(state.range(1));
  const int model = static_cast<int>(state.range(2));
  const auto scene = warehouse(n, steps, 100.0, 50.0, 7, model == 2 || model == 4);
  auto engine =
      loaded(warehouseConfig(100.0, 50.0, 0.1, steps), scene, model == 2 ? 1 : (model == 4 ? 3 : model));
  std::size_t regions = 0, runs = 0, painted = 0, pairs = 0, tested = 0;
  RegionExtractor extractor;
  for (auto _ : state) {
    engine.invalidate();
    const auto& r = engine.fuse(0);
    const auto reg = extractor.extract(r.levels);
    const auto rle = encodeRle(r.levels.level);
    regions = reg.size();
    runs = rle.size();
    painted = r.stats.discsPainted;
    pairs = r.stats.pairsPositive;
    tested = r.stats.pairsTested;
    benchmark::DoNotOptimize(reg.data());
  }
  state.counters["pairs_tested"] = static_cast<double>(tested);
  state.counters["regions"] = static_cast<double>(regions);
  state.counters["rle_runs"] = static_cast<double>(runs);
  state.counters["discs_painted"] = static_cast<double>(painted);
  state.counters["pairs_positive"] = static_cast<double>(pairs);
}
BENCHMARK(BM_FuseWarehouse)
    ->ArgNames({"sources", "steps", "gauss"})
    ->Args({1000, 30, 0})
    ->Args({1000, 30, 1})
    ->Args({1000, 30, 2})
    ->Args({1000, 30, 3})
    ->Args({1000, 30, 4})
    ->Args({1000, 30, 5})
    ->Args({1000, 30, 6})
    ->Unit(benchmark::kMillisecond)
    ->Repetitions(9)
    ->ReportAggregatesOnly(true);

// Fusion alone (no regions), for the breakdown.
void BM_FuseOnlyWarehouse(benchmark::State& state) {
  const auto scene = warehouse(1000, 30, 100.0, 50.0, 7);
  auto engine = loaded(warehouseConfig(100.0, 50.0, 0.1, 30), scene, static_cast<int>(state.range(0)));
  for (auto _ : state) {
    engine.invalidate();
    benchmark::DoNotOptimize(engine.fuse(0).sceneIndex);
  }
}
BENCHMARK(BM_FuseOnlyWarehouse)->ArgNames({"gauss"})->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Incremental: 10 of 1000 sources change between fusions on the same time base.
void BM_FuseIncremental10of1000(benchmark::State& state) {
  const auto scene = warehouse(1000, 30, 100.0, 50.0, 7);
  const auto moved = warehouse(1000, 30, 100.0, 50.0, 8);
  auto engine = loaded(warehouseConfig(100.0, 50.0, 0.1, 30), scene, static_cast<int>(state.range(0)));
  engine.fuse(0);
  std::size_t k = 0, tiles = 0;
  for (auto _ : state) {
    for (int c = 0; c < 10; ++c, ++k) {
      Source s = moved[k % 1000];
      s.id = scene[(k * 37) % 1000].id;
      (void)engine.upsert(std::move(s));
    }
    tiles = engine.fuse(0).stats.tilesRecomputed;
  }
  state.counters["tiles_recomputed"] = static_cast<double>(tiles);
}
BENCHMARK(BM_FuseIncremental10of1000)->ArgNames({"gauss"})->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond);

// Thread CPU time in ms: on a shared machine wall time mostly measures the other processes.
double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

// The anisotropic model (eigen-axis trapezoid) against the previous implementation (whitened rays,
// kept as the reference) on the same 1024 pairs in the same run. Arg: 1/minimum eigenvalue ratio
// (5: ratios 0.2–1 as above; 10000: 1e-4–1). Counters: ns per pair (medians of thread CPU time over
// the iterations, each a pass over all pairs), the ratio, and the largest |difference|.
void BM_PairAnisotropicVsReference(benchmark::State& state) {
  const auto p = anisotropicPairs(1.0 / static_cast<double>(state.range(0)));
  std::vector<double> tf, tr;
  double maxDiff = 0.0;
  std::vector<double> fast(1024), ref(1024);
  for (auto _ : state) {
    const double t0 = threadCpuMs();
    for (std::size_t k = 0; k < 1024; ++k) {
      fast[k] = gaussianCollisionProbability(p.mean[k], p.cov[k], p.R[k]);
    }
    benchmark::DoNotOptimize(fast.data());
    const double t1 = threadCpuMs();
    for (std::size_t k = 0; k < 1024; ++k) {
      ref[k] = gaussianCollisionProbabilityWhitened(p.mean[k], p.cov[k], p.R[k]);
    }
    benchmark::DoNotOptimize(ref.data());
    const double t2 = threadCpuMs();
    tf.push_back(t1 - t0);
    tr.push_back(t2 - t1);
    for (std::size_t k = 0; k < 1024; ++k) {
      maxDiff = std::max(maxDiff, std::abs(fast[k] - ref[k]));
    }
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  state.counters["fast_ns"] = median(tf) * 1e6 / 1024.0;
  state.counters["reference_ns"] = median(tr) * 1e6 / 1024.0;
  state.counters["ratio"] = median(tr) / median(tf);
  state.counters["max_abs_diff"] = maxDiff;
}
BENCHMARK(BM_PairAnisotropicVsReference)
    ->ArgNames({"inv_ratio"})
    ->Arg(5)
    ->Arg(10000)
    ->Unit(benchmark::kMillisecond);

// Engine vs the thesis grid loop on 50 sources × 30 steps, 20 m × 20 m at 0.1 m, timed in the same
// run; counters: engine_ms, reference_ms (medians of thread CPU time over the iterations), the ratio.
void BM_EngineVsReference(benchmark::State& state) {
  const int model = static_cast<int>(state.range(0));
  const auto scene = warehouse(50, 30, 20.0, 20.0, 11);
  const auto cfg = warehouseConfig(20.0, 20.0, 0.1, 30);
  auto engine = loaded(cfg, scene, model);
  engine.fuse(0);
  const auto aligned = engine.alignedSources();
  const auto m = modelOf(model);
  std::vector<double> te, tr;
  bool equal = true;
  for (auto _ : state) {
    const double t0 = threadCpuMs();
    engine.invalidate();
    const auto& r = engine.fuse(0);
    const double t1 = threadCpuMs();
    const auto ref = referenceProbabilityGrid(cfg.grid, aligned, *m, cfg.policy);
    const double t2 = threadCpuMs();
    equal = equal && ref.p == r.probability.p;
    te.push_back(t1 - t0);
    tr.push_back(t2 - t1);
  }
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2), v.end());
    return v[v.size() / 2];
  };
  state.counters["engine_ms"] = median(te);
  state.counters["reference_ms"] = median(tr);
  state.counters["ratio"] = median(tr) / median(te);
  state.counters["equal"] = equal ? 1.0 : 0.0;
}
BENCHMARK(BM_EngineVsReference)
    ->ArgNames({"gauss"})
    ->Arg(0)
    ->Arg(1)
    ->Unit(benchmark::kMillisecond)
    ->MinTime(2.0);

// Growth: full fusion (no regions) with sources, horizon and resolution varied one at a time around
// (500 sources, 30 steps, 0.1 m) on the 100 m × 50 m floor. Args: sources, steps, resolution in mm.
void BM_Growth(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int steps = static_cast<int>(state.range(1));
  const double res = static_cast<double>(state.range(2)) / 1000.0;
  const auto scene = warehouse(n, steps, 100.0, 50.0, 7);
  auto engine = loaded(warehouseConfig(100.0, 50.0, res, steps), scene, static_cast<int>(state.range(3)));
  for (auto _ : state) {
    engine.invalidate();
    benchmark::DoNotOptimize(engine.fuse(0).sceneIndex);
  }
}
BENCHMARK(BM_Growth)
    ->ArgNames({"sources", "steps", "res_mm", "gauss"})
    ->ArgsProduct({{250, 500, 1000, 2000}, {30}, {100}, {0, 1}})
    ->ArgsProduct({{500}, {10, 60}, {100}, {0, 1}})
    ->ArgsProduct({{500}, {30}, {200, 50}, {0, 1}})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
