#include "fleet/risk/fusion_engine.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>

namespace fleet::risk {

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

}  // namespace fleet::risk
