#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <unordered_map>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/risk/grid.hpp"
#include "fleet/risk/iso_levels.hpp"
#include "fleet/risk/reference_algorithm.hpp"
#include "fleet/risk/risk_model.hpp"
#include "fleet/risk/source.hpp"

namespace fleet::risk {

struct FusionConfig {
  GridSpec grid{0.0, 0.0, 0.1, 1000, 500};
  int levels = 10;  // K
  double dt = 0.1;  // s between fused steps
  int steps = 30;   // horizon = steps · dt
  PairPolicy policy;
  SourceLimits limits;
  int tileSize = 32;  // cells per side of the unit of incremental recomputation (a power of two)
};

/// Configuration problems, or nothing. Codes: "bad_grid", "bad_levels", "bad_time_base", "bad_tile".
Expected<void> validateFusionConfig(const FusionConfig& config);

struct FusionStats {
  bool fullRecompute = false;
  std::size_t discs = 0;          // discs present over all steps
  std::size_t pairsTested = 0;    // candidate pairs from the spatial hash within reach
  std::size_t pairsPositive = 0;  // pairs scored > 0 (not those the model bounded below both maxima)
  std::size_t discsPainted = 0;
  std::size_t cellsVisited = 0;
  std::size_t tilesRecomputed = 0;
};

struct FusionResult {
  TimeBase time;
  ProbabilityGrid probability;            // p(M) of def. 3.5 per cell
  LevelGrid levels;                       // def. 3.6
  std::vector<double> sceneIndexPerStep;  // eq. (3.7) per step over the allowed pairs
  double sceneIndex = 0.0;                // max over the steps
  FusionStats stats;
};

/// The production fusion: sources (robots, humans) with predicted discs → the per-cell maximum over
/// pairs and steps of the pair score, its iso-levels and the scene index. Equal cell for cell to
/// referenceProbabilityGrid on the aligned sources. Pairs are found with a per-step uniform spatial
/// hash sized by the model's reach, each disc is painted once per step with the largest score of its
/// pairs, only over the cells of its bounding box. When the time base is unchanged since the last
/// fuse(), only the tiles an upserted or removed source can influence are recomputed.
/// Not thread-safe: one thread owns an engine (the service's fusion loop).
///
/// Typical cycle: upsert()/remove() as samples arrive, then fuse(now) → result().levels, encodeRle(
/// result().levels.level) and RegionExtractor::extract(result().levels) for the wire.
class FusionEngine {
 public:
  static Expected<FusionEngine> create(FusionConfig config, std::shared_ptr<const RiskModel> model);

  /// Adds or replaces the source with this id after validateSource (nowNs enables the timestamp check).
  Expected<void> upsert(Source source, std::optional<std::int64_t> nowNs = std::nullopt);
  /// Removes a source; false when the id is unknown.
  bool remove(std::string_view id);
  /// Removes every source whose t0 is older than cutoff_ns; returns how many.
  std::size_t removeOlderThan(std::int64_t cutoff_ns);
  [[nodiscard]] std::size_t sourceCount() const { return sources_.size(); }
  [[nodiscard]] bool contains(std::string_view id) const;

  /// Fuses every source onto the time base starting at tRefNs. The reference stays valid until the
  /// next call.
  const FusionResult& fuse(std::int64_t tRefNs);
  [[nodiscard]] const FusionResult& result() const { return result_; }
  /// Makes the next fuse() recompute everything (e.g. after the caller changed its mind about the map).
  void invalidate() { haveResult_ = false; }

  /// The sources as aligned for the last fuse(), in a fixed order (for the reference and tests).
  [[nodiscard]] std::vector<AlignedSource> alignedSources() const;
  [[nodiscard]] const FusionConfig& config() const { return config_; }
  [[nodiscard]] const RiskModel& model() const { return *model_; }

 private:
  struct Entry {
    Source source;
    AlignedSource aligned;  // on result_.time, valid when alignedFor == result_.time
    TimeBase alignedFor{};
    bool hasAligned = false;
  };
  FusionEngine(FusionConfig config, std::shared_ptr<const RiskModel> model);
  void noteChanged(const AlignedSource& aligned);
  void markDirtyTiles(double maxReach);
  void recompute(bool full);
  int windowLength() const;
  void scanWindow(int k0, int k1);
  void visitPair(std::uint32_t qa, std::uint32_t qb, int k);
  void scorePair(std::uint32_t qa, std::uint32_t qb, double d, double inter);
  void scoreDeferred();
  void rowSpans(const Disc& d, int rowLo, int rowHi);
  void writeSpan(int j, int a, int b, double p, std::uint8_t level);
  struct SourcePaint {
    std::uint32_t begin, end;  // its discs in paintList_
    int rowMin, rowMax;        // rows they may cover
  };
  void paintSourceRows(const SourcePaint& sp, int rowLo, int rowHi);
  void paint(bool full);

  FusionConfig config_;
  std::shared_ptr<const RiskModel> model_;
  std::unordered_map<std::string, Entry> sources_;
  FusionResult result_;
  bool haveResult_ = false;
  std::vector<Disc> pendingDirty_;        // old and new discs of sources changed since the last fuse
  std::vector<std::uint8_t> dirtyTiles_;  // tiles to recompute
  bool allDirty_ = false;
  int tileShift_ = 0;
  int tilesX_ = 0;
  int tilesY_ = 0;
  struct RowSpan {
    int j, a, b;  // row j, cells a..b inside the disc
  };
  // Scratch, kept between calls to avoid reallocation. Per-disc arrays are indexed source-major,
  // q = source · steps + step, over the sources in id order.
  std::vector<const Entry*> entries_;
  std::vector<const Disc*> disc_;  // nullptr when the source has no disc at that step
  struct PairDisc {                // what the pair search reads of a disc, together
    double x, y;                   // centre; NaN when absent, so no distance test passes
    double reach, r;               // RiskModel::reach, radius
    double tail;                   // RiskModel::tail
  };
  std::vector<PairDisc> qd_;
  std::vector<SourceKind> kind_;      // per source
  std::vector<double> discMax_;       // the largest score of the disc's pairs
  std::vector<std::uint8_t> active_;  // the disc touches a tile being recomputed
  std::vector<double> interSum_;      // Σ∩ per step, for the scene index
  std::vector<RowSpan> rowSpans_;
  std::vector<double> cellX_;           // cell-centre x of every column
  std::vector<double> cellY_;           // and y of every row
  std::vector<int> coverLo_, coverHi_;  // per row of the source being painted: cells it already holds
  struct PaintDisc {  // what painting reads of a disc (copied: the discs are scattered), its score and level
    double x, y, r, p;
    std::uint8_t level;
  };
  std::vector<PaintDisc> paintList_;  // per source, in decreasing score
  std::vector<SourcePaint> sourcePaints_;
  std::vector<std::uint32_t> bandStart_, bandFill_, bandItems_;  // sources by band of rows
  // The spatial hash over the sources' bounding circles of one window of steps.
  struct HashEntry {
    double x, y, reach;
    bool wide;  // reach above half a bucket: searched from its own side
  };
  std::vector<HashEntry> items_;  // per source present in the window
  std::vector<std::uint32_t> itemSource_;
  std::vector<HashEntry> sorted_;  // the items in bucket order
  std::vector<std::uint32_t> bucketStart_;
  std::vector<std::uint32_t> bucketFill_;
  std::vector<std::uint32_t> order_;
  std::vector<std::uint32_t> bucketOf_;
  std::vector<std::uint32_t> wide_;
  std::vector<double> reachScratch_;
  struct DeferredPair {
    std::uint32_t qa, qb;
    double d;
    std::uint8_t bin;  // of the gap relative to the tails
  };
  std::vector<DeferredPair> deferred_;  // near pairs that do not touch, scored after the touching ones
  static constexpr std::size_t kDeferredBins = 32;
  double binBound_[kDeferredBins] = {};  // RiskModel::tailRatioBound of each bin's smallest ratio
  std::vector<DeferredPair> deferredSorted_;
  std::vector<std::uint32_t> deferredStart_;
  double maxReachInHash_ = 0.0;
  double bucketSize_ = 1.0;
  int bucketsX_ = 0;
  int bucketsY_ = 0;
  void buildHash();
};

}  // namespace fleet::risk
