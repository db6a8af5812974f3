// The checks every service applies at its edge, one test per failure listed.

#include "fleet/validation/sample_checks.hpp"

#include <gtest/gtest.h>

#include <limits>

using namespace fleet;
using namespace fleet::validation;

namespace {

msg::TaskAssignment order() {
  msg::TaskAssignment a;
  a.robot_id = "r1";
  a.task_id = "t1";
  a.goals.push_back({{5.0, 1.0, 0.0}, "P-1", msg::GoalAction::Load, 1.0});
  return a;
}

msg::SensorFrame frame() {
  msg::SensorFrame f;
  f.robot_id = "r1";
  f.ds_left = 0.01;
  f.ds_right = 0.01;
  f.range_max = 8.0F;
  f.ranges = {1.0F, std::numeric_limits<float>::infinity()};  // nothing hit: allowed
  f.wheel_totals_valid = true;
  f.wheel_left_total = 12.5;
  f.wheel_right_total = 12.4;
  f.battery = 0.5F;
  return f;
}

std::string reasonOf(const std::optional<Rejection>& r) {
  return r ? r->reason : "accepted";
}

}  // namespace

TEST(SampleChecks, AssignmentNeedsGoalsForATaskAndNoneWithout) {
  EXPECT_FALSE(check(order()));
  auto a = order();
  a.goals.clear();
  EXPECT_EQ(reasonOf(check(a)), "structure");
  auto cancel = order();
  cancel.task_id.clear();
  EXPECT_EQ(reasonOf(check(cancel)), "structure") << "goals without a task";
  cancel.goals.clear();
  EXPECT_FALSE(check(cancel)) << "an empty order (cancel) is fine";
  auto far = order();
  far.goals[0].pose.x = 1e300;
  EXPECT_EQ(reasonOf(check(far)), "implausible");
  auto nan = order();
  nan.goals[0].duration_s = std::nan("");
  EXPECT_EQ(reasonOf(check(nan)), "non_finite");
  auto badAction = order();
  badAction.goals[0].action = static_cast<msg::GoalAction>(77);
  EXPECT_EQ(reasonOf(check(badAction)), "enum");
}

TEST(SampleChecks, SensorFrameWithAbsurdWheelTotalsIsRefused) {
  EXPECT_FALSE(check(frame()));
  for (double v : {1e308, -1e308, 2e9}) {
    auto f = frame();
    f.wheel_left_total = v;
    EXPECT_EQ(reasonOf(check(f)), "implausible") << v;
  }
  auto f = frame();
  f.wheel_right_total = std::numeric_limits<double>::infinity();
  EXPECT_EQ(reasonOf(check(f)), "non_finite");
  auto notValid = frame();
  notValid.wheel_totals_valid = false;
  notValid.wheel_left_total = 1e308;  // not claimed valid: not used, not judged
  EXPECT_FALSE(check(notValid));
  auto step = frame();
  step.ds_left = 1e6;
  EXPECT_EQ(reasonOf(check(step)), "implausible");
  auto id = frame();
  id.robot_id = "r 1";
  EXPECT_EQ(reasonOf(check(id)), "id");
}

TEST(SampleChecks, FreeTextIsRepairedAndCounted) {
  msg::TaskStatus s{"r1", "t1", 1, msg::TaskState::Failed, 0.0F, "bad \xFF\xFE byte", 0};
  EXPECT_EQ(reasonOf(check(s)), "utf8");
  Rejections counters;
  EXPECT_TRUE(admit(s, counters));
  EXPECT_EQ(s.error, "bad \xEF\xBF\xBD\xEF\xBF\xBD byte");
  EXPECT_EQ(counters.repairedCount("TaskStatus"), 1u);
  EXPECT_EQ(counters.total(), 0u);
  msg::TaskEvent e{"t1", msg::TaskState::Failed, "r1", "\xC0", 0, 1, ""};
  EXPECT_TRUE(admit(e, counters));
  EXPECT_EQ(e.reason, "\xEF\xBF\xBD");
}

TEST(SampleChecks, RefusedSamplesAreCountedByTopicAndReason) {
  Rejections counters;
  auto a = order();
  a.goals.clear();
  Rejection why;
  EXPECT_FALSE(admit(a, counters, &why));
  EXPECT_EQ(why.topic, "TaskAssignment");
  EXPECT_NE(why.detail.find("t1"), std::string::npos) << why.detail;
  auto f = frame();
  f.wheel_left_total = 1e308;
  EXPECT_FALSE(admit(f, counters));
  EXPECT_FALSE(admit(f, counters));
  EXPECT_EQ(counters.count("TaskAssignment", "structure"), 1u);
  EXPECT_EQ(counters.count("SensorFrame", "implausible"), 2u);
  EXPECT_EQ(counters.total(), 3u);
  const auto j = counters.toJson();
  EXPECT_EQ(j["rejected"]["SensorFrame"]["implausible"], 2);
  EXPECT_EQ(j["rejected_total"], 3);
}

TEST(SampleChecks, SequencesAreBounded) {
  msg::RiskMap m;
  m.resolution = 0.5;
  m.width = 10;
  m.height = 10;
  m.levels = 3;
  m.runs = {{0, 100}};
  EXPECT_FALSE(check(m));
  m.runs.assign(101, {0, 1});
  EXPECT_EQ(reasonOf(check(m)), "too_large") << "more runs than cells";
  m.runs = {{0, 100}};
  m.width = 1 << 20;
  m.height = 1 << 20;
  EXPECT_EQ(reasonOf(check(m)), "too_large");

  msg::GroundTruth g;
  g.bodies.assign(kMaxBodies, {"b", msg::SourceKind::Human, {1, 1, 0}, 0.0, 0.3});
  EXPECT_FALSE(check(g));
  g.bodies.push_back(g.bodies.back());
  EXPECT_EQ(reasonOf(check(g)), "too_large");
}

TEST(SampleChecks, RobotStateAndDiscsMustBeFiniteAndPlausible) {
  msg::RobotState s;
  s.robot_id = "r1";
  s.radius = 0.3F;
  EXPECT_FALSE(check(s));
  s.covariance[4] = std::nan("");
  EXPECT_EQ(reasonOf(check(s)), "non_finite");
  s.covariance[4] = 0;
  s.battery = 7.0F;
  EXPECT_EQ(reasonOf(check(s)), "implausible");
  s.battery = 0.5F;
  s.activity = msg::RobotActivity::Faulted;
  EXPECT_FALSE(check(s));
  s.activity = static_cast<msg::RobotActivity>(10);  // one past RA_FAULTED
  EXPECT_EQ(reasonOf(check(s)), "enum");

  msg::PredictedDiscs d;
  d.source_id = "r1";
  d.dt = 0.5F;
  d.discs = {{1, 1, 0.3F, 0.1F, 0, 0, 0}};
  EXPECT_FALSE(check(d));
  d.dt = 0;
  EXPECT_EQ(reasonOf(check(d)), "implausible");
}

TEST(SampleChecks, TaskRequestNeedsValidIds) {
  msg::Task t;
  t.task_id = "t1";
  t.request_id = "wms1-1";
  EXPECT_FALSE(check(t));
  t.request_id.clear();
  EXPECT_EQ(reasonOf(check(t)), "id");
  t.request_id = "wms1-1";
  t.pickup = "\xFF";
  EXPECT_EQ(reasonOf(check(t)), "utf8");
}

TEST(SampleChecks, RoadmapAndReleasesNameNodesThatExist) {
  msg::Roadmap m;
  m.nodes = {{0, 1.0, 1.0}, {1, 1.5, 1.0}, {2, 2.0, 1.0}};
  m.kinds = {0, 3, 1};
  m.open = {true, true, true};
  m.edges = {{0, 1, 0.6F, true}, {1, 2, 0.6F, true}};
  EXPECT_FALSE(check(m));
  auto renumbered = m;
  renumbered.nodes[1].node = 7;
  EXPECT_EQ(reasonOf(check(renumbered)), "structure") << "a node's id is its index";
  auto dangling = m;
  dangling.edges.push_back({2, 3, 0.5F, true});
  EXPECT_EQ(reasonOf(check(dangling)), "structure");
  auto kind = m;
  kind.kinds[2] = 9;
  EXPECT_EQ(reasonOf(check(kind)), "enum");
  auto short_ = m;
  short_.open.pop_back();
  EXPECT_EQ(reasonOf(check(short_)), "structure");
  auto far = m;
  far.nodes[0].x = 1e300;
  EXPECT_EQ(reasonOf(check(far)), "implausible");
  auto slow = m;
  slow.edges[0].duration_s = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(reasonOf(check(slow)), "non_finite");

  msg::TrafficRelease r;
  r.robot_id = "r1";
  r.base = {{0, 1.0, 1.0}, {1, 1.5, 1.0}};
  r.horizon = {{2, 2.0, 1.0}};
  EXPECT_FALSE(check(r));
  auto negative = r;
  negative.horizon[0].node = -4;
  EXPECT_EQ(reasonOf(check(negative)), "implausible");
  auto nan = r;
  nan.base[1].y = std::nan("");
  EXPECT_EQ(reasonOf(check(nan)), "non_finite");
  auto noId = r;
  noId.robot_id = "r 1";
  EXPECT_EQ(reasonOf(check(noId)), "id");
  auto longBase = r;
  longBase.base.assign(65, {0, 1.0, 1.0});
  EXPECT_EQ(reasonOf(check(longBase)), "too_large");
}

TEST(SampleChecks, PeopleSeenMustBeFiniteBoundedAndNamed) {
  msg::PeopleSeen p;
  p.robot_id = "r1";
  EXPECT_FALSE(check(p)) << "a robot that sees nobody says so";
  p.people = {{2.0F, 3.0F, 0.5F, -0.2F, 0.25F, true}, {4.0F, 1.0F, 0.0F, 0.0F, 0.3F, false}};
  EXPECT_FALSE(check(p));
  auto bad = [&](auto edit) {
    msg::PeopleSeen q = p;
    edit(q);
    return reasonOf(check(q));
  };
  EXPECT_EQ(bad([](auto& q) { q.people[1].x = std::numeric_limits<float>::quiet_NaN(); }), "non_finite");
  EXPECT_EQ(bad([](auto& q) { q.people[0].vy = std::numeric_limits<float>::infinity(); }), "non_finite");
  EXPECT_EQ(bad([](auto& q) { q.people[0].y = 5e6F; }), "implausible");
  EXPECT_EQ(bad([](auto& q) { q.people[0].vx = 1000.0F; }), "implausible");
  EXPECT_EQ(bad([](auto& q) { q.people[0].r = -0.25F; }), "implausible");
  EXPECT_EQ(bad([](auto& q) { q.people[0].r = 0.0F; }), "implausible");
  EXPECT_EQ(bad([](auto& q) { q.robot_id = "r 1"; }), "id");
  EXPECT_EQ(bad([](auto& q) { q.people.resize(msg::kMaxPeopleSeen + 1, q.people[0]); }), "too_large");
  EXPECT_EQ(bad([](auto& q) { q.people.resize(msg::kMaxPeopleSeen, q.people[0]); }), "accepted");
}
