#include "fleet/risk/fusion_engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <string>

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
  cellY_.resize(static_cast<std::size_t>(g.height));
  for (int j = 0; j < g.height; ++j) {
    cellY_[static_cast<std::size_t>(j)] = g.cellCentreY(j);
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

void FusionEngine::recompute(bool full) {
  const GridSpec& g = config_.grid;
  const int steps = config_.steps;
  const auto K = static_cast<std::size_t>(steps);
  FusionStats stats;
  stats.fullRecompute = full;
  result_.stats = stats;

  // Entries in id order so the disc order is deterministic.
  entries_.clear();
  entries_.reserve(sources_.size());
  for (const auto& [id, e] : sources_) {
    entries_.push_back(&e);
  }
  std::sort(entries_.begin(), entries_.end(),
            [](const Entry* a, const Entry* b) { return a->source.id < b->source.id; });

  // Source-major arrays of every disc, and the per-step sums of eq. (3.7) in the same order as before.
  const std::size_t nq = entries_.size() * K;
  disc_.assign(nq, nullptr);
  qd_.resize(nq);
  kind_.resize(entries_.size());
  std::vector<double> areaAll(K, 0.0), areaHumans(K, 0.0);
  std::vector<std::size_t> count(K, 0), humans(K, 0);
  double maxReach = 0.0;
  constexpr double kAbsent = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t s = 0; s < entries_.size(); ++s) {
    const auto& aligned = entries_[s]->aligned.steps;
    kind_[s] = entries_[s]->source.kind;
    const bool human = kind_[s] == SourceKind::kHuman;
    for (std::size_t k = 0; k < K; ++k) {
      const std::size_t q = s * K + k;
      const auto& slot = aligned[k];
      if (!slot.has_value()) {
        qd_[q] = PairDisc{kAbsent, kAbsent, 0.0, 0.0, 0.0};
        continue;
      }
      const Disc& d = *slot;
      disc_[q] = &d;
      qd_[q] = PairDisc{d.x, d.y, model_->reach(d), d.r, model_->tail(d)};
      maxReach = std::max(maxReach, qd_[q].reach);
      const double a = std::numbers::pi * d.r * d.r;
      areaAll[k] += a;
      ++count[k];
      if (human) {
        areaHumans[k] += a;
        ++humans[k];
      }
    }
  }
  for (const auto n : count) {
    result_.stats.discs += n;
  }
  for (const Disc& d : pendingDirty_) {
    maxReach = std::max(maxReach, model_->reach(d));
  }

  allDirty_ = full;
  if (full) {
    std::fill(dirtyTiles_.begin(), dirtyTiles_.end(), 1);
    pendingDirty_.clear();  // the grid is cleared band by band as it is painted
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
  discMax_.assign(nq, 0.0);
  active_.assign(nq, 0);
  for (std::size_t q = 0; q < nq; ++q) {
    if (disc_[q] != nullptr) {
      active_[q] = touchesDirty(*disc_[q]) ? 1 : 0;
    }
  }

  // Candidate pairs per window of steps; touching pairs are scored as found, the others (which
  // score lower) after all of them, so that more of those fall below both discs' maxima. A disc's
  // pairs are all at its own step, so every one of them is known once its window is scanned: the
  // window's deferred pairs are scored then, while its discs are still in the cache.
  interSum_.assign(K, 0.0);
  // One bound per bin (the model's, for the bin's smallest gap ratio): a pair whose bin bound is
  // below both discs' maxima cannot raise either, and is passed over without asking the model —
  // which would skip it too, its own bound for the pair being no larger.
  for (std::size_t b = 0; b < kDeferredBins; ++b) {
    binBound_[b] =
        model_->tailRatioBound(static_cast<double>(b) / static_cast<double>(kDeferredBins)) * (1.0 + 1e-9);
  }
  const int w = windowLength();
  for (int k0 = 0; k0 < steps; k0 += w) {
    deferred_.clear();
    scanWindow(k0, std::min(steps, k0 + w));
    scoreDeferred();
  }

  // Eq. (3.7) over the allowed unordered pairs: Σ∪ = Σ_pairs (A_i + A_j) − Σ∩, and Σ_pairs (A_i + A_j)
  // = (n − 1)·ΣA over all pairs, minus (h − 1)·ΣA_humans for the human–human pairs when skipped.
  result_.sceneIndexPerStep.assign(K, 0.0);
  for (std::size_t k = 0; k < K; ++k) {
    if (count[k] == 0) {
      continue;
    }
    const double n = static_cast<double>(count[k]);
    double pairAreas = (n - 1.0) * areaAll[k];
    if (!config_.policy.humanHuman && humans[k] > 0) {
      pairAreas -= (static_cast<double>(humans[k]) - 1.0) * areaHumans[k];
    }
    const double den = pairAreas - interSum_[k];
    result_.sceneIndexPerStep[k] = den > 0.0 ? std::clamp(interSum_[k] / den, 0.0, 1.0) : 0.0;
  }

  paint(full);
  result_.sceneIndex = 0.0;
  for (double s : result_.sceneIndexPerStep) {
    result_.sceneIndex = std::max(result_.sceneIndex, s);
  }

  std::fill(dirtyTiles_.begin(), dirtyTiles_.end(), 0);
}

}  // namespace fleet::risk
