#include "fleet/risk/fusion_engine.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "fleet/risk/overlap_ratio.hpp"

namespace fleet::risk {

Expected<void> validateFusionConfig(const FusionConfig& c) {
  const GridSpec& g = c.grid;
  if (!(g.resolution > 0.0) || !std::isfinite(g.resolution) || !std::isfinite(g.originX) ||
      !std::isfinite(g.originY) || g.width <= 0 || g.height <= 0 ||
      static_cast<double>(g.width) * static_cast<double>(g.height) > 1e9) {
    return unexpected("bad_grid", "grid needs a positive finite resolution and 1..1e9 cells");
  }
  if (c.levels < 1 || c.levels > kMaxLevels) {
    return unexpected("bad_levels", "levels K must be in 1.." + std::to_string(kMaxLevels));
  }
  if (!(c.dt > 0.0) || !std::isfinite(c.dt) || c.steps < 1 || c.steps > 10000) {
    return unexpected("bad_time_base", "fusion needs dt > 0 and 1..10000 steps");
  }
  if (c.tileSize < 1 || c.tileSize > 4096 || (c.tileSize & (c.tileSize - 1)) != 0) {
    return unexpected("bad_tile", "tile size must be a power of two in 1..4096 cells");
  }
  return {};
}

Expected<FusionEngine> FusionEngine::create(FusionConfig config, std::shared_ptr<const RiskModel> model) {
  if (auto ok = validateFusionConfig(config); !ok) {
    return unexpected(ok.error());
  }
  if (!model) {
    return unexpected("no_model", "fusion engine needs a risk model");
  }
  return FusionEngine(std::move(config), std::move(model));
}

FusionEngine::FusionEngine(FusionConfig config, std::shared_ptr<const RiskModel> model)
    : config_(std::move(config)), model_(std::move(model)) {
  const GridSpec& g = config_.grid;
  while ((1 << tileShift_) < config_.tileSize) {
    ++tileShift_;  // tile index = cell index >> tileShift_ (integer division is slow on the paint path)
  }
  tilesX_ = (g.width + config_.tileSize - 1) / config_.tileSize;
  tilesY_ = (g.height + config_.tileSize - 1) / config_.tileSize;
  dirtyTiles_.assign(static_cast<std::size_t>(tilesX_) * static_cast<std::size_t>(tilesY_), 0);
  cellX_.resize(static_cast<std::size_t>(g.width));
  for (int i = 0; i < g.width; ++i) {
    cellX_[static_cast<std::size_t>(i)] = g.cellCentreX(i);  // the same doubles, looked up on the paint path
  }
  result_.probability = ProbabilityGrid{g, std::vector<double>(g.cellCount(), 0.0)};
  result_.levels = LevelGrid{g, config_.levels, std::vector<std::uint8_t>(g.cellCount(), 0)};
  result_.time = TimeBase{0, config_.dt, config_.steps};
}

bool FusionEngine::contains(std::string_view id) const {
  return sources_.find(std::string(id)) != sources_.end();
}

void FusionEngine::noteChanged(const AlignedSource& aligned) {
  for (const auto& d : aligned.steps) {
    if (d.has_value()) {
      pendingDirty_.push_back(*d);
    }
  }
}

Expected<void> FusionEngine::upsert(Source source, std::optional<std::int64_t> nowNs) {
  if (auto ok = validateSource(source, config_.limits, nowNs); !ok) {
    return ok;
  }
  auto it = sources_.find(source.id);
  if (it == sources_.end()) {
    it = sources_.emplace(source.id, Entry{}).first;
  } else if (it->second.hasAligned && haveResult_) {
    noteChanged(it->second.aligned);
  }
  Entry& e = it->second;
  e.source = std::move(source);
  if (haveResult_) {
    e.aligned = alignSource(e.source, result_.time);
    e.alignedFor = result_.time;
    e.hasAligned = true;
    noteChanged(e.aligned);
  } else {
    e.hasAligned = false;
  }
  return {};
}

bool FusionEngine::remove(std::string_view id) {
  auto it = sources_.find(std::string(id));
  if (it == sources_.end()) {
    return false;
  }
  if (it->second.hasAligned && haveResult_) {
    noteChanged(it->second.aligned);
  }
  sources_.erase(it);
  return true;
}

std::size_t FusionEngine::removeOlderThan(std::int64_t cutoff_ns) {
  std::vector<std::string> stale;
  for (const auto& [id, e] : sources_) {
    if (e.source.t0_ns < cutoff_ns) {
      stale.push_back(id);
    }
  }
  for (const auto& id : stale) {
    remove(id);
  }
  return stale.size();
}

std::vector<AlignedSource> FusionEngine::alignedSources() const {
  std::vector<const Entry*> entries;
  for (const auto& [id, e] : sources_) {
    entries.push_back(&e);
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry* a, const Entry* b) { return a->source.id < b->source.id; });
  std::vector<AlignedSource> out;
  for (const Entry* e : entries) {
    out.push_back(e->hasAligned && e->alignedFor == result_.time ? e->aligned
                                                                 : alignSource(e->source, result_.time));
  }
  return out;
}

void FusionEngine::markDirtyTiles(double maxReach) {
  const GridSpec& g = config_.grid;
  const double tileM = g.resolution * config_.tileSize;
  for (const Disc& d : pendingDirty_) {
    // A changed disc a influences its own cells and those of every partner b within
    // reach(a) + reach(b), whose disc extends r_b <= reach(b) further.
    const double m = model_->reach(d) + 2.0 * maxReach + g.resolution;
    const int tx0 = std::max(0, static_cast<int>(std::floor((d.x - m - g.originX) / tileM)));
    const int tx1 = std::min(tilesX_ - 1, static_cast<int>(std::floor((d.x + m - g.originX) / tileM)));
    const int ty0 = std::max(0, static_cast<int>(std::floor((d.y - m - g.originY) / tileM)));
    const int ty1 = std::min(tilesY_ - 1, static_cast<int>(std::floor((d.y + m - g.originY) / tileM)));
    for (int ty = ty0; ty <= ty1; ++ty) {
      for (int tx = tx0; tx <= tx1; ++tx) {
        dirtyTiles_[static_cast<std::size_t>(ty) * static_cast<std::size_t>(tilesX_) +
                    static_cast<std::size_t>(tx)] = 1;
      }
    }
  }
  pendingDirty_.clear();
}

const FusionResult& FusionEngine::fuse(std::int64_t tRefNs) {
  const TimeBase base{tRefNs, config_.dt, config_.steps};
  const bool full = !haveResult_ || !(base == result_.time);
  result_.time = base;
  for (auto& [id, e] : sources_) {
    if (!e.hasAligned || !(e.alignedFor == base)) {
      e.aligned = alignSource(e.source, base);
      e.alignedFor = base;
      e.hasAligned = true;
    }
  }
  recompute(full);
  haveResult_ = true;
  return result_;
}

void FusionEngine::buildHash(const std::vector<StepDisc>& discs) {
  // Uniform buckets over the bounding box of the centres, filled by counting sort. Their side is twice
  // the 90th percentile of the reaches rather than of the largest: a few very uncertain discs (people
  // late in the horizon) would otherwise make every bucket hold dozens of discs. Partners of two discs
  // with reach <= side/2 lie in the same or a neighbouring bucket; the few larger ("wide") discs search
  // as many buckets as their own reach plus the largest needs.
  double minX = discs[0].disc.x, maxX = minX, minY = discs[0].disc.y, maxY = minY, maxR = 0.0;
  reachScratch_.clear();
  for (const auto& s : discs) {
    minX = std::min(minX, s.disc.x);
    maxX = std::max(maxX, s.disc.x);
    minY = std::min(minY, s.disc.y);
    maxY = std::max(maxY, s.disc.y);
    maxR = std::max(maxR, s.reach);
    reachScratch_.push_back(s.reach);
  }
  const auto q = static_cast<std::ptrdiff_t>(reachScratch_.size() * 9 / 10);
  std::nth_element(reachScratch_.begin(), reachScratch_.begin() + q, reachScratch_.end());
  double size = std::max(2.0 * reachScratch_[static_cast<std::size_t>(q)], 1e-6);
  const double cap = 4.0 * static_cast<double>(discs.size()) + 64.0;
  double nx = std::floor((maxX - minX) / size) + 1.0;
  double ny = std::floor((maxY - minY) / size) + 1.0;
  if (nx * ny > cap) {
    size *= std::sqrt(nx * ny / cap) * 1.01;
    nx = std::floor((maxX - minX) / size) + 1.0;
    ny = std::floor((maxY - minY) / size) + 1.0;
  }
  bucketMinX_ = minX;
  bucketMinY_ = minY;
  bucketSize_ = size;
  bucketsX_ = static_cast<int>(nx);
  bucketsY_ = static_cast<int>(ny);
  maxReachInHash_ = maxR;
  const std::size_t nb = static_cast<std::size_t>(bucketsX_) * static_cast<std::size_t>(bucketsY_);
  bucketStart_.assign(nb + 1, 0);
  bucketOf_.resize(discs.size());
  wide_.clear();
  for (std::size_t i = 0; i < discs.size(); ++i) {
    const int bx = std::min(bucketsX_ - 1, static_cast<int>((discs[i].disc.x - minX) / size));
    const int by = std::min(bucketsY_ - 1, static_cast<int>((discs[i].disc.y - minY) / size));
    bucketOf_[i] = static_cast<std::uint32_t>(by * bucketsX_ + bx);
    ++bucketStart_[bucketOf_[i] + 1];
    if (discs[i].reach > 0.5 * size) {
      wide_.push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::size_t b = 0; b < nb; ++b) {
    bucketStart_[b + 1] += bucketStart_[b];
  }
  order_.resize(discs.size());
  sorted_.resize(discs.size());
  auto& fill = bucketFill_;
  fill.assign(bucketStart_.begin(), bucketStart_.end() - 1);
  for (std::size_t i = 0; i < discs.size(); ++i) {
    const std::uint32_t slot = fill[bucketOf_[i]]++;
    order_[slot] = static_cast<std::uint32_t>(i);
    // Contiguous copies of what the candidate test reads: the scan streams through them instead of
    // following order_ into the larger StepDisc records.
    sorted_[slot] = HashEntry{discs[i].disc.x, discs[i].disc.y, discs[i].reach, discs[i].reach > 0.5 * size};
  }
}

void FusionEngine::paintDisc(const Disc& disc, double p, std::uint8_t level) {
  // Local copies: the grid writes below could otherwise alias them and force reloads.
  const Disc d = disc;
  const GridSpec g = config_.grid;
  auto& P = result_.probability.p;
  auto& L = result_.levels.level;
  const double invRes = 1.0 / g.resolution;            // estimates only; the exact test settles the ends
  const double fy = (d.y - g.originY) * invRes - 0.5;  // row coordinate of the centre
  const double fr = d.r * invRes;
  const int j0 = std::max(0, static_cast<int>(std::floor(fy - fr)) - 1);
  const int j1 = std::min(g.height - 1, static_cast<int>(std::ceil(fy + fr)) + 1);
  const double fx = (d.x - g.originX) * invRes - 0.5;
  const int ts = config_.tileSize;
  std::size_t visited = 0;
  // First the cell interval of every row (independent rows, so their square roots overlap in the
  // pipeline), then the writes.
  rowSpans_.clear();
  const double* cx = cellX_.data();
  // The estimate's error bound below holds for coordinates under 1e6 cells and radii under 100 cells
  // (the rounding of r² − dy² then moves the ends by < 1e-8 cells when half > 1e-3); else always test.
  const bool spansByEstimate =
      fr < 100.0 && (std::abs(d.x) + std::abs(g.originX) + g.width * g.resolution) * invRes < 1e6;
  for (int j = j0; j <= j1; ++j) {
    const double cy = g.cellCentreY(j);
    const double dy = cy - d.y;
    const double rem = d.r * d.r - dy * dy;
    if (rem < -1e-9 * d.r * d.r) {
      continue;
    }
    // The cells of a row inside the disc form one interval (dx² grows monotonically away from the
    // centre); estimate its ends with sqrt, then settle them with the exact test the reference uses.
    const double half = std::sqrt(std::max(rem, 0.0)) * invRes;
    // Cell i's centre is at column coordinate i, so the row's cells are those in [lo, hi]. When both
    // ends are more than 1e-6 cells from a cell centre (and the row is not a near-tangent sliver), the
    // floating-point error of either computation (~1e-12 cells) cannot change which cells are inside,
    // and the interval stands as computed; otherwise the exact test the reference uses settles it.
    const double lo = fx - half;
    const double hi = fx + half;
    bool clear = spansByEstimate && half > 1e-3;
    int a = 0;
    int b = g.width - 1;
    if (lo > static_cast<double>(g.width)) {
      a = g.width;
    } else if (lo >= -1.0) {
      const int f = static_cast<int>(lo + 1.0) - 1;  // floor (lo + 1 >= 0), without SSE4.1 rounding
      const double frac = lo - static_cast<double>(f);
      clear = clear && frac > 1e-6 && frac < 1.0 - 1e-6;
      a = f + 1;
    }
    if (hi < -1.0) {
      b = -1;
    } else if (hi <= static_cast<double>(g.width)) {
      const int f = static_cast<int>(hi + 1.0) - 1;
      const double frac = hi - static_cast<double>(f);
      clear = clear && frac > 1e-6 && frac < 1.0 - 1e-6;
      b = std::min(f, g.width - 1);
    }
    if (!clear) {
      // Estimates at most one cell off; the corrections walk to the exact ends.
      a = std::clamp(a, 0, g.width);
      b = std::clamp(b, -1, g.width - 1);
      while (a > 0 && cellInsideDisc(cx[a - 1], cy, d))
        --a;
      while (a <= b && !cellInsideDisc(cx[a], cy, d))
        ++a;
      while (b < g.width - 1 && cellInsideDisc(cx[b + 1], cy, d))
        ++b;
      while (b >= a && !cellInsideDisc(cx[b], cy, d))
        --b;
    }
    if (a <= b) {
      rowSpans_.push_back(RowSpan{j, a, b});
    }
  }
  for (const RowSpan& span : rowSpans_) {
    const int j = span.j;
    const int a = span.a;
    const int b = span.b;
    double* row = P.data() + g.index(0, j);
    std::uint8_t* lrow = L.data() + g.index(0, j);
    const std::size_t tileRow = static_cast<std::size_t>(j >> tileShift_) * static_cast<std::size_t>(tilesX_);
    if (allDirty_) {
      for (int i = a; i <= b; ++i) {
        row[i] = std::max(row[i], p);
      }
      for (int i = a; i <= b; ++i) {
        lrow[i] = std::max(lrow[i], level);
      }
      visited += static_cast<std::size_t>(b - a + 1);
      continue;
    }
    for (int tx = a >> tileShift_; tx <= (b >> tileShift_); ++tx) {
      if (dirtyTiles_[tileRow + static_cast<std::size_t>(tx)] == 0) {
        continue;
      }
      const int lo = std::max(a, tx * ts);
      const int hi = std::min(b, tx * ts + ts - 1);
      for (int i = lo; i <= hi; ++i) {
        row[i] = std::max(row[i], p);
      }
      for (int i = lo; i <= hi; ++i) {
        lrow[i] = std::max(lrow[i], level);
      }
      visited += static_cast<std::size_t>(hi - lo + 1);
    }
  }
  result_.stats.cellsVisited += visited;
}

void FusionEngine::recompute(bool full) {
  const GridSpec& g = config_.grid;
  const int steps = config_.steps;
  FusionStats stats;
  stats.fullRecompute = full;
  result_.stats = stats;

  // Entries in id order so the per-step disc order is deterministic.
  std::vector<const Entry*> entries;
  entries.reserve(sources_.size());
  for (const auto& [id, e] : sources_) {
    entries.push_back(&e);
  }
  std::sort(entries.begin(), entries.end(),
            [](const Entry* a, const Entry* b) { return a->source.id < b->source.id; });

  stepDiscs_.resize(static_cast<std::size_t>(steps));
  double maxReach = 0.0;
  for (auto& list : stepDiscs_) {
    list.clear();
  }
  // Source-major: each source's discs are contiguous, the per-step lists are appended to in order.
  for (std::size_t s = 0; s < entries.size(); ++s) {
    const auto& aligned = entries[s]->aligned.steps;
    for (int k = 0; k < steps; ++k) {
      const auto& slot = aligned[static_cast<std::size_t>(k)];
      if (slot.has_value()) {
        const double reach = model_->reach(*slot);
        maxReach = std::max(maxReach, reach);
        stepDiscs_[static_cast<std::size_t>(k)].push_back(
            StepDisc{*slot, static_cast<std::uint32_t>(s), entries[s]->source.kind, reach});
      }
    }
  }
  for (const auto& list : stepDiscs_) {
    result_.stats.discs += list.size();
  }
  for (const Disc& d : pendingDirty_) {
    maxReach = std::max(maxReach, model_->reach(d));
  }

  allDirty_ = full;
  if (full) {
    std::fill(dirtyTiles_.begin(), dirtyTiles_.end(), 1);
    pendingDirty_.clear();
    std::fill(result_.probability.p.begin(), result_.probability.p.end(), 0.0);
    std::fill(result_.levels.level.begin(), result_.levels.level.end(), std::uint8_t{0});
  } else {
    markDirtyTiles(maxReach);
    const int ts = config_.tileSize;
    for (int ty = 0; ty < tilesY_; ++ty) {
      for (int tx = 0; tx < tilesX_; ++tx) {
        if (dirtyTiles_[static_cast<std::size_t>(ty * tilesX_ + tx)] == 0) {
          continue;
        }
        for (int j = ty * ts; j < std::min(g.height, ty * ts + ts); ++j) {
          double* row = result_.probability.p.data() + g.index(0, j);
          std::fill(row + tx * ts, row + std::min(g.width, tx * ts + ts), 0.0);
          std::uint8_t* lrow = result_.levels.level.data() + g.index(0, j);
          std::fill(lrow + tx * ts, lrow + std::min(g.width, tx * ts + ts), std::uint8_t{0});
        }
      }
    }
  }
  for (auto t : dirtyTiles_) {
    result_.stats.tilesRecomputed += t;
  }

  const double tileM = g.resolution * config_.tileSize;
  auto touchesDirty = [&](const Disc& d) {
    if (full) {
      return true;
    }
    const int tx0 = std::max(0, static_cast<int>(std::floor((d.x - d.r - g.originX) / tileM - 1e-9)));
    const int tx1 =
        std::min(tilesX_ - 1, static_cast<int>(std::floor((d.x + d.r - g.originX) / tileM + 1e-9)));
    const int ty0 = std::max(0, static_cast<int>(std::floor((d.y - d.r - g.originY) / tileM - 1e-9)));
    const int ty1 =
        std::min(tilesY_ - 1, static_cast<int>(std::floor((d.y + d.r - g.originY) / tileM + 1e-9)));
    for (int ty = ty0; ty <= ty1; ++ty) {
      for (int tx = tx0; tx <= tx1; ++tx) {
        if (dirtyTiles_[static_cast<std::size_t>(ty * tilesX_ + tx)] != 0) {
          return true;
        }
      }
    }
    return false;
  };

  result_.sceneIndexPerStep.assign(static_cast<std::size_t>(steps), 0.0);
  paints_.clear();
  const PairPolicy& policy = config_.policy;
  for (int k = 0; k < steps; ++k) {
    const auto& list = stepDiscs_[static_cast<std::size_t>(k)];
    if (list.empty()) {
      continue;
    }
    discMax_.assign(list.size(), 0.0);
    active_.resize(list.size());
    double areaAll = 0.0;
    double areaHumans = 0.0;
    std::size_t humans = 0;
    for (std::size_t i = 0; i < list.size(); ++i) {
      active_[i] = touchesDirty(list[i].disc) ? 1 : 0;
      const double a = std::numbers::pi * list[i].disc.r * list[i].disc.r;
      areaAll += a;
      if (list[i].kind == SourceKind::kHuman) {
        areaHumans += a;
        ++humans;
      }
    }
    buildHash(list);
    double interSum = 0.0;
    // Only each disc's maximum is painted: a pair scoring below both active discs' maxima so far
    // changes nothing, and the model may skip scoring it (pairAbove). Touching pairs, which score
    // highest, go first; the others are scored after the scan.
    auto scorePair = [&](std::uint32_t i, std::uint32_t j, double d, double inter) {
      constexpr double kNone = 2.0;
      const double known =
          std::min(active_[i] != 0 ? discMax_[i] : kNone, active_[j] != 0 ? discMax_[j] : kNone);
      const double p = model_->pairAbove(list[i].disc, list[j].disc, d, inter, known);
      if (p > 0.0) {
        ++result_.stats.pairsPositive;
        discMax_[i] = std::max(discMax_[i], p);
        discMax_[j] = std::max(discMax_[j], p);
      }
    };
    deferred_.clear();
    auto visitPair = [&](std::uint32_t i, std::uint32_t j) {
      const StepDisc& a = list[i];
      const StepDisc& b = list[j];
      const double dx = a.disc.x - b.disc.x;
      const double dy = a.disc.y - b.disc.y;
      const double reachSum = a.reach + b.reach;
      if (dx * dx + dy * dy >= reachSum * reachSum || !pairAllowed(a.kind, b.kind, policy)) {
        return;
      }
      ++result_.stats.pairsTested;
      const double d = centreDistance(a.disc, b.disc);
      // Most pairs of the Gaussian model's reach do not touch: no call for their zero area.
      const double inter = d < a.disc.r + b.disc.r ? discIntersectionArea(a.disc.r, b.disc.r, d) : 0.0;
      interSum += inter;
      if (active_[i] == 0 && active_[j] == 0) {
        return;
      }
      if (d < a.disc.r + b.disc.r) {
        scorePair(i, j, d, inter);
      } else {
        deferred_.push_back(DeferredPair{i, j, d});
      }
    };
    const HashEntry* he = sorted_.data();
    auto near = [](const HashEntry& a, const HashEntry& b) {
      const double dx = a.x - b.x;
      const double dy = a.y - b.y;
      const double rs = a.reach + b.reach;
      return dx * dx + dy * dy < rs * rs;
    };
    for (int by = 0; by < bucketsY_; ++by) {
      for (int bx = 0; bx < bucketsX_; ++bx) {
        const std::size_t b = static_cast<std::size_t>(by * bucketsX_ + bx);
        for (std::uint32_t u = bucketStart_[b]; u < bucketStart_[b + 1]; ++u) {
          if (he[u].wide) {
            continue;  // its pairs are found from the wide discs' side below
          }
          const std::uint32_t i = order_[u];
          for (std::uint32_t v = u + 1; v < bucketStart_[b + 1]; ++v) {
            if (!he[v].wide && near(he[u], he[v])) {
              visitPair(i, order_[v]);
            }
          }
          // Forward half of the 8-neighbourhood, so every pair of buckets is visited once.
          constexpr int kNeighbours[4][2] = {{1, -1}, {1, 0}, {1, 1}, {0, 1}};
          for (const auto& nb : kNeighbours) {
            const int nx = bx + nb[0];
            const int ny = by + nb[1];
            if (nx < 0 || ny < 0 || nx >= bucketsX_ || ny >= bucketsY_) {
              continue;
            }
            const std::size_t c = static_cast<std::size_t>(ny * bucketsX_ + nx);
            for (std::uint32_t v = bucketStart_[c]; v < bucketStart_[c + 1]; ++v) {
              if (!he[v].wide && near(he[u], he[v])) {
                visitPair(i, order_[v]);
              }
            }
          }
        }
      }
    }
    // A wide disc pairs with every narrow disc and with the wide discs after it in list order.
    for (const std::uint32_t i : wide_) {
      const StepDisc& a = list[i];
      const HashEntry self{a.disc.x, a.disc.y, a.reach, true};
      const int m = static_cast<int>(std::floor((a.reach + maxReachInHash_) / bucketSize_)) + 1;
      const int bx = static_cast<int>(bucketOf_[i] % static_cast<std::uint32_t>(bucketsX_));
      const int by = static_cast<int>(bucketOf_[i] / static_cast<std::uint32_t>(bucketsX_));
      for (int y = std::max(0, by - m); y <= std::min(bucketsY_ - 1, by + m); ++y) {
        for (int x = std::max(0, bx - m); x <= std::min(bucketsX_ - 1, bx + m); ++x) {
          const std::size_t c = static_cast<std::size_t>(y * bucketsX_ + x);
          for (std::uint32_t v = bucketStart_[c]; v < bucketStart_[c + 1]; ++v) {
            const std::uint32_t j = order_[v];
            if ((!he[v].wide || j > i) && near(self, he[v])) {
              visitPair(i, j);
            }
          }
        }
      }
    }
    for (const DeferredPair& q : deferred_) {
      scorePair(q.i, q.j, q.d, 0.0);
    }
    for (std::size_t i = 0; i < list.size(); ++i) {
      if (active_[i] != 0 && discMax_[i] > 0.0) {
        paints_.push_back(Paint{list[i].disc.x, list[i].disc.y, list[i].disc.r, discMax_[i]});
      }
    }
    // Eq. (3.7) over the allowed unordered pairs: Σ∪ = Σ_pairs (A_i + A_j) − Σ∩, and Σ_pairs (A_i + A_j)
    // = (n − 1)·ΣA over all pairs, minus (h − 1)·ΣA_humans for the human–human pairs when skipped.
    const double n = static_cast<double>(list.size());
    double pairAreas = (n - 1.0) * areaAll;
    if (!policy.humanHuman && humans > 0) {
      pairAreas -= (static_cast<double>(humans) - 1.0) * areaHumans;
    }
    const double den = pairAreas - interSum;
    result_.sceneIndexPerStep[static_cast<std::size_t>(k)] =
        den > 0.0 ? std::clamp(interSum / den, 0.0, 1.0) : 0.0;
  }
  // Paint in tile order rather than step order: discs of nearby places and different steps then reuse
  // the same cache lines of the grid (the grid is megabytes; the discs are scattered).
  {
    const double inv = 1.0 / (g.resolution * config_.tileSize);
    // Counting sort by tile (stable; discs off the grid go to the nearest edge tile), gathered into
    // tile order before painting: the gather's independent loads overlap, whereas a load behind each
    // long paint call would wait for its cache miss alone.
    const std::size_t tiles = static_cast<std::size_t>(tilesX_) * static_cast<std::size_t>(tilesY_);
    paintTile_.resize(paints_.size());
    tileStart_.assign(tiles + 1, 0);
    for (std::size_t n = 0; n < paints_.size(); ++n) {
      const Paint& pt = paints_[n];
      const auto tx = static_cast<std::size_t>(
          std::clamp((pt.x - g.originX) * inv, 0.0, static_cast<double>(tilesX_ - 1)));
      const auto ty = static_cast<std::size_t>(
          std::clamp((pt.y - g.originY) * inv, 0.0, static_cast<double>(tilesY_ - 1)));
      paintTile_[n] = static_cast<std::uint32_t>(ty * static_cast<std::size_t>(tilesX_) + tx);
      ++tileStart_[paintTile_[n] + 1];
    }
    for (std::size_t t = 0; t < tiles; ++t) {
      tileStart_[t + 1] += tileStart_[t];
    }
    sortedPaints_.resize(paints_.size());
    for (std::size_t n = 0; n < paints_.size(); ++n) {
      sortedPaints_[tileStart_[paintTile_[n]]++] = paints_[n];
    }
    // The level of a cell is that of its maximum, and isoLevel is monotone, so painting each disc's
    // level with max gives the classified grid without a pass over the cells.
    const int K = config_.levels;
    for (const Paint& pt : sortedPaints_) {
      paintDisc(Disc{pt.x, pt.y, pt.r}, pt.p, static_cast<std::uint8_t>(isoLevel(pt.p, K)));
    }
    result_.stats.discsPainted = paints_.size();
  }
  result_.sceneIndex = 0.0;
  for (double s : result_.sceneIndexPerStep) {
    result_.sceneIndex = std::max(result_.sceneIndex, s);
  }

  std::fill(dirtyTiles_.begin(), dirtyTiles_.end(), 0);
}

}  // namespace fleet::risk
