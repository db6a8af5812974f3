#include "fleet/fleet/task_state.hpp"

#include <gtest/gtest.h>

#include <set>

#include "fleet/fleet/errors.hpp"

namespace fleet {
namespace {

TEST(TaskState, NamesRoundTrip) {
  std::set<std::string_view> names;
  for (auto s : kAllTaskStates) {
    EXPECT_EQ(parseTaskState(toString(s)), s);
    names.insert(toString(s));
  }
  EXPECT_EQ(names.size(), kAllTaskStates.size());
  for (auto k : kAllTaskKinds) {
    EXPECT_EQ(parseTaskKind(toString(k)), k);
  }
  EXPECT_EQ(toString(TaskState::EnRoute), "en_route");
  EXPECT_FALSE(parseTaskState("EnRoute"));
  EXPECT_FALSE(parseTaskState(""));
  EXPECT_FALSE(parseTaskKind("deliver"));
}

TEST(TaskState, RejectedIsTheAnswerToARefusalNeverAStoredState) {
  // One enum for the store, the wire and the API: its last value names a refused submission.
  EXPECT_EQ(toString(TaskState::Rejected), "rejected");
  EXPECT_EQ(kTaskStateNames.size(), kAllTaskStates.size() + 1);
  EXPECT_FALSE(parseTaskState("rejected")) << "no stored task is in it";
  EXPECT_FALSE(isWaiting(TaskState::Rejected));
  EXPECT_FALSE(isActive(TaskState::Rejected));
  for (auto s : kAllTaskStates) {
    EXPECT_FALSE(checkTransition(s, TaskState::Rejected)) << toString(s);
    EXPECT_FALSE(checkTransition(TaskState::Rejected, s)) << toString(s);
  }
}

TEST(TaskState, HappyPathsAreLegal) {
  using S = TaskState;
  const std::vector<S> transport = {S::Queued,     S::Assigned,  S::EnRoute, S::Loading,
                                    S::Delivering, S::Unloading, S::Done};
  for (std::size_t i = 0; i + 1 < transport.size(); ++i) {
    EXPECT_TRUE(checkTransition(transport[i], transport[i + 1], TaskKind::Transport)) << i;
  }
  for (auto k : {TaskKind::Goto, TaskKind::Charge, TaskKind::Park}) {
    EXPECT_TRUE(checkTransition(S::Queued, S::Assigned, k));
    EXPECT_TRUE(checkTransition(S::Assigned, S::EnRoute, k));
    EXPECT_TRUE(checkTransition(S::EnRoute, S::Done, k));
    EXPECT_FALSE(checkTransition(S::EnRoute, S::Loading, k));
  }
  EXPECT_FALSE(checkTransition(S::EnRoute, S::Done, TaskKind::Transport));
}

TEST(TaskState, ExactTransitionTable) {
  using S = TaskState;
  // The full relation, written out independently of the implementation's switch.
  const std::set<std::pair<S, S>> legal = {
      {S::Queued, S::Assigned},    {S::Queued, S::Failed},        {S::Queued, S::Cancelled},
      {S::Requeued, S::Queued},    {S::Requeued, S::Assigned},    {S::Requeued, S::Failed},
      {S::Requeued, S::Cancelled}, {S::Assigned, S::EnRoute},     {S::Assigned, S::Failed},
      {S::Assigned, S::Cancelled}, {S::Assigned, S::Requeued},    {S::EnRoute, S::Loading},
      {S::EnRoute, S::Done},       {S::EnRoute, S::Failed},       {S::EnRoute, S::Cancelled},
      {S::EnRoute, S::Requeued},   {S::Loading, S::Delivering},   {S::Loading, S::Failed},
      {S::Loading, S::Cancelled},  {S::Loading, S::Requeued},     {S::Delivering, S::Unloading},
      {S::Delivering, S::Failed},  {S::Delivering, S::Cancelled}, {S::Delivering, S::Requeued},
      {S::Unloading, S::Done},     {S::Unloading, S::Failed},     {S::Unloading, S::Cancelled},
      {S::Unloading, S::Requeued},
  };
  for (auto from : kAllTaskStates) {
    for (auto to : kAllTaskStates) {
      const bool expect = legal.contains({from, to});
      auto r = checkTransition(from, to);
      EXPECT_EQ(r.has_value(), expect) << toString(from) << " -> " << toString(to);
      if (!r) {
        EXPECT_EQ(r.error().code, errc::kIllegalTransition);
        EXPECT_NE(r.error().message.find(std::string(toString(from))), std::string::npos);
      }
    }
  }
}

TEST(TaskState, TerminalStatesHaveNoSuccessor) {
  for (auto from : {TaskState::Done, TaskState::Failed, TaskState::Cancelled}) {
    EXPECT_TRUE(isTerminal(from));
    for (auto to : kAllTaskStates) {
      EXPECT_FALSE(checkTransition(from, to));
    }
  }
  for (auto s : kAllTaskStates) {
    // Every state is exactly one of waiting, active, terminal.
    EXPECT_EQ(int(isTerminal(s)) + int(isActive(s)) + int(isWaiting(s)), 1) << toString(s);
  }
}

}  // namespace
}  // namespace fleet
