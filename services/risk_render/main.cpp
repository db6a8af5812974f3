// risk_render <output-dir>: computes the thesis cases (seed 000, Tables 3.1 / 3.2, Fig. 3.10) with the
// reference grid loop, checks the fusion engine gives the same grid, and writes for each case and K:
//   <case>_p.png            probability p(M) (def. 3.5), viridis, white where p = 0
//   <case>_K<k>_levels.png  iso-levels (def. 3.6)
//   <case>_K<k>_regions.svg region polygons with holes
//   <case>_complement.png   1 − P (Table 3.2 cases and Fig. 3.10)
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "colormap.hpp"
#include "fleet/risk/fusion_engine.hpp"
#include "fleet/risk/iso_levels.hpp"
#include "fleet/risk/overlap_ratio.hpp"
#include "fleet/risk/reference_algorithm.hpp"
#include "fleet/risk/regions.hpp"
#include "fleet/risk/thesis_cases.hpp"
#include "fleet/service/command_line.hpp"
#include "png_writer.hpp"
#include "svg_writer.hpp"

namespace {

using fleet::risk_render::Image;
using fleet::risk_render::Rgb;

// Nearest-neighbour upscale of a grid to ~600 px, y up.
template <class ColourOf>
Image render(const fleet::risk::GridSpec& spec, ColourOf colourOf) {
  const int scale = std::max(1, 600 / std::max(spec.width, spec.height));
  Image img{spec.width * scale, spec.height * scale, {}};
  img.rgb.resize(static_cast<std::size_t>(img.width) * static_cast<std::size_t>(img.height) * 3);
  for (int y = 0; y < img.height; ++y) {
    const int j = spec.height - 1 - y / scale;
    for (int x = 0; x < img.width; ++x) {
      const Rgb c = colourOf(spec.index(x / scale, j));
      auto* px = img.rgb.data() + (static_cast<std::size_t>(y) * static_cast<std::size_t>(img.width) +
                                   static_cast<std::size_t>(x)) *
                                      3;
      px[0] = c.r;
      px[1] = c.g;
      px[2] = c.b;
    }
  }
  return img;
}

constexpr Rgb kWhite{255, 255, 255};

// The engine on the same discs: one source per track, dt = 1 time unit, thesis-sized radii allowed.
bool engineAgrees(const fleet::risk::ThesisCase& c, const fleet::risk::ProbabilityGrid& ref) {
  fleet::risk::FusionConfig cfg;
  cfg.grid = c.grid;
  cfg.dt = 1.0;
  cfg.steps = static_cast<int>(c.sources[0].steps.size());
  cfg.levels = c.levels[0];
  cfg.policy.humanHuman = true;
  cfg.limits.maxRadius = 1000;
  auto engine = fleet::risk::FusionEngine::create(cfg, std::make_shared<fleet::risk::OverlapRatio>());
  if (!engine) {
    return false;
  }
  for (std::size_t s = 0; s < c.sources.size(); ++s) {
    fleet::risk::Source src{std::string("s").append(std::to_string(s)), c.sources[s].kind, 0, 1.0, {}};
    for (const auto& d : c.sources[s].steps) {
      src.discs.push_back(*d);
    }
    if (!engine->upsert(src)) {
      return false;
    }
  }
  return engine->fuse(0).probability.p == ref.p;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::string(argv[1]) == "--version") {
    std::printf("risk_render %s\n", fleet::service::version());
    return 0;
  }
  if (argc != 2 || argv[1][0] == '-') {
    std::fprintf(stderr, "usage: %s <output-dir>\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir(argv[1]);
  std::filesystem::create_directories(dir);
  const fleet::risk::OverlapRatio model;
  const fleet::risk::PairPolicy all{true};  // the thesis counts every pair of objects
  bool ok = true;
  for (const auto& c : fleet::risk::thesisCases()) {
    const auto prob = fleet::risk::referenceProbabilityGrid(c.grid, c.sources, model, all);
    double pmax = 0.0;
    for (double p : prob.p)
      pmax = std::max(pmax, p);
    const bool agrees = engineAgrees(c, prob);
    ok = ok && agrees;
    std::printf("%-16s max p = %.4f  engine == reference: %s  (%s)\n", c.name.c_str(), pmax,
                agrees ? "yes" : "NO", c.description.c_str());
    ok = ok && fleet::risk_render::writePng(
                   (dir / (c.name + "_p.png")).string(), render(c.grid, [&](std::size_t i) {
                     return prob.p[i] > 0.0 ? fleet::risk_render::viridis(prob.p[i]) : kWhite;
                   }));
    for (int K : c.levels) {
      const auto lv = fleet::risk::classifyLevels(prob, K);
      std::string stem = c.name;
      stem.append("_K").append(std::to_string(K));
      ok = ok && fleet::risk_render::writePng(
                     (dir / (stem + "_levels.png")).string(), render(c.grid, [&](std::size_t i) {
                       return lv.level[i] > 0
                                  ? fleet::risk_render::viridis(static_cast<double>(lv.level[i]) / K)
                                  : kWhite;
                     }));
      const auto regions = fleet::risk::extractRegions(lv);
      ok = ok &&
           fleet::risk_render::writeRegionsSvg((dir / (stem + "_regions.svg")).string(), c.grid, K, regions);
      std::printf("%-16s K=%-2d %zu regions\n", "", K, regions.size());
    }
    if (c.complement) {
      const auto comp = fleet::risk::complementMap(prob);
      ok = ok && fleet::risk_render::writePng(
                     (dir / (c.name + "_complement.png")).string(),
                     render(c.grid, [&](std::size_t i) { return fleet::risk_render::viridis(comp[i]); }));
    }
  }
  return ok ? 0 : 1;
}
