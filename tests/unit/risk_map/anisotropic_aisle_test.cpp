// A robot driving fast along an aisle, its predicted discs made by the agent from its EKF covariance,
// fused by the risk map service with the anisotropic model and, for comparison, with each disc's
// isotropic σ (√λmax, what a reader that knows only σ uses).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "disc_prediction.hpp"
#include "risk_map_node.hpp"

using namespace fleet;

namespace {

constexpr std::int64_t kNow = 1'000'000'000'000;
constexpr double kY = 5.0;       // aisle centre line
constexpr double kStartX = 2.0;  // robot at t0
constexpr double kEndX = 6.5;    // after 3 s at 1.5 m/s

riskmap::Settings aisleSettings() {
  auto cfg = Config::fromText(R"({"grid": {"width": 160, "height": 100, "resolution": 0.1}})", "t");
  auto s = riskmap::readSettings(cfg);
  cfg.finish();
  return s;
}

msg::PredictedDiscs robot(bool anisotropic) {
  Eigen::Matrix3d P = Eigen::Matrix3d::Zero();
  P.diagonal() << 0.02 * 0.02, 0.02 * 0.02, 0.01 * 0.01;
  agent::DiscPredictionParams p;
  p.radius = 0.3;
  msg::PredictedDiscs m{"r1", msg::SourceKind::Robot, kNow, static_cast<float>(p.dt), {}};
  m.discs = agent::predictDiscs({kStartX, kY, 0.0}, P, 1.5, 0.0, p);
  if (!anisotropic) {
    for (auto& d : m.discs) {
      d.cov_xx = d.cov_xy = d.cov_yy = 0.0f;
    }
  }
  return m;
}

// Static probes (people standing still, certain positions) on a lattice around the aisle: each one's
// painted probability is the model's P(robot hits it) somewhere over the horizon. Human–human pairs are
// not fused, so the probes do not see each other.
struct Probe {
  double x, y;
};

std::vector<Probe> probes() {
  std::vector<Probe> out;
  for (int i = 0; i <= 52; ++i) {
    for (int j = -16; j <= 16; ++j) {
      out.push_back({1.0 + 0.25 * i, kY + 0.25 * j});
    }
  }
  return out;
}

struct Extent {
  double along = 0.0;    // m beyond the robot's last predicted rim, on the aisle's centre line
  double across = 0.0;   // m from the centre line, beside the predicted path
  double pAhead = 0.0;   // at 1 m beyond the last rim
  double pBeside = 0.0;  // 1 m beside the path's middle
};

Extent riskExtent(bool anisotropic, double threshold) {
  auto node = riskmap::RiskMapNode::create(aisleSettings());
  EXPECT_TRUE(node);
  EXPECT_TRUE(node->accept(robot(anisotropic), kNow));
  const auto ps = probes();
  for (std::size_t n = 0; n < ps.size(); ++n) {
    msg::PredictedDiscs h{"p" + std::to_string(n), msg::SourceKind::Human, kNow, 0.1f, {}};
    h.discs.push_back({static_cast<float>(ps[n].x), static_cast<float>(ps[n].y), 0.1f, 0.0f});
    EXPECT_TRUE(node->accept(h, kNow));
  }
  node->fuse(kNow);
  const auto& grid = node->engine().result().probability;
  auto pAt = [&](double x, double y) {
    const auto c = grid.spec.cellOf(x, y);
    return c ? grid.p[grid.spec.index(c->first, c->second)] : 0.0;
  };
  Extent e;
  const double rim = kEndX + 0.3;
  for (const auto& p : ps) {
    const double v = pAt(p.x, p.y);
    // Probes the robot's own painted discs cover are skipped: their cells carry the robot's maximum.
    if (std::abs(p.y - kY) < 1e-9 && p.x > rim + 0.1 && v >= threshold) {
      e.along = std::max(e.along, p.x - rim);
    }
    if (p.x > kStartX + 0.5 && p.x < kEndX - 0.5 && std::abs(p.y - kY) > 0.45 && v >= threshold) {
      e.across = std::max(e.across, std::abs(p.y - kY));
    }
  }
  e.pAhead = pAt(7.75, kY);  // the probe 0.95 m beyond the last rim
  e.pBeside = pAt(0.5 * (kStartX + kEndX) + 0.25, kY + 1.0);
  return e;
}

TEST(AnisotropicAisle, RiskIsStretchedAlongTheAisleAndNarrowerAcross) {
  const double threshold = 0.01;
  const Extent iso = riskExtent(false, threshold);
  const Extent aniso = riskExtent(true, threshold);
  // Isotropic: the same σ in every direction reaches as far across the aisle as along it.
  EXPECT_GT(iso.across, 1.0);
  // Anisotropic: the along-track σ (which √λmax equals) keeps the reach ahead, while across the aisle
  // the risk ends within the EKF's and the isotropic growth's few decimetres.
  EXPECT_GE(aniso.along, iso.along - 0.25);
  EXPECT_GT(aniso.along, 0.5);
  EXPECT_LT(aniso.across, 0.6 * iso.across);
  EXPECT_GT(aniso.along / std::max(aniso.across, 0.25), 1.5 * iso.along / iso.across);
  EXPECT_GT(aniso.pAhead, 10.0 * aniso.pBeside);
  EXPECT_LT(aniso.pBeside, 0.1 * iso.pBeside);
  RecordProperty("iso_along_m", std::to_string(iso.along));
  RecordProperty("iso_across_m", std::to_string(iso.across));
  RecordProperty("aniso_along_m", std::to_string(aniso.along));
  RecordProperty("aniso_across_m", std::to_string(aniso.across));
  std::printf("p >= %.2f: isotropic along %.2f m across %.2f m; anisotropic along %.2f m across %.2f m\n",
              threshold, iso.along, iso.across, aniso.along, aniso.across);
  std::printf("p ahead / beside: isotropic %.3g / %.3g, anisotropic %.3g / %.3g\n", iso.pAhead, iso.pBeside,
              aniso.pAhead, aniso.pBeside);
}

TEST(AnisotropicAisle, BadCovariancesAreDroppedCountedByReasonAndTheRestIsFused) {
  auto node = riskmap::RiskMapNode::create(aisleSettings());
  ASSERT_TRUE(node);
  ASSERT_TRUE(node->accept(robot(true), kNow));
  auto indefinite = robot(true);
  indefinite.source_id = "r2";
  indefinite.discs[3].cov_xy = 10.0f;
  auto nan = robot(true);
  nan.source_id = "r3";
  nan.discs[1].cov_yy = std::numeric_limits<float>::quiet_NaN();
  auto negative = robot(true);
  negative.source_id = "r4";
  negative.discs[0].cov_xx = -0.01f;
  const auto e1 = node->accept(indefinite, kNow);
  ASSERT_FALSE(e1);
  EXPECT_EQ(e1.error().code, "bad_covariance");
  EXPECT_NE(e1.error().message.find("disc 3"), std::string::npos);
  EXPECT_FALSE(node->accept(nan, kNow));
  EXPECT_FALSE(node->accept(negative, kNow));
  EXPECT_EQ(node->rejected(), 3u);
  EXPECT_EQ(node->rejectedByReason().at("bad_covariance"), 2u);
  EXPECT_EQ(node->rejectedByReason().at("non_finite_covariance"), 1u);
  // The valid robot is still fused, with a partner: the service runs on what is valid.
  ASSERT_TRUE(node->accept({"h1", msg::SourceKind::Human, kNow, 0.1f, {{7.2f, 5.0f, 0.3f, 0.1f}}}, kNow));
  const auto m = node->fuse(kNow);
  EXPECT_EQ(m.sources, 2u);
  EXPECT_GT(node->engine().result().stats.pairsPositive, 0u);
}

}  // namespace
