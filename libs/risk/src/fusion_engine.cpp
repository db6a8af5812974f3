#include "fleet/risk/fusion_engine.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
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

namespace {
// Conservative row bounds of a disc whose rows span the row coordinates [lo, hi]: floor(lo) − 1 and
// at least ceil(hi) + 1, by truncation of clamped values (cheaper than floor/ceil without SSE4.1).

int firstRow(double lo) {
  return static_cast<int>(std::clamp(lo, 1.0, 2e9)) - 1;
}
int lastRow(double hi) {
  return static_cast<int>(std::clamp(hi + 2.0, 0.0, 2e9));
}
}  // namespace

void FusionEngine::buildHash() {
  // Uniform buckets over the bounding box of the centres, filled by counting sort. Their side is twice
  // the 90th percentile of the reaches rather than of the largest: a few very uncertain discs (people
  // late in the horizon) would otherwise make every bucket hold dozens of discs. Partners of two items
  // with reach <= side/2 lie in the same or a neighbouring bucket; the few larger ("wide") ones search
  // as many buckets as their own reach plus the largest needs.
  const auto& items = items_;
  double minX = items[0].x, maxX = minX, minY = items[0].y, maxY = minY, maxR = 0.0;
  reachScratch_.clear();
  for (const auto& it : items) {
    minX = std::min(minX, it.x);
    maxX = std::max(maxX, it.x);
    minY = std::min(minY, it.y);
    maxY = std::max(maxY, it.y);
    maxR = std::max(maxR, it.reach);
    reachScratch_.push_back(it.reach);
  }
  const auto q = static_cast<std::ptrdiff_t>(reachScratch_.size() * 9 / 10);
  std::nth_element(reachScratch_.begin(), reachScratch_.begin() + q, reachScratch_.end());
  double size = std::max(2.0 * reachScratch_[static_cast<std::size_t>(q)], 1e-6);
  const double cap = 4.0 * static_cast<double>(items.size()) + 64.0;
  double nx = std::floor((maxX - minX) / size) + 1.0;
  double ny = std::floor((maxY - minY) / size) + 1.0;
  if (nx * ny > cap) {
    size *= std::sqrt(nx * ny / cap) * 1.01;
    nx = std::floor((maxX - minX) / size) + 1.0;
    ny = std::floor((maxY - minY) / size) + 1.0;
  }
  bucketSize_ = size;
  bucketsX_ = static_cast<int>(nx);
  bucketsY_ = static_cast<int>(ny);
  maxReachInHash_ = maxR;
  const std::size_t nb = static_cast<std::size_t>(bucketsX_) * static_cast<std::size_t>(bucketsY_);
  bucketStart_.assign(nb + 1, 0);
  bucketOf_.resize(items.size());
  wide_.clear();
  for (std::size_t i = 0; i < items.size(); ++i) {
    const int bx = std::min(bucketsX_ - 1, static_cast<int>((items[i].x - minX) / size));
    const int by = std::min(bucketsY_ - 1, static_cast<int>((items[i].y - minY) / size));
    bucketOf_[i] = static_cast<std::uint32_t>(by * bucketsX_ + bx);
    ++bucketStart_[bucketOf_[i] + 1];
    if (items[i].reach > 0.5 * size) {
      wide_.push_back(static_cast<std::uint32_t>(i));
    }
  }
  for (std::size_t b = 0; b < nb; ++b) {
    bucketStart_[b + 1] += bucketStart_[b];
  }
  order_.resize(items.size());
  sorted_.resize(items.size());
  auto& fill = bucketFill_;
  fill.assign(bucketStart_.begin(), bucketStart_.end() - 1);
  for (std::size_t i = 0; i < items.size(); ++i) {
    const std::uint32_t slot = fill[bucketOf_[i]]++;
    order_[slot] = static_cast<std::uint32_t>(i);
    // Contiguous copies of what the candidate test reads: the scan streams through them.
    sorted_[slot] = HashEntry{items[i].x, items[i].y, items[i].reach, items[i].reach > 0.5 * size};
  }
}

void FusionEngine::rowSpans(const Disc& d, int rowLo, int rowHi) {
  // The cell interval of every row the disc covers within rowLo..rowHi (independent rows, so their
  // square roots overlap in the pipeline); the writes follow separately.
  const GridSpec& g = config_.grid;
  const double invRes = 1.0 / g.resolution;            // estimates only; the exact test settles the ends
  const double fy = (d.y - g.originY) * invRes - 0.5;  // row coordinate of the centre
  const double fr = d.r * invRes;
  const int j0 = std::max(rowLo, firstRow(fy - fr));
  const int j1 = std::min(rowHi, lastRow(fy + fr));
  const double fx = (d.x - g.originX) * invRes - 0.5;
  rowSpans_.clear();
  const double* cx = cellX_.data();
  // The estimate's error bound below holds for coordinates under 1e6 cells and radii under 100 cells
  // (the rounding of r² − dy² then moves the ends by < 1e-8 cells when half > 1e-3); else always test.
  const bool spansByEstimate =
      fr < 100.0 && (std::abs(d.x) + std::abs(g.originX) + g.width * g.resolution) * invRes < 1e6;
  // Every row's ends inside the grid with a cell of margin: no clamping, floor by truncation.
  const bool interior = spansByEstimate && fx - fr > 1.0 && fx + fr < g.width - 2.0;
  const double* cyOf = cellY_.data();
  for (int j = j0; j <= j1; ++j) {
    const double cy = cyOf[j];
    const double dy = cy - d.y;
    const double rem = d.r * d.r - dy * dy;
    if (rem < -1e-9 * d.r * d.r) {
      continue;
    }
    // The cells of a row inside the disc form one interval (dx² grows monotonically away from the
    // centre); estimate its ends with sqrt, then settle them with the exact test the reference uses.
    const double half = std::sqrt(std::max(rem, 0.0)) * invRes;
    if (interior) {
      // The common case of the general path below, without its branches: both ends clear of cell
      // centres (non-short-circuit &, so the test is one predictable branch).
      const double lo = fx - half;
      const double hi = fx + half;
      const int fa = static_cast<int>(lo);
      const int fb = static_cast<int>(hi);
      const double ra = lo - static_cast<double>(fa);
      const double rb = hi - static_cast<double>(fb);
      if ((half > 1e-3) & (ra > 1e-6) & (ra < 1.0 - 1e-6) & (rb > 1e-6) & (rb < 1.0 - 1e-6)) {
        if (fa < fb) {
          rowSpans_.push_back(RowSpan{j, fa + 1, fb});
        }
        continue;
      }
    }
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
}

void FusionEngine::writeSpan(int j, int a, int b, double p, std::uint8_t level) {
  const GridSpec& g = config_.grid;
  double* row = result_.probability.p.data() + g.index(0, j);
  std::uint8_t* lrow = result_.levels.level.data() + g.index(0, j);
  if (allDirty_) {
    for (int i = a; i <= b; ++i) {
      row[i] = std::max(row[i], p);
    }
    for (int i = a; i <= b; ++i) {
      lrow[i] = std::max(lrow[i], level);
    }
    result_.stats.cellsVisited += static_cast<std::size_t>(b - a + 1);
    return;
  }
  const int ts = config_.tileSize;
  const std::size_t tileRow = static_cast<std::size_t>(j >> tileShift_) * static_cast<std::size_t>(tilesX_);
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
    result_.stats.cellsVisited += static_cast<std::size_t>(hi - lo + 1);
  }
}

void FusionEngine::paintSourceRows(const SourcePaint& sp, int rowLo, int rowHi) {
  // The discs of one source overlap heavily from step to step (it moves a fraction of its radius per
  // step). Painted in decreasing score, a disc only needs to write the cells of each row that the
  // source's higher-scored discs have not written yet: per row the cells written so far are kept as
  // one interval (the union of overlapping spans; of two disjoint ones the longer), and anything
  // outside it is written with max as before, so the grid is the same whatever the shapes.
  const auto rows = static_cast<std::size_t>(rowHi - rowLo + 1);
  coverLo_.assign(rows, 1);
  coverHi_.assign(rows, 0);  // lo > hi: nothing written in the row yet
  const GridSpec& g = config_.grid;
  double* P = result_.probability.p.data();
  std::uint8_t* L = result_.levels.level.data();
  for (std::uint32_t n = sp.begin; n < sp.end; ++n) {
    const PaintDisc pd = paintList_[n];
    const std::uint8_t level = pd.level;
    rowSpans(Disc{pd.x, pd.y, pd.r}, rowLo, rowHi);
    auto write = [&](int j, int a, int b) {
      if (!allDirty_) {
        writeSpan(j, a, b, pd.p, level);
        return;
      }
      double* row = P + g.index(0, j);
      std::uint8_t* lrow = L + g.index(0, j);
      for (int i = a; i <= b; ++i) {
        row[i] = std::max(row[i], pd.p);
      }
      for (int i = a; i <= b; ++i) {
        lrow[i] = std::max(lrow[i], level);
      }
      result_.stats.cellsVisited += static_cast<std::size_t>(b - a + 1);
    };
    for (const RowSpan& span : rowSpans_) {
      const auto r = static_cast<std::size_t>(span.j - rowLo);
      int& lo = coverLo_[r];
      int& hi = coverHi_[r];
      if (lo > hi) {
        write(span.j, span.a, span.b);
        lo = span.a;
        hi = span.b;
      } else if (span.b < lo - 1 || span.a > hi + 1) {
        write(span.j, span.a, span.b);
        if (span.b - span.a > hi - lo) {
          lo = span.a;
          hi = span.b;
        }
      } else {
        if (span.a < lo) {
          write(span.j, span.a, lo - 1);
          lo = span.a;
        }
        if (span.b > hi) {
          write(span.j, hi + 1, span.b);
          hi = span.b;
        }
      }
    }
  }
}

void FusionEngine::paint(bool full) {
  // The grid (megabytes) is painted band by band of rows, each band small enough to stay in the
  // cache while every source crossing it paints its rows there; a full recompute clears each band
  // just before painting it rather than the whole grid up front.
  const GridSpec& g = config_.grid;
  const auto steps = static_cast<std::size_t>(config_.steps);
  const double invRes = 1.0 / g.resolution;
  paintList_.clear();
  sourcePaints_.clear();
  for (std::size_t s = 0; s < entries_.size(); ++s) {
    const auto begin = static_cast<std::uint32_t>(paintList_.size());
    int rowMin = g.height;
    int rowMax = -1;
    for (std::size_t k = 0; k < steps; ++k) {
      const std::size_t q = s * steps + k;
      if (active_[q] != 0 && discMax_[q] > 0.0) {
        const Disc& d = *disc_[q];
        // The level of a cell is that of its maximum, and isoLevel is monotone, so painting each disc's
        // level with max gives the classified grid without a pass over the cells.
        paintList_.push_back(PaintDisc{d.x, d.y, d.r, discMax_[q],
                                       static_cast<std::uint8_t>(isoLevel(discMax_[q], config_.levels))});
        const double fy = (d.y - g.originY) * invRes - 0.5;
        const double fr = d.r * invRes;
        rowMin = std::min(rowMin, firstRow(fy - fr));
        rowMax = std::max(rowMax, std::min(g.height - 1, lastRow(fy + fr)));
      }
    }
    const auto end = static_cast<std::uint32_t>(paintList_.size());
    if (end == begin) {
      continue;
    }
    std::sort(paintList_.begin() + begin, paintList_.begin() + end,
              [](const PaintDisc& a, const PaintDisc& b) { return a.p > b.p; });
    if (rowMin <= rowMax) {
      sourcePaints_.push_back(SourcePaint{begin, end, rowMin, rowMax});
    }
  }
  result_.stats.discsPainted = paintList_.size();
  // ~256 KiB of grid per band.
  const std::size_t rowBytes = static_cast<std::size_t>(g.width) * (sizeof(double) + 1);
  const int band = static_cast<int>(std::clamp<std::size_t>((256u << 10) / rowBytes, 1, g.height));
  const int bands = (g.height + band - 1) / band;
  bandStart_.assign(static_cast<std::size_t>(bands) + 1, 0);
  for (const SourcePaint& sp : sourcePaints_) {
    for (int b = sp.rowMin / band; b <= sp.rowMax / band; ++b) {
      ++bandStart_[static_cast<std::size_t>(b) + 1];
    }
  }
  for (int b = 0; b < bands; ++b) {
    bandStart_[static_cast<std::size_t>(b) + 1] += bandStart_[static_cast<std::size_t>(b)];
  }
  bandItems_.resize(bandStart_.back());
  bandFill_.assign(bandStart_.begin(), bandStart_.end() - 1);
  for (std::uint32_t n = 0; n < sourcePaints_.size(); ++n) {
    for (int b = sourcePaints_[n].rowMin / band; b <= sourcePaints_[n].rowMax / band; ++b) {
      bandItems_[bandFill_[static_cast<std::size_t>(b)]++] = n;
    }
  }
  for (int b = 0; b < bands; ++b) {
    const int lo = b * band;
    const int hi = std::min(g.height, lo + band) - 1;
    if (full) {
      std::fill(result_.probability.p.begin() + static_cast<std::ptrdiff_t>(g.index(0, lo)),
                result_.probability.p.begin() + static_cast<std::ptrdiff_t>(g.index(0, hi + 1)), 0.0);
      std::fill(result_.levels.level.begin() + static_cast<std::ptrdiff_t>(g.index(0, lo)),
                result_.levels.level.begin() + static_cast<std::ptrdiff_t>(g.index(0, hi + 1)),
                std::uint8_t{0});
    }
    for (std::uint32_t n = bandStart_[static_cast<std::size_t>(b)];
         n < bandStart_[static_cast<std::size_t>(b) + 1]; ++n) {
      const SourcePaint& sp = sourcePaints_[bandItems_[n]];
      paintSourceRows(sp, std::max(lo, sp.rowMin), std::min(hi, sp.rowMax));
    }
  }
}

void FusionEngine::scorePair(std::uint32_t qa, std::uint32_t qb, double d, double inter) {
  // Only each disc's maximum is painted: a pair scoring below both active discs' maxima so far changes
  // nothing, and the model may skip scoring it (pairAbove).
  constexpr double kNone = 2.0;
  const double known =
      std::min(active_[qa] != 0 ? discMax_[qa] : kNone, active_[qb] != 0 ? discMax_[qb] : kNone);
  const double p = model_->pairAbove(*disc_[qa], *disc_[qb], d, inter, known);
  if (p > 0.0) {
    ++result_.stats.pairsPositive;
    discMax_[qa] = std::max(discMax_[qa], p);
    discMax_[qb] = std::max(discMax_[qb], p);
  }
}

void FusionEngine::visitPair(std::uint32_t qa, std::uint32_t qb, int k) {
  // Called for two discs of one step within reach of each other, of sources the policy pairs.
  ++result_.stats.pairsTested;
  // From the contiguous copies rather than the discs (scattered over the sources' records); the same
  // doubles, so d is centreDistance(a, b) exactly.
  const double dx = qd_[qa].x - qd_[qb].x;
  const double dy = qd_[qa].y - qd_[qb].y;
  const double d = std::sqrt(dx * dx + dy * dy);
  const double ra = qd_[qa].r;
  const double rb = qd_[qb].r;
  // Most pairs of the Gaussian model's reach do not touch: no call for their zero area.
  const double R = ra + rb;
  if (d < R) {
    const double inter = discIntersectionArea(ra, rb, d);
    interSum_[static_cast<std::size_t>(k)] += inter;
    if (active_[qa] != 0 || active_[qb] != 0) {
      scorePair(qa, qb, d, inter);  // touching pairs score highest: first, so more of the others skip
    }
    return;
  }
  // Beyond the model's cull (tighter than the reaches: for the Gaussian √(σa² + σb²) instead of
  // σa + σb) the pair scores 0; a third of the Gaussian's candidates end here.
  const double ta = qd_[qa].tail;
  const double tb = qd_[qb].tail;
  const double t2 = ta * ta + tb * tb;
  const double gap = d - R;
  if ((active_[qa] != 0 || active_[qb] != 0) && gap * gap < t2) {
    // Scored later in kDeferredBins bins of (gap / √(ta² + tb²))² ∈ [0, 1): for the Gaussian a
    // decreasing order of the tail bound, so a disc's best partners come first and set the maxima
    // that let the model skip the rest.
    const auto bin = static_cast<std::uint8_t>(
        std::min(static_cast<double>(kDeferredBins) - 1.0,
                 t2 > 0.0 ? gap * gap / t2 * static_cast<double>(kDeferredBins) : 0.0));
    deferred_.push_back(DeferredPair{qa, qb, d, bin});
  }
}

int FusionEngine::windowLength() const {
  // Candidate pairs are found once per window of consecutive steps, between the sources' bounding
  // circles over the window (centre ± how far it moves, plus its largest reach). A longer window
  // means fewer hash builds and scans but circles inflated by the motion; it pays while the motion
  // over the window stays well under the typical reach. Both are estimated from a sample.
  const int steps = config_.steps;
  const std::size_t n = entries_.size();
  if (steps < 2 || n == 0) {
    return 1;
  }
  const std::size_t stride = std::max<std::size_t>(1, n / 128);
  std::vector<double> reach;
  std::vector<double> move;
  for (std::size_t s = 0; s < n; s += stride) {
    for (int k = 0; k + 1 < steps; k += 4) {
      const std::size_t q = s * static_cast<std::size_t>(steps) + static_cast<std::size_t>(k);
      if (disc_[q] != nullptr && disc_[q + 1] != nullptr) {
        reach.push_back(qd_[q].reach);
        move.push_back(std::hypot(qd_[q + 1].x - qd_[q].x, qd_[q + 1].y - qd_[q].y));
      }
    }
  }
  if (reach.empty()) {
    return 1;
  }
  const auto mid = static_cast<std::ptrdiff_t>(reach.size() / 2);
  std::nth_element(reach.begin(), reach.begin() + mid, reach.end());
  std::nth_element(move.begin(), move.begin() + mid, move.end());
  const double m = move[static_cast<std::size_t>(mid)];
  const double r = reach[static_cast<std::size_t>(mid)];
  const double w = m > 0.0 ? 1.0 + r / m : static_cast<double>(steps);
  return static_cast<int>(std::clamp(w, 1.0, std::min(8.0, static_cast<double>(steps))));
}

void FusionEngine::scanWindow(int k0, int k1) {
  const auto steps = static_cast<std::size_t>(config_.steps);
  items_.clear();
  itemSource_.clear();
  for (std::size_t s = 0; s < entries_.size(); ++s) {
    const std::size_t base = s * steps;
    double minX = 0.0, maxX = 0.0, minY = 0.0, maxY = 0.0;
    bool any = false;
    for (int k = k0; k < k1; ++k) {
      const std::size_t q = base + static_cast<std::size_t>(k);
      if (disc_[q] == nullptr) {
        continue;
      }
      if (!any) {
        minX = maxX = qd_[q].x;
        minY = maxY = qd_[q].y;
        any = true;
      } else {
        minX = std::min(minX, qd_[q].x);
        maxX = std::max(maxX, qd_[q].x);
        minY = std::min(minY, qd_[q].y);
        maxY = std::max(maxY, qd_[q].y);
      }
    }
    if (!any) {
      continue;
    }
    const double cx = 0.5 * (minX + maxX);
    const double cy = 0.5 * (minY + maxY);
    double rho = 0.0;
    for (int k = k0; k < k1; ++k) {
      const std::size_t q = base + static_cast<std::size_t>(k);
      if (disc_[q] != nullptr) {
        // sqrt rather than hypot (coordinates are validated); the padding below covers its rounding.
        const double dx = qd_[q].x - cx;
        const double dy = qd_[q].y - cy;
        rho = std::max(rho, std::sqrt(dx * dx + dy * dy) + qd_[q].reach);
      }
    }
    // |a_k − b_k| < reach_a + reach_b implies |c_a − c_b| < ρ_a + ρ_b by the triangle inequality; the
    // padding covers the rounding of these few operations.
    rho += 1e-9 * (rho + std::abs(cx) + std::abs(cy)) + 1e-12;
    items_.push_back(HashEntry{cx, cy, rho, false});
    itemSource_.push_back(static_cast<std::uint32_t>(s));
  }
  if (items_.empty()) {
    return;
  }
  buildHash();
  const PairPolicy& policy = config_.policy;
  // Every step of the window of two candidate sources: the same test as a per-step hash would make.
  auto sourcePair = [&](std::uint32_t ia, std::uint32_t ib) {
    const std::uint32_t sa = itemSource_[ia];
    const std::uint32_t sb = itemSource_[ib];
    if (!pairAllowed(kind_[sa], kind_[sb], policy)) {
      return;
    }
    const std::size_t ba = sa * steps;
    const std::size_t bb = sb * steps;
    for (int k = k0; k < k1; ++k) {
      const std::size_t qa = ba + static_cast<std::size_t>(k);
      const std::size_t qb = bb + static_cast<std::size_t>(k);
      const double dx = qd_[qa].x - qd_[qb].x;  // NaN when either is absent: the test below fails
      const double dy = qd_[qa].y - qd_[qb].y;
      const double reachSum = qd_[qa].reach + qd_[qb].reach;
      if (dx * dx + dy * dy < reachSum * reachSum) {
        visitPair(static_cast<std::uint32_t>(qa), static_cast<std::uint32_t>(qb), k);
      }
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
          continue;  // its pairs are found from the wide items' side below
        }
        const std::uint32_t i = order_[u];
        for (std::uint32_t v = u + 1; v < bucketStart_[b + 1]; ++v) {
          if (!he[v].wide && near(he[u], he[v])) {
            sourcePair(i, order_[v]);
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
              sourcePair(i, order_[v]);
            }
          }
        }
      }
    }
  }
  // A wide item pairs with every narrow item and with the wide items after it.
  for (const std::uint32_t i : wide_) {
    const HashEntry self = items_[i];
    const int m = static_cast<int>(std::floor((self.reach + maxReachInHash_) / bucketSize_)) + 1;
    const int bx = static_cast<int>(bucketOf_[i] % static_cast<std::uint32_t>(bucketsX_));
    const int by = static_cast<int>(bucketOf_[i] / static_cast<std::uint32_t>(bucketsX_));
    for (int y = std::max(0, by - m); y <= std::min(bucketsY_ - 1, by + m); ++y) {
      for (int x = std::max(0, bx - m); x <= std::min(bucketsX_ - 1, bx + m); ++x) {
        const std::size_t c = static_cast<std::size_t>(y * bucketsX_ + x);
        for (std::uint32_t v = bucketStart_[c]; v < bucketStart_[c + 1]; ++v) {
          const std::uint32_t j = order_[v];
          if ((!he[v].wide || j > i) && near(self, he[v])) {
            sourcePair(i, j);
          }
        }
      }
    }
  }
}

void FusionEngine::scoreDeferred() {
  deferredStart_.assign(kDeferredBins + 1, 0);
  for (const DeferredPair& q : deferred_) {
    ++deferredStart_[q.bin + 1u];
  }
  for (std::size_t b = 0; b < kDeferredBins; ++b) {
    deferredStart_[b + 1] += deferredStart_[b];
  }
  deferredSorted_.resize(deferred_.size());
  for (const DeferredPair& q : deferred_) {
    deferredSorted_[deferredStart_[q.bin]++] = q;
  }
  constexpr double kNone = 2.0;
  // In bin order the pairs' discs are scattered: their loads are issued a few pairs ahead.
  constexpr std::size_t kAhead = 8;
  for (std::size_t n = 0; n < deferredSorted_.size(); ++n) {
    if (n + kAhead < deferredSorted_.size()) {
      const DeferredPair& f = deferredSorted_[n + kAhead];
      __builtin_prefetch(disc_[f.qa]);
      __builtin_prefetch(disc_[f.qb]);
      __builtin_prefetch(&discMax_[f.qa]);
      __builtin_prefetch(&discMax_[f.qb]);
    }
    const DeferredPair& q = deferredSorted_[n];
    const double known =
        std::min(active_[q.qa] != 0 ? discMax_[q.qa] : kNone, active_[q.qb] != 0 ? discMax_[q.qb] : kNone);
    if (binBound_[q.bin] < known) {
      continue;
    }
    scorePair(q.qa, q.qb, q.d, 0.0);
  }
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
