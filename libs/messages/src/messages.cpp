#include "fleet/messages/messages.hpp"

#include <array>
#include <string_view>

namespace fleet::msg {
namespace {
constexpr std::array<std::string_view, 5> kKinds = {"transport", "goto", "charge", "park", "multistop"};
constexpr std::array<std::string_view, 7> kModes = {"idle",     "moving",  "waiting", "loading",
                                                    "charging", "blocked", "fault"};

template <class E, std::size_t N>
bool lookup(const std::array<std::string_view, N>& names, const std::string& name, E& out) {
  for (std::size_t i = 0; i < N; ++i) {
    if (names[i] == name) {
      out = static_cast<E>(i);
      return true;
    }
  }
  return false;
}
}  // namespace

const char* toString(TaskState s) {
  return taskStateName(s).data();  // the names are string literals: NUL-terminated
}
const char* toString(TaskKind k) {
  return kKinds.at(static_cast<std::size_t>(k)).data();
}
const char* toString(RobotMode m) {
  return kModes.at(static_cast<std::size_t>(m)).data();
}
RobotActivity activityOf(const RobotState& s) {
  return s.activity != RobotActivity::Unset ? s.activity
                                            : activityFromMode(toString(s.mode), !s.task_id.empty());
}
bool parse(const std::string& name, TaskState& out) {
  return lookup(kTaskStateNames, name, out);
}
bool parse(const std::string& name, TaskKind& out) {
  return lookup(kKinds, name, out);
}

}  // namespace fleet::msg
