// Test peer: reads every topic type and writes each sample back on "<topic>_echo", until it has
// been idle for the given number of seconds (so it always ends by itself).

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "fleet/transport/dds.hpp"

using namespace fleet;
using namespace fleet::transport;

namespace {
// Reliable keep-all transient-local: nothing may be dropped, not even a sample written before the
// other side has discovered the writer (discovery is not symmetric in time).
const QosProfile kAll{true, true, 0, 0, 2000};

struct Echo {
  virtual ~Echo() = default;
  virtual std::size_t pump() = 0;
};

template <class T>
struct EchoOf : Echo {
  EchoOf(Participant& p, WaitSet& ws)
      : r(p, kAll, Traits<T>::kTopic), w(p, kAll, std::string(Traits<T>::kTopic) + "_echo") {
    ws.attach(r);
  }
  std::size_t pump() override {
    return r.takeEach([this](const T& m) { w.write(m); });
  }
  Reader<T> r;
  Writer<T> w;
};
}  // namespace

int main(int argc, char** argv) {
  const int idleSeconds = argc > 1 ? std::atoi(argv[1]) : 20;
  try {
    Participant p;
    WaitSet ws(p);
    std::vector<std::unique_ptr<Echo>> echoes;
    echoes.push_back(std::make_unique<EchoOf<msg::Task>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TaskAck>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TaskEvent>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TaskAssignment>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TaskStatus>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::RobotState>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::PredictedDiscs>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::RiskMap>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::SensorFrame>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::VelocityCommand>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::Clock>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::StepDone>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::GroundTruth>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::Roadmap>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TrafficRelease>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TrafficProgress>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::TrafficClosure>>(p, ws));
    echoes.push_back(std::make_unique<EchoOf<msg::PeopleSeen>>(p, ws));
    auto lastActivity = std::chrono::steady_clock::now();
    while (std::chrono::steady_clock::now() - lastActivity < std::chrono::seconds(idleSeconds)) {
      ws.wait(std::chrono::milliseconds(200));
      for (auto& e : echoes) {
        if (e->pump() > 0) {
          lastActivity = std::chrono::steady_clock::now();
        }
      }
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "echo_peer: %s\n", e.what());
    return 1;
  }
  return 0;
}
