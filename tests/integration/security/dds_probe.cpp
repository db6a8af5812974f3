// Test peer for the DDS Security test: joins the domain with whatever CYCLONEDDS_URI says and
// either writes Task samples or counts the Task samples it receives.
//
//   dds_probe write SECONDS PREFIX    writes a Task "PREFIX-<n>" every 100 ms for SECONDS
//   dds_probe read SECONDS OUTFILE    counts Tasks for SECONDS by prefix, writes "PREFIX COUNT"
//                                     lines to OUTFILE
//   dds_probe speak SECONDS ROBOT IN  writes a RobotState and a TaskStatus of robot ROBOT every
//                                     100 ms, in partition robot/IN (a writer made by hand, as a
//                                     process speaking for another robot would)
//   dds_probe states SECONDS OUTFILE  reads RobotState and TaskStatus as the services do (robot/*,
//                                     the partition check), writes "state:ROBOT N", "status:ROBOT N"
//                                     and "foreign N" (samples dropped by the check) to OUTFILE
//   dds_probe command SECONDS ROBOT IN
//                                     writes a VelocityCommand (0.4 m/s ahead) for robot ROBOT
//                                     every 100 ms, in partition robot/IN (made by hand, likewise)
//
// Exit 0 when it ran, 3 when security refused its writer or reader, 4 when it refused the
// participant (e.g. no valid certificate), 2 on bad usage.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "fleet/transport/dds.hpp"

using namespace fleet;
using namespace std::chrono_literals;

int main(int argc, char** argv) {
  if (argc < 3) {
    std::fprintf(stderr, "usage: dds_probe write SECONDS PREFIX | read SECONDS OUTFILE\n");
    return 2;
  }
  const std::string mode = argv[1];
  const auto until = std::chrono::steady_clock::now() + std::chrono::seconds(std::atoi(argv[2]));
  std::optional<transport::Participant> p;
  try {
    p.emplace();
  } catch (const std::exception& e) {
    std::fprintf(stderr, "dds_probe: participant refused: %s\n", e.what());
    return 4;
  }
  if (mode == "write" && argc == 4) {
    std::optional<transport::Writer<msg::Task>> w;
    try {
      w.emplace(*p);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "dds_probe: writer refused: %s\n", e.what());
      return 3;
    }
    for (int k = 0; std::chrono::steady_clock::now() < until; ++k) {
      msg::Task t;
      t.task_id = std::string(argv[3]) + "-" + std::to_string(k);
      t.request_id = t.task_id;
      t.pickup = "P-1";
      t.dropoff = "D-1";
      w->write(t);
      std::this_thread::sleep_for(100ms);
    }
    return 0;
  }
  if (mode == "read" && argc == 4) {
    std::optional<transport::Reader<msg::Task>> r;
    try {
      r.emplace(*p);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "dds_probe: reader refused: %s\n", e.what());
      return 3;
    }
    std::map<std::string, std::size_t> got;
    while (std::chrono::steady_clock::now() < until) {
      for (const auto& t : r->take()) {
        ++got[t.task_id.substr(0, t.task_id.find('-'))];
      }
      std::this_thread::sleep_for(50ms);
    }
    std::ofstream out(argv[3]);
    for (const auto& [prefix, n] : got) {
      out << prefix << " " << n << "\n";
    }
    return 0;
  }
  if (mode == "speak" && argc == 5) {
    const std::string robot = argv[3];
    const std::vector<std::string> partition = {transport::robotPartition(argv[4])};
    dds_entity_t stateW = 0;
    dds_entity_t statusW = 0;
    try {
      using SW = transport::Traits<msg::RobotState>;
      using TW = transport::Traits<msg::TaskStatus>;
      stateW = transport::detail::createWriter(
          p->handle(), transport::detail::createTopic(*p, SW::descriptor(), SW::kTopic), SW::qos(),
          partition);
      statusW = transport::detail::createWriter(
          p->handle(), transport::detail::createTopic(*p, TW::descriptor(), TW::kTopic), TW::qos(),
          partition);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "dds_probe: writer refused: %s\n", e.what());
      return 3;
    }
    for (int k = 0; std::chrono::steady_clock::now() < until; ++k) {
      msg::RobotState st;
      st.robot_id = robot;
      st.stamp_ns = k;
      msg::TaskStatus ts;
      ts.robot_id = robot;
      ts.task_id = "t-" + std::to_string(k);
      ts.state = msg::TaskState::Done;
      transport::Arena arena;
      fleet_RobotState cs{};
      transport::Traits<msg::RobotState>::toC(st, cs, arena);
      transport::check(dds_write(stateW, &cs), "dds_write");
      fleet_TaskStatus ct{};
      transport::Traits<msg::TaskStatus>::toC(ts, ct, arena);
      transport::check(dds_write(statusW, &ct), "dds_write");
      std::this_thread::sleep_for(100ms);
    }
    return 0;
  }
  if (mode == "command" && argc == 5) {
    dds_entity_t w = 0;
    try {
      using CW = transport::Traits<msg::VelocityCommand>;
      w = transport::detail::createWriter(
          p->handle(), transport::detail::createTopic(*p, CW::descriptor(), CW::kTopic),
          transport::qos::command(false), {transport::robotPartition(argv[4])});
    } catch (const std::exception& e) {
      std::fprintf(stderr, "dds_probe: writer refused: %s\n", e.what());
      return 3;
    }
    for (std::uint32_t k = 0; std::chrono::steady_clock::now() < until; ++k) {
      const msg::VelocityCommand m{argv[3], 0.4, 0.0, 0, k};
      transport::Arena arena;
      fleet_VelocityCommand c{};
      transport::Traits<msg::VelocityCommand>::toC(m, c, arena);
      transport::check(dds_write(w, &c), "dds_write");
      std::this_thread::sleep_for(100ms);
    }
    return 0;
  }
  if (mode == "states" && argc == 4) {
    std::optional<transport::Reader<msg::RobotState>> states;
    std::optional<transport::Reader<msg::TaskStatus>> statuses;
    try {
      states.emplace(*p);
      statuses.emplace(*p);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "dds_probe: reader refused: %s\n", e.what());
      return 3;
    }
    std::map<std::string, std::size_t> got;
    while (std::chrono::steady_clock::now() < until) {
      for (const auto& m : states->take()) {
        ++got["state:" + m.robot_id];
      }
      for (const auto& m : statuses->take()) {
        ++got["status:" + m.robot_id];
      }
      std::this_thread::sleep_for(50ms);
    }
    got["foreign"] = states->foreign() + statuses->foreign();
    std::ofstream out(argv[3]);
    for (const auto& [key, n] : got) {
      out << key << " " << n << "\n";
    }
    return 0;
  }
  std::fprintf(stderr, "dds_probe: unknown mode '%s'\n", mode.c_str());
  return 2;
}
