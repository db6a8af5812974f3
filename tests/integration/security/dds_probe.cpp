// Test peer for the DDS Security test: joins the domain with whatever CYCLONEDDS_URI says and
// either writes Task samples or counts the Task samples it receives.
//
//   dds_probe write SECONDS PREFIX    writes a Task "PREFIX-<n>" every 100 ms for SECONDS
//   dds_probe read SECONDS OUTFILE    counts Tasks for SECONDS by prefix, writes "PREFIX COUNT"
//                                     lines to OUTFILE
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
  std::fprintf(stderr, "dds_probe: unknown mode '%s'\n", mode.c_str());
  return 2;
}
