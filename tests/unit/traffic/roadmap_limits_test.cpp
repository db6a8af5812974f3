// The roadmap's lattice and lookup grids are bounded whatever the site: a lattice of more than
// kMaxLatticePoints is refused (ConfigError naming the spacing and the map's size) before anything
// is allocated for it, and a large site with few nodes gets coarser buckets rather than a huge grid.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "fleet/core/config.hpp"
#include "fleet/site/site_loader.hpp"
#include "fleet/traffic/roadmap.hpp"

namespace fleet::traffic {
namespace {

using ::testing::HasSubstr;

// An open 2 km x 2 km floor at 1 m a cell (4 M cells: within the map limits), walled in.
site::Site openKilometres() {
  site::Site s;
  s.name = "open";
  s.map = planning::OccupancyGrid(2000, 2000, 1.0);
  for (int i = 0; i < 2000; ++i) {
    s.map.setBlocked({i, 0});
    s.map.setBlocked({i, 1999});
    s.map.setBlocked({0, i});
    s.map.setBlocked({1999, i});
  }
  site::completeSite(s);
  return s;
}

TEST(RoadmapLimits, ALatticeOverTheLimitIsRefusedBeforeItIsBuilt) {
  const site::Site s = openKilometres();
  RoadmapOptions o;
  o.spacing = 0.05;  // 40000 x 40000 points
  try {
    (void)buildRoadmap(s, o);
    FAIL() << "a lattice of 1.6e9 points was built";
  } catch (const ConfigError& e) {
    ASSERT_EQ(e.problems().size(), 1u);
    EXPECT_THAT(e.problems()[0],
                HasSubstr("roadmap: a lattice 0.05 m apart over the map's 2000 x 2000 m has"));
    EXPECT_THAT(e.problems()[0], HasSubstr("more than the limit of 4194304"));
  }
}

TEST(RoadmapLimits, NearestNodeWorksWithCoarseBucketsOnALargeSite) {
  // A corridor 1.9 km long: buckets of 1.86 m (1900 m / kMaxBucketsPerSide) rather than 1 m.
  site::Site s;
  s.name = "far";
  s.map = planning::OccupancyGrid(1900, 10, 1.0);
  for (int x = 0; x < 1900; ++x) {
    for (int y = 0; y < 10; ++y) {
      s.map.setBlocked({x, y}, x < 2 || x >= 1898 || y < 2 || y >= 8);
    }
  }
  site::completeSite(s);
  RoadmapOptions o;
  o.spacing = 1.0;
  const Roadmap r = buildRoadmap(s, o);
  ASSERT_GT(r.graph.size(), 0u);
  const NodeId west = r.nearest({5.0, 5.0});
  const NodeId east = r.nearest({1895.0, 5.0});
  ASSERT_NE(west, kNoNode);
  ASSERT_NE(east, kNoNode);
  EXPECT_LT(r.graph.position(west).x, 10.0);
  EXPECT_GT(r.graph.position(east).x, 1890.0);
}

}  // namespace
}  // namespace fleet::traffic
