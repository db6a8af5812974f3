// Geometry benchmarks: BVH vs brute force over 10,000 boxes (both measured in the same
// benchmark, ratio reported as a counter), MMS vs the convex cross-check on 10..1000 segments, OBB
// SAT and grid DDA throughput.
#include <benchmark/benchmark.h>

#include <Eigen/Geometry>
#include <chrono>
#include <cmath>
#include <ctime>
#include <random>

#include "fleet/geometry/bvh.hpp"
#include "fleet/geometry/grid_raycast.hpp"
#include "fleet/geometry/obb.hpp"
#include "fleet/geometry/segment_path.hpp"

using namespace fleet;
using namespace fleet::geometry;

namespace {

std::vector<Primitive> boxes(int n, double world, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, world), s(0.2, 2.0);
  std::vector<Primitive> prims;
  for (int i = 0; i < n; ++i) {
    prims.push_back(Primitive::makeBox(Aabb2::fromCenterSize({u(rng), u(rng)}, {s(rng), s(rng)})));
  }
  return prims;
}

using Clock = std::chrono::steady_clock;

// One iteration = the same 256 queries answered by the BVH and by brute force.
void BM_BvhVsBrute_Overlap(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto prims = boxes(n, 1000.0, 1);
  const Bvh2 bvh(prims, 4);
  std::mt19937 rng(2);
  std::uniform_real_distribution<double> u(0, 1000), s(0.5, 5.0);
  std::vector<Aabb2> queries;
  for (int k = 0; k < 256; ++k) {
    queries.push_back(Aabb2::fromCenterSize({u(rng), u(rng)}, {s(rng), s(rng)}));
  }
  double tb = 0, tf = 0;
  std::size_t hits = 0;
  for (auto _ : state) {
    const auto t0 = Clock::now();
    for (const auto& q : queries) {
      hits += bvh.overlapping(q).size();
    }
    const auto t1 = Clock::now();
    for (const auto& q : queries) {
      hits -= bruteOverlapping(prims, q).size();
    }
    const auto t2 = Clock::now();
    tb += std::chrono::duration<double>(t1 - t0).count();
    tf += std::chrono::duration<double>(t2 - t1).count();
  }
  if (hits != 0) {
    state.SkipWithError("BVH and brute force disagree");
  }
  const double q = static_cast<double>(state.iterations()) * 256.0;
  state.counters["bvh_us_per_query"] = 1e6 * tb / q;
  state.counters["brute_us_per_query"] = 1e6 * tf / q;
  state.counters["speedup"] = tf / tb;
}
BENCHMARK(BM_BvhVsBrute_Overlap)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_BvhVsBrute_Nearest(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto prims = boxes(n, 1000.0, 3);
  const Bvh2 bvh(prims, 4);
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(0, 1000);
  std::vector<Vec2> queries;
  for (int k = 0; k < 256; ++k) {
    queries.push_back({u(rng), u(rng)});
  }
  double tb = 0, tf = 0, diff = 0;
  for (auto _ : state) {
    double a = 0, b = 0;
    const auto t0 = Clock::now();
    for (const auto& q : queries) {
      a += bvh.nearest(q).distance;
    }
    const auto t1 = Clock::now();
    for (const auto& q : queries) {
      b += bruteNearest(prims, q).distance;
    }
    const auto t2 = Clock::now();
    tb += std::chrono::duration<double>(t1 - t0).count();
    tf += std::chrono::duration<double>(t2 - t1).count();
    diff += std::abs(a - b);
  }
  if (diff != 0.0) {
    state.SkipWithError("BVH and brute force disagree");
  }
  const double q = static_cast<double>(state.iterations()) * 256.0;
  state.counters["bvh_us_per_query"] = 1e6 * tb / q;
  state.counters["brute_us_per_query"] = 1e6 * tf / q;
  state.counters["speedup"] = tf / tb;
}
BENCHMARK(BM_BvhVsBrute_Nearest)->Arg(1000)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_BvhVsBrute_Raycast(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto prims = boxes(n, 1000.0, 5);
  const Bvh2 bvh(prims, 4);
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> u(0, 1000), a(-3.14159, 3.14159);
  std::vector<std::pair<Vec2, Vec2>> rays;
  for (int k = 0; k < 256; ++k) {
    const double t = a(rng);
    rays.push_back({{u(rng), u(rng)}, {std::cos(t), std::sin(t)}});
  }
  double tb = 0, tf = 0;
  for (auto _ : state) {
    double x = 0;
    const auto t0 = Clock::now();
    for (const auto& [o, d] : rays) {
      const auto r = bvh.raycast(o, d, 30.0);
      x += r ? r->range : 0.0;
    }
    const auto t1 = Clock::now();
    for (const auto& [o, d] : rays) {
      const auto r = bruteRaycast(prims, o, d, 30.0);
      x -= r ? r->range : 0.0;
    }
    const auto t2 = Clock::now();
    tb += std::chrono::duration<double>(t1 - t0).count();
    tf += std::chrono::duration<double>(t2 - t1).count();
    benchmark::DoNotOptimize(x);
  }
  const double q = static_cast<double>(state.iterations()) * 256.0;
  state.counters["bvh_us_per_query"] = 1e6 * tb / q;
  state.counters["brute_us_per_query"] = 1e6 * tf / q;
  state.counters["speedup"] = tf / tb;
}
BENCHMARK(BM_BvhVsBrute_Raycast)->Arg(10000)->Unit(benchmark::kMillisecond);

void BM_BvhBuild(benchmark::State& state) {
  const auto prims = boxes(static_cast<int>(state.range(0)), 1000.0, 7);
  for (auto _ : state) {
    Bvh2 bvh(prims, 4);
    benchmark::DoNotOptimize(bvh.nodeCount());
  }
}
BENCHMARK(BM_BvhBuild)->Arg(10000)->Unit(benchmark::kMillisecond);

std::vector<Segment2> randomSegments(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> off(-3, 3), len(0.2, 3), ang(-3.14, 3.14);
  std::vector<Segment2> segs;
  for (int k = 0; k < n; ++k) {
    const Vec2 a{2.0 * (k + 1) + 0.5 * off(rng), off(rng)};
    const double t = ang(rng), l = len(rng);
    segs.push_back({a, a + Vec2{std::cos(t), std::sin(t)} * l});
  }
  return segs;
}

void BM_SegmentPath_Mms(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto segs = randomSegments(n, 11);
  const Vec2 p{0, 0}, q{2.0 * (n + 1), 0.5};
  SegmentPath r;
  for (auto _ : state) {
    r = shortestPathMms(p, q, segs);
    benchmark::DoNotOptimize(r.length);
  }
  const auto ref = shortestPathConvex(p, q, segs);
  state.counters["mms_iterations"] = r.iterations;
  state.counters["merges"] = r.merges;
  state.counters["rel_diff_vs_convex"] = std::abs(r.length - ref.length) / ref.length;
  state.counters["shorter_than_skeleton_pct"] = 100.0 * (1.0 - r.length / skeletonLength(p, q, segs));
}
BENCHMARK(BM_SegmentPath_Mms)->Arg(10)->Arg(30)->Arg(100)->Arg(300)->Arg(1000)->Unit(benchmark::kMillisecond);

void BM_SegmentPath_Convex(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto segs = randomSegments(n, 11);
  const Vec2 p{0, 0}, q{2.0 * (n + 1), 0.5};
  SegmentPath r;
  for (auto _ : state) {
    r = shortestPathConvex(p, q, segs);
    benchmark::DoNotOptimize(r.length);
  }
  state.counters["newton_steps"] = r.iterations;
}
BENCHMARK(BM_SegmentPath_Convex)
    ->Arg(10)
    ->Arg(30)
    ->Arg(100)
    ->Arg(300)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond);

// MMS and the independent rubber-band solver on the same sequence in one loop, thread CPU time of
// each side: counters mms_ms, rubber_band_ms, their ratio, MMS iterations, rubber-band sweeps and
// joint pair moves, and the relative length difference.
double threadCpuMs() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

void BM_SegmentPath_MmsVsRubberBand(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const auto segs = randomSegments(n, 11);
  const Vec2 p{0, 0}, q{2.0 * (n + 1), 0.5};
  SegmentPath m, r;
  double tm = 0, tr = 0;
  for (auto _ : state) {
    const double c0 = threadCpuMs();
    m = shortestPathMms(p, q, segs);
    const double c1 = threadCpuMs();
    r = shortestPathRubberBand(p, q, segs);
    const double c2 = threadCpuMs();
    tm += c1 - c0;
    tr += c2 - c1;
    benchmark::DoNotOptimize(m.length + r.length);
  }
  const auto it = static_cast<double>(state.iterations());
  state.counters["mms_ms"] = tm / it;
  state.counters["rubber_band_ms"] = tr / it;
  state.counters["mms_over_rb"] = tm / tr;
  state.counters["mms_iterations"] = m.iterations;
  state.counters["rb_sweeps"] = r.iterations;
  state.counters["rb_pair_moves"] = r.merges;
  state.counters["rel_diff"] = std::abs(m.length - r.length) / r.length;
  if (!m.converged || !r.converged) {
    state.SkipWithError("a solver did not converge");
  }
}
BENCHMARK(BM_SegmentPath_MmsVsRubberBand)
    ->Arg(10)
    ->Arg(30)
    ->Arg(100)
    ->Arg(300)
    ->Arg(1000)
    ->Unit(benchmark::kMillisecond);

void BM_ObbSat(benchmark::State& state) {
  std::mt19937 rng(8);
  std::normal_distribution<double> nd(0, 1);
  std::uniform_real_distribution<double> u(-3, 3);
  std::vector<std::pair<Obb3, Obb3>> pairs;
  for (int k = 0; k < 1024; ++k) {
    Eigen::Quaterniond qa(nd(rng), nd(rng), nd(rng), nd(rng)), qb(nd(rng), nd(rng), nd(rng), nd(rng));
    pairs.push_back(
        {Obb3{Eigen::Vector3d::Zero(), qa.normalized().toRotationMatrix(), Eigen::Vector3d(1, 0.5, 0.7)},
         Obb3{Eigen::Vector3d(u(rng), u(rng), u(rng)), qb.normalized().toRotationMatrix(),
              Eigen::Vector3d(0.6, 0.9, 0.4)}});
  }
  int inter = 0;
  for (auto _ : state) {
    for (const auto& [a, b] : pairs) {
      inter += satTest(a, b).intersect ? 1 : 0;
    }
  }
  benchmark::DoNotOptimize(inter);
  state.SetItemsProcessed(state.iterations() * 1024);
}
BENCHMARK(BM_ObbSat);

void BM_GridRaycast(benchmark::State& state) {
  const int w = 340, h = 164;
  std::vector<std::uint8_t> cells(static_cast<std::size_t>(w * h), 0);
  std::mt19937 rng(9);
  std::bernoulli_distribution occ(0.05);
  for (auto& c : cells) {
    c = occ(rng) ? 1 : 0;
  }
  const GridView g{w, h, 0.1, {0, 0}, cells};
  std::uniform_real_distribution<double> ux(0.5, 33.5), uy(0.5, 16), ua(-3.14, 3.14);
  double sum = 0;
  for (auto _ : state) {
    sum += raycastGrid(g, {ux(rng), uy(rng)}, ua(rng), 8.0).range;
  }
  benchmark::DoNotOptimize(sum);
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_GridRaycast);

}  // namespace

BENCHMARK_MAIN();
