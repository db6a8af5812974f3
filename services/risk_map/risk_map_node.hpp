#pragma once

// The risk map service without its DDS wiring: takes PredictedDiscs samples, keeps the latest per
// source, fuses them at the configured rate and builds the RiskMap message.

#include <cstdint>
#include <map>
#include <memory>
#include <string>

#include "fleet/core/config.hpp"
#include "fleet/core/expected.hpp"
#include "fleet/risk/fusion_engine.hpp"
#include "fleet/messages/messages.hpp"

namespace fleet::riskmap {

struct Settings {
  risk::FusionConfig fusion;
  /// A site (or a scenario naming one): the grid then covers the site's map at `grid.resolution`
  /// (see gridOverSite), and grid.origin_x/origin_y/width/height must not be given.
  std::string site;
  std::string model = "gaussian";  // or "overlap" (the thesis ratio)
  double gaussianFloor = 1e-4;
  std::string gaussianEval = "fast";  // or "exact" (the series and quadrature; the fast path is within 1e-6)
  double rateHz = 10.0;
  double staleAfterS = 1.0;  // a source not heard from for this long is dropped
  bool regions = true;
  std::string clock = "wall";  // or "sim": time from the simulator's Clock topic
  bool lockstep = false;       // register with the simulator and acknowledge every step
};

/// Reads the settings; every problem is recorded in `cfg` (call cfg.finish() after).
Settings readSettings(Config& cfg);
/// The risk grid over a map's rectangle (origin, size) at `resolution`: every map cell covered.
risk::GridSpec gridOverSite(Vec2 origin, double widthM, double heightM, double resolution);

/// The pair model named in the settings.
std::shared_ptr<const risk::RiskModel> makeModel(const Settings& s);

/// A DDS sample as the risk library's source (float fields widened exactly; a disc with a non-zero
/// covariance is anisotropic, one with cov_xx = cov_xy = cov_yy = 0 isotropic with its sigma).
risk::Source toSource(const msg::PredictedDiscs& m);

/// The fused result as the wire message.
msg::RiskMap toMessage(const risk::FusionResult& r, std::int64_t stamp_ns, std::uint32_t sources,
                       bool regions);

class RiskMapNode {
 public:
  static Expected<RiskMapNode> create(const Settings& s);

  /// Validates and stores a sample (the latest per source wins). Bad samples are refused with the
  /// library's error code and message and leave the stored state untouched.
  Expected<void> accept(const msg::PredictedDiscs& m, std::int64_t now_ns);
  /// Drops stale sources, fuses at now_ns and returns the message to publish.
  msg::RiskMap fuse(std::int64_t now_ns);

  [[nodiscard]] std::size_t sources() const { return engine_.sourceCount(); }
  [[nodiscard]] std::uint64_t accepted() const { return accepted_; }
  [[nodiscard]] std::uint64_t rejected() const { return rejected_; }
  /// Rejected samples by the library's error code (e.g. "bad_covariance", "non_finite_covariance").
  [[nodiscard]] const std::map<std::string, std::uint64_t>& rejectedByReason() const { return rejectedBy_; }
  [[nodiscard]] std::uint64_t dropped_stale() const { return staleDropped_; }
  [[nodiscard]] const Settings& settings() const { return settings_; }
  [[nodiscard]] const risk::FusionEngine& engine() const { return engine_; }

 private:
  RiskMapNode(Settings s, risk::FusionEngine e) : settings_(std::move(s)), engine_(std::move(e)) {}
  Settings settings_;
  risk::FusionEngine engine_;
  std::map<std::string, std::int64_t> lastHeard_;
  std::uint64_t accepted_ = 0;
  std::uint64_t rejected_ = 0;
  std::map<std::string, std::uint64_t> rejectedBy_;
  std::uint64_t staleDropped_ = 0;
};

}  // namespace fleet::riskmap
