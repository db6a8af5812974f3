#include "fault_plan.hpp"

#include <gtest/gtest.h>

namespace fleet::ctl {
namespace {

TEST(FaultPlan, ParsesEveryKind) {
  auto f = parseFaults(
      {"kill-agent@30", "kill-agent@12.5s+4s:2", "kill-manager@60+3", "stall:r7@40+10", "drop-dds=0.05"});
  ASSERT_TRUE(f) << f.error().message;
  ASSERT_EQ(f->size(), 5u);
  EXPECT_EQ((*f)[0].kind, Fault::Kind::KillAgent);
  EXPECT_DOUBLE_EQ((*f)[0].atS, 30);
  EXPECT_DOUBLE_EQ((*f)[0].downS, 2);  // default restart delay
  EXPECT_EQ((*f)[0].agent, 0);
  EXPECT_DOUBLE_EQ((*f)[1].atS, 12.5);
  EXPECT_DOUBLE_EQ((*f)[1].downS, 4);
  EXPECT_EQ((*f)[1].agent, 2);
  EXPECT_EQ((*f)[2].kind, Fault::Kind::KillManager);
  EXPECT_DOUBLE_EQ((*f)[2].downS, 3);
  EXPECT_EQ((*f)[3].kind, Fault::Kind::StallRobot);
  EXPECT_EQ((*f)[3].robot, "r7");
  EXPECT_DOUBLE_EQ((*f)[3].downS, 10);
  EXPECT_EQ((*f)[4].kind, Fault::Kind::DropDds);
  EXPECT_DOUBLE_EQ(dropFraction(*f), 0.05);
}

TEST(FaultPlan, DescribeParsesBackToTheSameFault) {
  auto f = parseFaults({"kill-agent@12.5+4:2", "kill-manager@60", "stall:r7@40+10", "drop-dds=0.2"});
  ASSERT_TRUE(f);
  for (const auto& x : *f) {
    auto again = parseFaults({describe(x)});
    ASSERT_TRUE(again) << describe(x);
    EXPECT_EQ(describe((*again)[0]), describe(x));
    EXPECT_EQ((*again)[0].kind, x.kind);
    EXPECT_DOUBLE_EQ((*again)[0].atS, x.atS);
    EXPECT_DOUBLE_EQ((*again)[0].downS, x.downS);
  }
}

TEST(FaultPlan, HideLandmarksTakesSimulatedSecondsAndParsesBack) {
  auto f = parseFaults({"hide-landmarks@100+300", "hide-landmarks@500s+1200s"});
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ((*f)[0].kind, Fault::Kind::HideLandmarks);
  EXPECT_DOUBLE_EQ((*f)[0].atS, 100);
  EXPECT_DOUBLE_EQ((*f)[0].downS, 300);
  EXPECT_DOUBLE_EQ((*f)[1].downS, 1200) << "simulated seconds: longer than a process may be down";
  EXPECT_EQ(describe((*f)[0]), "hide-landmarks@100+300");
  auto bad = parseFaults({"hide-landmarks@100"});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("how many simulated seconds"), std::string::npos) << bad.error().message;
}

TEST(FaultPlan, KillTrafficNamesTheTrafficManagerAndParsesBack) {
  auto f = parseFaults({"kill-traffic@45", "kill-traffic@10+3", "kill-manager@5", "kill-agent@5"});
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ((*f)[0].kind, Fault::Kind::KillTraffic);
  EXPECT_DOUBLE_EQ((*f)[0].downS, 1);  // default restart delay
  EXPECT_EQ(describe((*f)[1]), "kill-traffic@10+3");
  EXPECT_EQ(killedService((*f)[0]), "traffic_manager");
  EXPECT_EQ(killedService((*f)[2]), "fleet_manager");
  EXPECT_EQ(killedService((*f)[3]), "") << "which agent process depends on the run";
  auto bad = parseFaults({"kill-traffic@3+0"});
  ASSERT_FALSE(bad);
  EXPECT_NE(bad.error().message.find("kill-traffic: expected a duration"), std::string::npos)
      << bad.error().message;
}

TEST(FaultPlan, CloseTakesAnAreaAndSimulatedSecondsAndParsesBack) {
  auto f = parseFaults({"close@40+60:10,4,14,4,14,6,-1.5,6"});
  ASSERT_TRUE(f) << f.error().message;
  EXPECT_EQ((*f)[0].kind, Fault::Kind::CloseArea);
  EXPECT_DOUBLE_EQ((*f)[0].atS, 40);
  EXPECT_DOUBLE_EQ((*f)[0].downS, 60);
  EXPECT_EQ((*f)[0].area, (std::vector<double>{10, 4, 14, 4, 14, 6, -1.5, 6}));
  EXPECT_EQ(describe((*f)[0]), "close@40+60:10,4,14,4,14,6,-1.5,6");
  EXPECT_EQ(killedService((*f)[0]), "");
  const std::pair<const char*, const char*> bad[] = {
      {"close@40+60", "the area's corners"},
      {"close@40:1,1,2,2,3,3", "expected '+D'"},
      {"close@40+60:1,1,2,2", "3 to 256 corners"},
      {"close@40+60:1,1,2,x,3,3", "got \"x\""},
  };
  for (const auto& [spec, expect] : bad) {
    auto e = parseFaults({spec});
    ASSERT_FALSE(e) << spec;
    EXPECT_NE(e.error().message.find(expect), std::string::npos) << spec << " -> " << e.error().message;
  }
}

TEST(FaultPlan, NoDropWithoutDropFault) {
  auto f = parseFaults({"kill-manager@1"});
  ASSERT_TRUE(f);
  EXPECT_EQ(dropFraction(*f), 0.0);
}

// Each bad spec gives an error naming the spec and what was expected.
TEST(FaultPlan, BadInputIsNamed) {
  struct Case {
    const char* spec;
    const char* expect;
  };
  const Case cases[] = {
      {"kill-agent", "expected kill-agent@T"},
      {"explode@3", "unknown fault \"explode\""},
      {"kill-agent@-3", "expected a time in simulated seconds"},
      {"kill-agent@abc", "got \"abc\""},
      {"kill-agent@3:x", "agent process index"},
      {"kill-manager@3+0", "duration in wall seconds"},
      {"kill-manager@3+1000", "(0, 600]"},
      {"stall:r1@5", "expected '+D'"},
      {"stall:@5+1", "expected a robot id"},
      {"drop-dds=0.9", "fraction in (0, 0.5]"},
      {"drop-dds=", "fraction"},
  };
  for (const auto& c : cases) {
    auto f = parseFaults({c.spec});
    ASSERT_FALSE(f) << c.spec;
    EXPECT_NE(f.error().message.find(c.expect), std::string::npos) << c.spec << " -> " << f.error().message;
    EXPECT_NE(f.error().message.find(c.spec), std::string::npos) << f.error().message;
  }
}

TEST(FaultPlan, EveryProblemIsListedAndDropOnlyOnce) {
  auto f = parseFaults({"kill-agent@x", "drop-dds=0.1", "drop-dds=0.2", "stall:r1@1"});
  ASSERT_FALSE(f);
  const auto& m = f.error().message;
  EXPECT_NE(m.find("kill-agent@x"), std::string::npos);
  EXPECT_NE(m.find("drop-dds given more than once"), std::string::npos);
  EXPECT_NE(m.find("stall:r1@1"), std::string::npos);
  EXPECT_EQ(m.find("\"drop-dds=0.1\""), std::string::npos);  // the first drop is fine
}

}  // namespace
}  // namespace fleet::ctl
