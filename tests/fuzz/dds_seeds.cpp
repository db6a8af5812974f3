// Writes the seed corpus of fuzz_dds_sample: one or two plausible samples of every topic type,
// serialized by Cyclone as a writer would (dds_stream_write), each file prefixed with the byte
// fuzz_dds_sample reads (topic index, byte order, XCDR version). Run once after a change to
// idl/fleet.idl:  fuzz_dds_seeds tests/fuzz/corpus/dds_sample
// (build it with `cmake --build BUILD_FUZZ --target fuzz_dds_seeds`).

#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>

#include "dds/ddsi/ddsi_cdrstream.h"
#include "dds/ddsi/q_protocol.h"
#include "fleet/transport/dds.hpp"
#include "fleet/transport/traits.hpp"

namespace {

namespace msg = fleet::msg;
namespace transport = fleet::transport;

std::string outDir;

template <class M>
void seed(int topic, const M& m, const std::string& name) {
  using Traits = transport::Traits<M>;
  typename Traits::C c{};
  transport::Arena arena;
  Traits::toC(m, c, arena);
  for (const std::uint32_t xcdr : {CDR_ENC_VERSION_1, CDR_ENC_VERSION_2}) {
    dds_ostream_t os;
    dds_ostream_init(&os, 0, xcdr);
    dds_stream_write(&os, reinterpret_cast<const char*>(&c), Traits::descriptor()->m_ops);
    const char head = static_cast<char>(topic | (xcdr == CDR_ENC_VERSION_2 ? 0x40 : 0));
    std::ofstream f(outDir + "/" + name + (xcdr == CDR_ENC_VERSION_2 ? ".xcdr2" : ".xcdr1"),
                    std::ios::binary);
    f.put(head);
    f.write(reinterpret_cast<const char*>(os.m_buffer), os.m_index);
    dds_ostream_fini(&os);
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: fuzz_dds_seeds DIR\n");
    return 2;
  }
  outDir = argv[1];
  // Indices as in dds_sample.cpp's kTopics.
  seed(0,
       msg::Task{"T-1", "req-1", msg::TaskKind::Transport, "P-1", "D-1", "", "", 2'000'000'000, 1'000'000'000,
                 5, 0, 1000, false, msg::TaskControl::None},
       "task");
  seed(0,
       msg::Task{"T-2", "req-2", msg::TaskKind::Park, "", "", "PARK-1", "r-9", 0, 0, -5, 0, 0, true,
                 msg::TaskControl::Pause},
       "task_cancel");
  seed(1, msg::TaskAck{"req-1", "T-1", msg::AckResult::Stored, msg::TaskState::Queued, "stored", 5},
       "task_ack");
  seed(2, msg::TaskEvent{"T-1", msg::TaskState::Unloading, "r-7", "Kệ hàng Ω-7 → dock ✓", 99, 4, "D-3"},
       "task_event");
  msg::TaskAssignment a{"r-1", "T-1", 3, {}, false, 10};
  a.goals.push_back({{1.0, 2.0, 0.5}, "P-1", msg::GoalAction::Load, 2.0});
  a.goals.push_back({{5.0, 2.0, 1.5}, "D-1", msg::GoalAction::Unload, 1.0});
  seed(3, a, "task_assignment");
  seed(4, msg::TaskStatus{"r-1", "T-1", 3, msg::TaskState::EnRoute, 0.5f, "", 7}, "task_status");
  seed(5,
       msg::RobotState{"r-1",
                       5,
                       {1.5, 2.5, -3.0},
                       {1, 0, 0, 0, 1, 0, 0, 0, 1},
                       0.7,
                       -0.2,
                       msg::RobotMode::Moving,
                       0.8f,
                       "T-1",
                       0.3f},
       "robot_state");
  msg::PredictedDiscs d{"h-1", msg::SourceKind::Human, 100, 0.1f, {}};
  d.discs = {{1, 2, 0.3f, 0.05f, 0.01f, 0, 0.01f}, {1.1f, 2, 0.3f, 0.06f, 0.01f, 0.001f, 0.01f}};
  seed(6, d, "predicted_discs");
  msg::RiskMap r{1, -5, -6, 0.1, 20, 10, 10, 3.0f, 0.25f, 2, {{0, 150}, {3, 40}, {9, 10}}, {}};
  r.regions.push_back({3, {{0, 0}, {1, 0}, {1, 1}, {0, 1}}, {{{0.2, 0.2}, {0.4, 0.2}, {0.4, 0.4}}}});
  seed(7, r, "risk_map");
  msg::SensorFrame s{"r-1", 1,   2,  0.01, 0.02, -3.1f, 0.087f, 10.0f, {1.0f, 2.0f, 3.5f},
                     true,  0.3, {}, {},   0.9f, false};
  s.landmarks = {{4, 0.5f}};
  s.detections = {{msg::SourceKind::Human, 1.0f, -1.0f, 0.3f}};
  s.wheel_totals_valid = true;
  s.wheel_left_total = 12.5;
  s.wheel_right_total = 12.7;
  seed(8, s, "sensor_frame");
  seed(9, msg::VelocityCommand{"r-1", 0.5, -0.25, 77, 9}, "velocity_command");
  seed(10, msg::Clock{12, 1'200'000'000, 100'000'000, true}, "clock");
  seed(11, msg::StepDone{"agent-proc-1", 12}, "step_done");
  msg::GroundTruth g{5, 500, {}, {}};
  g.bodies = {{"r-1", msg::SourceKind::Robot, {1, 2, 0}, 0.5, 0.3},
              {"h-1", msg::SourceKind::Human, {3, 2, 1}, 1.0, 0.25}};
  g.contacts = {{"r-1", "h-1", 0.01}};
  seed(12, g, "ground_truth");
  msg::Roadmap m{"small-warehouse",    3, 7, {{0, 1.0, 1.0}, {1, 2.0, 1.0}}, {1, 0}, {true, false},
                 {{0, 1, 1.5f, true}}, 99};
  seed(13, m, "roadmap");
  msg::TrafficRelease rel;
  rel.robot_id = "r-1";
  rel.epoch = 3;
  rel.seq = 4;
  rel.base = {{0, 1.0, 1.0}, {1, 2.0, 1.0}};
  seed(14, rel, "traffic_release");
  msg::TrafficProgress p;
  p.robot_id = "r-1";
  p.epoch = 3;
  seed(15, p, "traffic_progress");
  msg::PeopleSeen people{
      "r-1", 7, {{1.0f, 2.0f, 0.5f, -0.5f, 0.25f, true}, {3.0f, 1.0f, 0.0f, 0.0f, 0.3f, false}}};
  seed(16, people, "people_seen");
  msg::TrafficClosure closure{"spill-1", true, {{1, 1}, {3, 1}, {3, 2}}, {4, 5}, {{5, 6}}, "a spill", 12};
  seed(17, closure, "traffic_closure");
  return 0;
}
