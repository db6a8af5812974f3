#pragma once

// RAII over the Cyclone DDS C API. Every failed call throws DdsError naming the call.

#include <dds/dds.h>

#include <chrono>
#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "fleet/transport/errors.hpp"
#include "fleet/transport/robot_partition.hpp"
#include "fleet/transport/traits.hpp"
#include "fleet/transport/writer_partitions.hpp"

namespace fleet::transport {

/// The loopback-only configuration used when CYCLONEDDS_URI is unset: interface lo, multicast
/// off, unicast discovery with peer 127.0.0.1, room for 200 participants on the host.
/// Lost packets are repaired with retransmits as large as first transmissions and heartbeats at
/// least once a second. `writeBatch` adds Cyclone's Internal/WriteBatch (see ParticipantOptions);
/// `lossPerMille` drops that share of outgoing packets (Internal/Test/XmitLossiness: fault tests).
std::string loopbackConfig(bool writeBatch = false, int lossPerMille = 0);

/// Domain id from FLEET_DDS_DOMAIN (0..229), else 0. Tests set it to keep parallel runs apart.
int domainFromEnvironment();

/// An owned DDS entity handle; deleting it deletes its children.
class Entity {
 public:
  Entity() = default;
  explicit Entity(dds_entity_t h) : h_(h) {}
  Entity(const Entity&) = delete;
  Entity& operator=(const Entity&) = delete;
  Entity(Entity&& o) noexcept : h_(o.h_) { o.h_ = 0; }
  Entity& operator=(Entity&& o) noexcept;
  ~Entity();
  [[nodiscard]] dds_entity_t handle() const { return h_; }

 private:
  dds_entity_t h_ = 0;
};

struct ParticipantOptions {
  /// Writers pack samples into shared datagrams and send them when a datagram is full or on
  /// Writer::flush() (Writer::write() flushes by itself; Writer::queue() does not). For processes
  /// that publish bursts of small samples: one datagram per ~50 RobotStates instead of one each.
  /// It is a property of the process's domain (Cyclone's Internal/WriteBatch), so every
  /// participant of the process on that domain must ask for the same setting.
  bool writeBatching = false;
};

class Participant {
 public:
  /// Joins `domain`; when CYCLONEDDS_URI is unset the domain is first created with loopbackConfig().
  /// Throws DdsError (PRECONDITION_NOT_MET) when the process already joined `domain` with a
  /// different writeBatching setting.
  explicit Participant(int domain = domainFromEnvironment(), ParticipantOptions options = {});
  explicit Participant(ParticipantOptions options) : Participant(domainFromEnvironment(), options) {}
  [[nodiscard]] dds_entity_t handle() const { return e_.handle(); }
  [[nodiscard]] int domain() const { return domain_; }
  [[nodiscard]] bool writeBatching() const { return options_.writeBatching; }

 private:
  int domain_;
  ParticipantOptions options_;
  Entity e_;
};

namespace detail {
dds_entity_t createTopic(const Participant& p, const dds_topic_descriptor_t* desc, const std::string& name);
/// `partitions` empty: the default partition.
dds_entity_t createWriter(dds_entity_t participant, dds_entity_t topic, const QosProfile& q,
                          const std::vector<std::string>& partitions = {});
dds_entity_t createReader(const Participant& p, dds_entity_t topic, const QosProfile& q,
                          const std::vector<std::string>& partitions = {},
                          const dds_listener_t* listener = nullptr);
std::uint32_t matched(dds_entity_t e, bool publication);
}  // namespace detail

/// Writes one topic. On a per-robot topic (robot_partition.hpp) it is one DDS writer per robot, each
/// in the robot's partition, made by forRobots() or at the robot's first sample.
template <class T>
class Writer {
 public:
  using Tr = Traits<T>;
  static constexpr bool kPerRobot = RobotOf<T>::kPerRobot;
  explicit Writer(const Participant& p, std::optional<QosProfile> q = std::nullopt,
                  const std::string& topic = Tr::kTopic)
      : participant_(p.handle()),
        topic_(detail::createTopic(p, Tr::descriptor(), topic)),
        qos_(q.value_or(Tr::qos())),
        w_(kPerRobot ? 0 : detail::createWriter(participant_, topic_, qos_)),
        batching_(p.writeBatching()) {}

  /// Per-robot topics: makes the writers of these robots now (at start-up, so that readers have
  /// matched them before the first sample). Under DDS Security this throws DdsError for a robot
  /// whose partition the process's permissions do not grant.
  Writer& forRobots(const std::vector<std::string>& robots) {
    if constexpr (kPerRobot) {
      for (const auto& r : robots) {
        writerOf(r);
      }
    }
    return *this;
  }

  /// Copies `m` into a C sample and writes it; it is on its way when this returns (also on a
  /// write-batching participant). Throws MessageError (bounds) or DdsError.
  void write(const T& m) {
    const dds_entity_t w = put(m);
    if (batching_) {
      dds_write_flush(w);
    }
  }
  /// Like write(), but on a write-batching participant the sample may wait in the writer's
  /// datagram until it is full or flush() is called: write a burst with queue(), then flush().
  void queue(const T& m) { put(m); }
  /// Sends what queue() left in the writers' datagrams (nothing to do without write batching).
  /// Batches are per DDS writer: on a per-robot topic only one robot's samples share a datagram.
  void flush() {
    if constexpr (kPerRobot) {
      for (const auto& [robot, w] : byRobot_) {
        dds_write_flush(w);
      }
    } else {
      dds_write_flush(w_);
    }
  }
  /// Disposes the instance with m's key (readers see it not-alive).
  void dispose(const T& m) {
    typename Tr::C c{};
    arena_.clear();
    Tr::toC(m, c, arena_);
    check(dds_dispose(writerFor(m), &c), "dds_dispose");
  }
  /// Tells readers this writer has nothing more for m's key and lets it forget the instance.
  void unregister(const T& m) {
    typename Tr::C c{};
    arena_.clear();
    Tr::toC(m, c, arena_);
    check(dds_unregister_instance(writerFor(m), &c), "dds_unregister_instance");
  }
  /// Readers matched; on a per-robot topic the fewest any of its robots' writers has (0 before
  /// the first robot).
  [[nodiscard]] std::uint32_t matchedReaders() const {
    if constexpr (kPerRobot) {
      if (byRobot_.empty()) {
        return 0;
      }
      std::uint32_t least = UINT32_MAX;
      for (const auto& [robot, w] : byRobot_) {
        least = std::min(least, detail::matched(w, true));
      }
      return least;
    } else {
      return detail::matched(w_, true);
    }
  }
  /// True once every matched reliable reader has acknowledged everything this writer holds (for
  /// transient-local data: the late joiner has it), false when `timeout` passes first.
  [[nodiscard]] bool waitForAcks(std::chrono::nanoseconds timeout) const {
    if constexpr (kPerRobot) {
      for (const auto& [robot, w] : byRobot_) {
        if (dds_wait_for_acks(w, static_cast<dds_duration_t>(timeout.count())) != DDS_RETCODE_OK) {
          return false;
        }
      }
      return true;
    } else {
      return dds_wait_for_acks(w_, static_cast<dds_duration_t>(timeout.count())) == DDS_RETCODE_OK;
    }
  }

  /// The DDS writer m goes through (on a per-robot topic, its robot's; made if new).
  [[nodiscard]] dds_entity_t handleFor(const T& m) { return writerFor(m); }

 private:
  /// Converts first: a sample that breaks a bound makes no writer for its robot.
  dds_entity_t put(const T& m) {
    typename Tr::C c{};
    arena_.clear();
    Tr::toC(m, c, arena_);
    const dds_entity_t w = writerFor(m);
    check(dds_write(w, &c), "dds_write");
    return w;
  }
  dds_entity_t writerFor(const T& m) {
    if constexpr (kPerRobot) {
      return writerOf(RobotOf<T>::of(m));
    } else {
      return w_;
    }
  }
  dds_entity_t writerOf(const std::string& robot) {
    auto it = byRobot_.find(robot);
    if (it == byRobot_.end()) {
      const std::vector<std::string> partitions =
          robot.empty() ? std::vector<std::string>{} : std::vector<std::string>{robotPartition(robot)};
      it = byRobot_.emplace(robot, detail::createWriter(participant_, topic_, qos_, partitions)).first;
    }
    return it->second;
  }

  dds_entity_t participant_;
  dds_entity_t topic_;
  QosProfile qos_;
  dds_entity_t w_;                               // children of the participant: deleted with it
  std::map<std::string, dds_entity_t> byRobot_;  // per-robot topics: robot id -> its writer
  bool batching_;
  Arena arena_;
};

template <class T>
class Reader {
 public:
  using Tr = Traits<T>;
  static constexpr bool kPerRobot = RobotOf<T>::kPerRobot;
  explicit Reader(const Participant& p, std::optional<QosProfile> q = std::nullopt,
                  const std::string& topic = Tr::kTopic)
      : topic_(detail::createTopic(p, Tr::descriptor(), topic)),
        writers_(kPerRobot ? std::make_unique<WriterPartitions>() : nullptr),
        r_(detail::createReader(p, topic_, q.value_or(Tr::qos()), partitions(),
                                writers_ ? writers_->listener() : nullptr)) {}
  Reader(const Reader&) = delete;
  Reader& operator=(const Reader&) = delete;
  /// The reader itself goes with its participant; its listener must not outlive writers_.
  ~Reader() {
    if (writers_) {
      dds_set_listener(r_, nullptr);
    }
  }

  /// Takes every available sample (removing it from the reader). Loans are returned before return.
  std::vector<T> take(std::size_t max = 1u << 20) { return collect(max, true); }
  /// Reads without removing: for keep-last-1 "latest value" topics.
  std::vector<T> read(std::size_t max = 1u << 20) { return collect(max, false); }
  /// Calls f for each sample taken; returns how many.
  std::size_t takeEach(const std::function<void(const T&)>& f, std::size_t max = 1u << 20) {
    auto v = take(max);
    for (const auto& m : v) {
      f(m);
    }
    return v.size();
  }
  /// Takes everything, like take(), and also reports instances whose writers are all gone or that
  /// were disposed (liveliness lost, process ended): `gone` gets the key fields of each such
  /// instance (other fields empty).
  std::vector<T> takeWithLifecycle(std::vector<T>& gone) {
    constexpr std::size_t kBatch = 256;
    std::vector<T> out;
    while (true) {
      void* samples[kBatch] = {nullptr};
      dds_sample_info_t infos[kBatch];
      const int n = dds_take(r_, samples, infos, kBatch, kBatch);
      check(n, "dds_take");
      for (int i = 0; i < n; ++i) {
        const auto& c = *static_cast<const typename Tr::C*>(samples[i]);
        if (infos[i].valid_data) {
          admit(Tr::fromC(c), infos[i], out);
        } else if (infos[i].instance_state != DDS_IST_ALIVE) {
          gone.push_back(Tr::fromC(c));
        }
      }
      if (n > 0) {
        check(dds_return_loan(r_, samples, n), "dds_return_loan");
      }
      if (static_cast<std::size_t>(n) < kBatch) {
        break;
      }
    }
    return out;
  }
  /// Blocks until data is available or the timeout passes; true when data is there.
  bool waitForData(std::chrono::milliseconds timeout);
  [[nodiscard]] std::uint32_t matchedWriters() const { return detail::matched(r_, false); }
  [[nodiscard]] dds_entity_t handle() const { return r_; }
  /// Per-robot topics: samples dropped because their writer is not in the partition of the robot
  /// they name (a writer speaking for another robot; robot_partition.hpp). Services count them.
  [[nodiscard]] std::uint64_t foreign() const { return foreign_; }

 private:
  static std::vector<std::string> partitions() {
    if constexpr (kPerRobot) {
      if constexpr (RobotOf<T>::kAlsoDefault) {
        return {kAnyRobotPartition, ""};
      } else {
        return {kAnyRobotPartition};
      }
    } else {
      return {};
    }
  }
  void admit(T&& m, const dds_sample_info_t& info, std::vector<T>& out) {
    if constexpr (kPerRobot) {
      if (!writers_->speaksFor(r_, info.publication_handle, RobotOf<T>::of(m))) {
        ++foreign_;
        return;
      }
    }
    out.push_back(std::move(m));
  }

  std::vector<T> collect(std::size_t max, bool takeIt) {
    constexpr std::size_t kBatch = 256;
    // Most calls find one or a few samples: a small first request keeps Cyclone's per-call loan
    // handling small; a full first batch means a backlog, then take it in large batches.
    std::size_t batch = 8;
    std::vector<T> out;
    while (out.size() < max) {
      void* samples[kBatch] = {nullptr};
      dds_sample_info_t infos[kBatch];
      const std::size_t want = std::min(batch, max - out.size());
      batch = kBatch;
      const int n = takeIt ? dds_take(r_, samples, infos, want, static_cast<std::uint32_t>(want))
                           : dds_read(r_, samples, infos, want, static_cast<std::uint32_t>(want));
      check(n, takeIt ? "dds_take" : "dds_read");
      for (int i = 0; i < n; ++i) {
        if (infos[i].valid_data) {
          admit(Tr::fromC(*static_cast<const typename Tr::C*>(samples[i])), infos[i], out);
        }
      }
      if (n > 0) {
        check(dds_return_loan(r_, samples, n), "dds_return_loan");
      }
      if (static_cast<std::size_t>(n) < want || !takeIt) {
        break;
      }
    }
    return out;
  }

  dds_entity_t topic_;
  std::unique_ptr<WriterPartitions> writers_;  // per-robot topics; before r_: its listener is r_'s
  dds_entity_t r_;
  Entity waitset_;
  std::uint64_t foreign_ = 0;
};

/// Waits on several readers at once; wake() interrupts a wait from another thread (shutdown).
class WaitSet {
 public:
  explicit WaitSet(const Participant& p);
  template <class T>
  void attach(const Reader<T>& r) {
    attachReader(r.handle());
  }
  /// Returns the number of triggered conditions (0 on timeout).
  int wait(std::chrono::milliseconds timeout);
  void wake();

 private:
  void attachReader(dds_entity_t reader);
  dds_entity_t ws_;
  dds_entity_t guard_;
  std::vector<dds_entity_t> conditions_;
};

template <class T>
bool Reader<T>::waitForData(std::chrono::milliseconds timeout) {
  if (waitset_.handle() == 0) {
    const dds_entity_t ws = check(dds_create_waitset(dds_get_participant(r_)), "dds_create_waitset");
    waitset_ = Entity(ws);
    const dds_entity_t rc = check(
        dds_create_readcondition(r_, DDS_NOT_READ_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ANY_INSTANCE_STATE),
        "dds_create_readcondition");
    check(dds_waitset_attach(ws, rc, 0), "dds_waitset_attach");
  }
  const int n =
      dds_waitset_wait(waitset_.handle(), nullptr, 0, DDS_MSECS(static_cast<std::int64_t>(timeout.count())));
  check(n, "dds_waitset_wait");
  return n > 0;
}

}  // namespace fleet::transport
