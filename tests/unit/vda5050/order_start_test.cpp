#include "fleet/vda5050/order_start.hpp"

#include <gtest/gtest.h>

namespace fleet::vda5050 {
namespace {

ReleaseInput release(std::vector<int> base) {
  ReleaseInput r;
  for (int n : base) {
    r.base.push_back({n, static_cast<double>(n), 0.0});
  }
  return r;
}

std::vector<int> nodes(const ReleaseInput& r) {
  std::vector<int> out;
  for (const auto& n : r.base) {
    out.push_back(n.node);
  }
  return out;
}

KnownRoadmap line() {  // 1144 - 1145 - 1146 - 1147, both ways
  KnownRoadmap m;
  for (int n = 1144; n <= 1147; ++n) {
    m.addNode({n, static_cast<double>(n), 0.0});
    if (n > 1144) {
      m.addEdge(n - 1, n);
      m.addEdge(n, n - 1);
    }
  }
  return m;
}

TEST(Vda5050OrderStart, DropsTheNodesOfTheReleaseTheVehicleHasPassed) {
  const auto r = startAtVehicle(release({1144, 1145, 1146}), "n1145", line());
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(nodes(*r), (std::vector<int>{1145, 1146}));
}

TEST(Vda5050OrderStart, PutsTheVehiclesLastNodeInFrontWhenTheReleaseBeginsAtANeighbour) {
  // The traffic layer has the vehicle at n1146, the vehicle's own last node is n1145.
  const auto r = startAtVehicle(release({1146, 1147}), "n1145", line());
  ASSERT_TRUE(r) << r.error().message;
  EXPECT_EQ(nodes(*r), (std::vector<int>{1145, 1146, 1147}));
  EXPECT_DOUBLE_EQ(r->base.front().x, 1145.0) << "the node's position comes from the roadmap";
}

TEST(Vda5050OrderStart, RefusesWhenTheVehiclesLastNodeIsNotJoinedToTheRelease) {
  auto m = line();
  m.addNode({2000, 50.0, 50.0});
  const auto far = startAtVehicle(release({1146, 1147}), "n1144", m);
  ASSERT_FALSE(far);
  EXPECT_NE(far.error().message.find("n1144"), std::string::npos) << far.error().message;
  EXPECT_NE(far.error().message.find("n1146"), std::string::npos) << far.error().message;
  EXPECT_FALSE(startAtVehicle(release({1146}), "n2000", m));
  EXPECT_FALSE(startAtVehicle(release({1146}), "n9999", m)) << "a node of unknown position";
  EXPECT_FALSE(startAtVehicle(release({1146}), "dock-3", m)) << "a node that is not ours";
}

TEST(Vda5050OrderStart, AOneWayEdgeCountsOnlyInItsDirection) {
  KnownRoadmap m;
  m.addNode({1, 1.0, 0.0});
  m.addNode({2, 2.0, 0.0});
  m.addEdge(2, 1);
  EXPECT_FALSE(startAtVehicle(release({2}), "n1", m));
  EXPECT_TRUE(startAtVehicle(release({1}), "n2", m));
}

TEST(Vda5050OrderStart, AVehicleWithoutALastNodeTakesTheReleaseAsItIs) {
  const auto r = startAtVehicle(release({1146, 1147}), "", KnownRoadmap{});
  ASSERT_TRUE(r);
  EXPECT_EQ(nodes(*r), (std::vector<int>{1146, 1147}));
  EXPECT_FALSE(startAtVehicle(ReleaseInput{}, "n1", line())) << "an empty release";
}

}  // namespace
}  // namespace fleet::vda5050
