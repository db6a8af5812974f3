// One-way latency (round trip / 2, as ddsperf reports it) and throughput of RobotState (~256 B)
// between two processes through our transport wrapper. The second process is this executable
// started with --pong or --sink. tests/bench/transport/run.sh runs ddsperf in the same run.

#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <csignal>
#include <cstring>
#include <memory>
#include <thread>
#include <vector>

#include "fleet/transport/dds.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace fleet::transport;
using namespace std::chrono_literals;
using Clk = std::chrono::steady_clock;

namespace {
// Children end on SIGTERM by leaving the loop, so their DDS participant is deleted and announced;
// a SIGKILLed reader would stay matched (and block reliable writers) until its lease expires.
std::atomic<bool> gStop{false};
extern "C" void onTerm(int) {
  gStop = true;
}

const QosProfile kPingQos{true, false, 1, 0, 1000};
const QosProfile kStreamQos{true, false, 0, 0, 5000};  // reliable keep-all: nothing may be lost

msg::RobotState sample(std::uint32_t i) {
  msg::RobotState s;
  s.robot_id = "robot-" + std::to_string(i % 16);
  s.pose = {1.0 * i, 2.0, 0.5};
  s.covariance = {0.01, 0, 0, 0, 0.01, 0, 0, 0, 0.001};
  s.v = 1.0;
  s.task_id = "task-0000000001";
  s.radius = 0.35f;
  return s;
}

/// The robots of sample(): RobotState is a per-robot topic, one writer per robot (made up front so
/// that the match is complete before timing starts).
std::vector<std::string> sampleRobots() {
  std::vector<std::string> ids;
  for (std::uint32_t i = 0; i < 16; ++i) {
    ids.push_back(sample(i).robot_id);
  }
  return ids;
}

template <class W, class R>
void waitMatched(const W& w, const R& r) {
  const auto end = Clk::now() + 20s;
  while ((w.matchedReaders() == 0 || r.matchedWriters() == 0) && Clk::now() < end) {
    std::this_thread::sleep_for(10ms);
  }
}

int runPong() {
  Participant p;
  Reader<msg::RobotState> in(p, kPingQos, "BenchPing");
  Writer<msg::RobotState> out(p, kPingQos, "BenchPong");
  out.forRobots(sampleRobots());
  auto last = Clk::now();
  while (!gStop && Clk::now() - last < 5s) {
    if (in.waitForData(100ms)) {
      for (const auto& m : in.take()) {
        out.write(m);
      }
      last = Clk::now();
    }
  }
  return 0;
}

// The same echo with the C API only (loaned sample written straight back): what Cyclone costs for
// this type without the wrapper, to split the gap to ddsperf into "type" and "wrapper".
int runPongRaw() {
  Participant p;
  Reader<msg::RobotState> in(p, kPingQos, "BenchPing");
  Writer<msg::RobotState> out(p, kPingQos, "BenchPong");
  out.forRobots(sampleRobots());
  auto last = Clk::now();
  while (!gStop && Clk::now() - last < 5s) {
    if (in.waitForData(100ms)) {
      void* samples[16] = {nullptr};
      dds_sample_info_t infos[16];
      const int n = dds_take(in.handle(), samples, infos, 16, 16);
      for (int i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          msg::RobotState key;
          key.robot_id = static_cast<const fleet_RobotState*>(samples[i])->robot_id;
          check(dds_write(out.handleFor(key), samples[i]), "dds_write");
        }
      }
      if (n > 0) {
        dds_return_loan(in.handle(), samples, n);
      }
      last = Clk::now();
    }
  }
  return 0;
}

// raw = count with dds_take loans and no conversion (to see what the wrapper's copy costs).
int runSink(bool raw) {
  Participant p;
  Reader<msg::RobotState> in(p, kStreamQos, "BenchStream");
  Reader<msg::StepDone> ctl(p, kPingQos, "BenchCtl");
  Writer<msg::StepDone> reply(p, kPingQos, "BenchReply");
  std::int64_t count = 0;
  auto last = Clk::now();
  while (!gStop && Clk::now() - last < 10s) {
    if (in.waitForData(20ms)) {
      if (raw) {
        dds_sample_info_t infos[256];
        while (true) {
          void* samples[256] = {nullptr};  // null first entry: ask for a loan every time
          const int n = dds_take(in.handle(), samples, infos, 256, 256);
          if (n <= 0) {
            break;
          }
          count += n;
          dds_return_loan(in.handle(), samples, n);
        }
      } else {
        count += static_cast<std::int64_t>(in.take().size());
      }
      last = Clk::now();
    }
    for (const auto& c : ctl.take()) {
      // Drain what is still in flight before answering.
      const auto settle = Clk::now() + 2s;
      while (count < c.step && Clk::now() < settle) {
        in.waitForData(20ms);
        count += static_cast<std::int64_t>(in.take().size());
      }
      reply.write({"sink", count});
      count = 0;
      last = Clk::now();
    }
  }
  return 0;
}

std::string self;

// Arg 0: through the wrapper on both sides; 1: the C API on both sides (same type, same QoS).
void BM_PingPongOneWay(benchmark::State& state) {
  const bool raw = state.range(0) != 0;
  test::ChildProcess pong(self, {raw ? "--pong-raw" : "--pong"});
  Participant p;
  Writer<msg::RobotState> out(p, kPingQos, "BenchPing");
  out.forRobots(sampleRobots());
  Reader<msg::RobotState> in(p, kPingQos, "BenchPong");
  waitMatched(out, in);
  fleet_RobotState c{};
  Arena arena;
  const auto rawSample = sample(1);
  Traits<msg::RobotState>::toC(rawSample, c, arena);
  std::vector<msg::RobotState> pings;
  for (std::uint32_t k = 0; k < 16; ++k) {
    pings.push_back(sample(k));
  }
  // False when no echo came back within 5 s (the pong process died or lost the match): the bench
  // reports an error and ends instead of waiting for ever.
  auto exchange = [&](std::uint32_t k) {
    const auto giveUp = Clk::now() + 5s;
    if (!raw) {
      out.write(pings[k % 16]);
      while (Clk::now() < giveUp) {
        in.waitForData(100ms);
        if (!in.take().empty()) {
          return true;
        }
      }
      return false;
    }
    check(dds_write(out.handleFor(rawSample), &c), "dds_write");
    while (Clk::now() < giveUp) {
      in.waitForData(100ms);
      void* samples[4] = {nullptr};
      dds_sample_info_t infos[4];
      const int n = dds_take(in.handle(), samples, infos, 4, 4);
      if (n > 0) {
        dds_return_loan(in.handle(), samples, n);
        return true;
      }
    }
    return false;
  };
  std::vector<double> oneWayUs;
  std::uint32_t i = 0;
  for (int warm = 0; warm < 200; ++warm) {
    if (!exchange(i++)) {
      state.SkipWithError("no echo from the pong process within 5 s (warm-up)");
      return;
    }
  }
  for (auto _ : state) {
    const auto t0 = Clk::now();
    if (!exchange(i++)) {
      state.SkipWithError("no echo from the pong process within 5 s");
      break;
    }
    oneWayUs.push_back(std::chrono::duration<double, std::micro>(Clk::now() - t0).count() / 2);
  }
  if (oneWayUs.empty()) {
    return;
  }
  pong.kill(SIGTERM);
  (void)pong.wait(10s);
  std::sort(oneWayUs.begin(), oneWayUs.end());
  auto pct = [&](double q) {
    return oneWayUs[static_cast<std::size_t>(q * static_cast<double>(oneWayUs.size() - 1))];
  };
  state.counters["p50_us"] = pct(0.5);
  state.counters["p90_us"] = pct(0.9);
  state.counters["p99_us"] = pct(0.99);
  state.counters["max_us"] = oneWayUs.back();
}

// Args: samples per burst, raw sink (no conversion), write batching (queue() the burst, one flush()).
void BM_Throughput(benchmark::State& state) {
  const bool batching = state.range(2) != 0;
  // Write batching is a per-process domain setting: the batched runs use a domain of their own.
  const int domain = domainFromEnvironment() + (batching ? 1 : 0);
  test::ChildProcess sink(self, {state.range(1) != 0 ? "--sink-raw" : "--sink"},
                          {{"FLEET_DDS_DOMAIN", std::to_string(domain)}});
  Participant p(domain, ParticipantOptions{.writeBatching = batching});
  Writer<msg::RobotState> out(p, kStreamQos, "BenchStream");
  out.forRobots(sampleRobots());
  Writer<msg::StepDone> ctl(p, kPingQos, "BenchCtl");
  Reader<msg::StepDone> reply(p, kPingQos, "BenchReply");
  waitMatched(out, reply);
  waitMatched(ctl, reply);
  std::vector<msg::RobotState> samples;
  for (std::uint32_t i = 0; i < 16; ++i) {
    samples.push_back(sample(i));
  }
  std::int64_t written = 0;
  std::int64_t received = 0;
  double seconds = 0;
  for (auto _ : state) {
    const std::int64_t n = state.range(0);
    const auto t0 = Clk::now();
    for (std::int64_t k = 0; k < n; ++k) {
      out.queue(samples[static_cast<std::size_t>(k % 16)]);
    }
    out.flush();
    ctl.write({"bench", n});
    std::int64_t got = -1;
    const auto giveUp = Clk::now() + 30s;
    while (got < 0 && Clk::now() < giveUp) {
      reply.waitForData(100ms);
      for (const auto& r : reply.take()) {
        got = r.step;
      }
    }
    if (got < 0) {
      state.SkipWithError("no count from the sink process within 30 s");
      break;
    }
    seconds += std::chrono::duration<double>(Clk::now() - t0).count();
    written += n;
    received += got;
  }
  sink.kill(SIGTERM);
  (void)sink.wait(10s);
  if (seconds <= 0.0) {
    return;
  }
  state.counters["samples_per_s"] = static_cast<double>(received) / seconds;
  state.counters["lost"] = static_cast<double>(written - received);
  state.counters["MB_per_s"] = static_cast<double>(received) * 256.0 / seconds / 1e6;
}

// Cost of one write through the wrapper vs the same sample written with the raw C API (one local
// reader matched, so the sample is really serialized and delivered): the wrapper's own overhead.
void BM_WriteWrapper(benchmark::State& state) {
  Participant p;
  Writer<msg::RobotState> w(p, kStreamQos, "BenchLocal");
  w.forRobots(sampleRobots());
  Reader<msg::RobotState> r(p, kStreamQos, "BenchLocal");
  const auto s = sample(1);
  std::int64_t n = 0;
  for (auto _ : state) {
    w.write(s);
    if (++n % 256 == 0) {
      state.PauseTiming();
      (void)r.take();
      state.ResumeTiming();
    }
  }
}

void BM_WriteRawC(benchmark::State& state) {
  Participant p;
  Writer<msg::RobotState> w(p, kStreamQos, "BenchLocal");
  w.forRobots(sampleRobots());
  Reader<msg::RobotState> r(p, kStreamQos, "BenchLocal");
  fleet_RobotState c{};
  Arena arena;
  Traits<msg::RobotState>::toC(sample(1), c, arena);
  std::int64_t n = 0;
  for (auto _ : state) {
    check(dds_write(w.handleFor(sample(1)), &c), "dds_write");
    if (++n % 256 == 0) {
      state.PauseTiming();
      (void)r.take();
      state.ResumeTiming();
    }
  }
}

BENCHMARK(BM_WriteWrapper)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_WriteRawC)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PingPongOneWay)->Arg(0)->Arg(1)->Iterations(20000)->Unit(benchmark::kMicrosecond)->UseRealTime();
BENCHMARK(BM_Throughput)
    ->Args({200000, 0, 0})
    ->Args({200000, 1, 0})
    ->Args({200000, 0, 1})
    ->Args({200000, 1, 1})
    ->Iterations(3)
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
}  // namespace

int main(int argc, char** argv) {
  std::signal(SIGTERM, onTerm);
  if (argc > 1 && std::strcmp(argv[1], "--pong") == 0) {
    return runPong();
  }
  if (argc > 1 && std::strcmp(argv[1], "--pong-raw") == 0) {
    return runPongRaw();
  }
  if (argc > 1 && std::strcmp(argv[1], "--sink") == 0) {
    return runSink(false);
  }
  if (argc > 1 && std::strcmp(argv[1], "--sink-raw") == 0) {
    return runSink(true);
  }
  char buf[4096];
  const ssize_t n = readlink("/proc/self/exe", buf, sizeof(buf) - 1);
  self = std::string(buf, n > 0 ? static_cast<std::size_t>(n) : 0);
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
