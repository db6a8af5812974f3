#include "fleet/risk/fusion_engine.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <vector>

#include "fleet/risk/overlap_ratio.hpp"

namespace fleet::risk {

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

}  // namespace fleet::risk
