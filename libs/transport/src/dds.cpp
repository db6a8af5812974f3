#include "fleet/transport/dds.hpp"

#include <cstdlib>
#include <map>
#include <mutex>

namespace fleet::transport {

DdsError::DdsError(const std::string& what, int rc)
    : std::runtime_error(what + " failed: " + dds_strretcode(rc) + " (" + std::to_string(rc) + ")"),
      rc_(rc) {}

int check(int rc, const char* what) {
  if (rc < 0) {
    throw DdsError(what, rc);
  }
  return rc;
}

std::string loopbackConfig(bool writeBatch, int lossPerMille) {
  // Repair of lost packets (docs/architecture.md, "Transport"): Cyclone 0.10 retransmits at most
  // MaxRexmitMessageSize per message (default 1456 B: one fragment of a large sample per NACK round)
  // and lets a writer's heartbeats, which drive the repair, thin out to one per 8 s. On loopback a
  // retransmit may be as large as a first transmission, and heartbeats stay at least once a second.
  // Loss on loopback is a receive buffer overflowing while its process waits for a CPU: ask for 4 MiB
  // (Cyclone's default asks 1 MiB; the kernel grants at most net.core.rmem_max, accepted as it is).
  std::string internal =
      "<HeartbeatInterval max=\"1 s\">100 ms</HeartbeatInterval><SocketReceiveBufferSize max=\"4 MiB\"/>";
  if (writeBatch) {
    internal += "<WriteBatch>true</WriteBatch>";
  }
  if (lossPerMille > 0) {
    internal += "<Test><XmitLossiness>" + std::to_string(lossPerMille) + "</XmitLossiness></Test>";
  }
  return "<CycloneDDS><Domain id=\"any\"><General><Interfaces><NetworkInterface name=\"lo\"/></Interfaces>"
         "<AllowMulticast>false</AllowMulticast><MaxRexmitMessageSize>14720 "
         "B</MaxRexmitMessageSize></General>"
         "<Discovery><Peers><Peer address=\"127.0.0.1\"/></Peers><ParticipantIndex>auto</ParticipantIndex>"
         "<MaxAutoParticipantIndex>200</MaxAutoParticipantIndex></Discovery><Internal>" +
         internal + "</Internal></Domain></CycloneDDS>";
}

int domainFromEnvironment() {
  const char* s = std::getenv("FLEET_DDS_DOMAIN");
  if (s == nullptr || *s == '\0') {
    return 0;
  }
  char* end = nullptr;
  const long v = std::strtol(s, &end, 10);
  if (*end != '\0' || v < 0 || v > 229) {
    throw DdsError(std::string("FLEET_DDS_DOMAIN=\"") + s + "\" is not a domain id in 0..229",
                   DDS_RETCODE_BAD_PARAMETER);
  }
  return static_cast<int>(v);
}

Entity& Entity::operator=(Entity&& o) noexcept {
  if (this != &o) {
    if (h_ > 0) {
      dds_delete(h_);
    }
    h_ = o.h_;
    o.h_ = 0;
  }
  return *this;
}

Entity::~Entity() {
  if (h_ > 0) {
    dds_delete(h_);  // may already be gone with its parent; nothing to do then
  }
}

namespace {
// Domains we created with the built-in config stay for the life of the process, so that every
// participant of the process (one per agent, say) shares them.
// With CYCLONEDDS_URI set the operator's file decides everything, write batching included
// (Writer::write() still flushes, so it is correct either way).
void ensureLoopbackDomain(int domain, bool writeBatch) {
  const char* uri = std::getenv("CYCLONEDDS_URI");
  if (uri != nullptr && *uri != '\0') {
    return;
  }
  static std::mutex m;
  static std::map<int, bool> domains;  // domain -> created with write batching
  std::lock_guard lock(m);
  if (const auto it = domains.find(domain); it != domains.end()) {
    if (it->second != writeBatch) {
      throw DdsError("Participant on domain " + std::to_string(domain) +
                         " with writeBatching=" + (writeBatch ? "true" : "false") +
                         ": this process already joined the domain with the other setting",
                     DDS_RETCODE_PRECONDITION_NOT_MET);
    }
    return;
  }
  const dds_entity_t d =
      dds_create_domain(static_cast<dds_domainid_t>(domain), loopbackConfig(writeBatch).c_str());
  if (d < 0 && d != DDS_RETCODE_PRECONDITION_NOT_MET) {
    check(d, "dds_create_domain (built-in loopback config)");
  }
  domains[domain] = writeBatch;
}
}  // namespace

Participant::Participant(int domain, ParticipantOptions options) : domain_(domain), options_(options) {
  ensureLoopbackDomain(domain, options.writeBatching);
  e_ = Entity(check(dds_create_participant(static_cast<dds_domainid_t>(domain), nullptr, nullptr),
                    "dds_create_participant"));
}

namespace detail {

dds_entity_t createTopic(const Participant& p, const dds_topic_descriptor_t* desc, const std::string& name) {
  return check(dds_create_topic(p.handle(), desc, name.c_str(), nullptr, nullptr),
               ("dds_create_topic " + name).c_str());
}

namespace {
dds_qos_t* makeQos(const QosProfile& q, const std::vector<std::string>& partitions) {
  dds_qos_t* qos = q.make();
  if (!partitions.empty()) {
    std::vector<const char*> names;
    for (const auto& p : partitions) {
      names.push_back(p.c_str());
    }
    dds_qset_partition(qos, static_cast<uint32_t>(names.size()), names.data());
  }
  return qos;
}
std::string inPartitions(const char* call, const std::vector<std::string>& partitions) {
  std::string s = call;
  for (std::size_t i = 0; i < partitions.size(); ++i) {
    s += (i == 0 ? " (partition \"" : ", \"") + partitions[i] + "\"";
  }
  return partitions.empty() ? s : s + ")";
}
}  // namespace

dds_entity_t createWriter(dds_entity_t participant, dds_entity_t topic, const QosProfile& q,
                          const std::vector<std::string>& partitions) {
  dds_qos_t* qos = makeQos(q, partitions);
  const dds_entity_t w = dds_create_writer(participant, topic, qos, nullptr);
  dds_delete_qos(qos);
  return check(w, inPartitions("dds_create_writer", partitions).c_str());
}

dds_entity_t createReader(const Participant& p, dds_entity_t topic, const QosProfile& q,
                          const std::vector<std::string>& partitions, const dds_listener_t* listener) {
  dds_qos_t* qos = makeQos(q, partitions);
  const dds_entity_t r = dds_create_reader(p.handle(), topic, qos, listener);
  dds_delete_qos(qos);
  return check(r, inPartitions("dds_create_reader", partitions).c_str());
}

std::uint32_t matched(dds_entity_t e, bool publication) {
  if (publication) {
    dds_publication_matched_status_t st{};
    check(dds_get_publication_matched_status(e, &st), "dds_get_publication_matched_status");
    return st.current_count;
  }
  dds_subscription_matched_status_t st{};
  check(dds_get_subscription_matched_status(e, &st), "dds_get_subscription_matched_status");
  return st.current_count;
}

}  // namespace detail

WaitSet::WaitSet(const Participant& p)
    : ws_(check(dds_create_waitset(p.handle()), "dds_create_waitset")),
      guard_(check(dds_create_guardcondition(p.handle()), "dds_create_guardcondition")) {
  check(dds_waitset_attach(ws_, guard_, guard_), "dds_waitset_attach");
}

void WaitSet::attachReader(dds_entity_t reader) {
  const dds_entity_t c =
      check(dds_create_readcondition(reader,
                                     DDS_NOT_READ_SAMPLE_STATE | DDS_ANY_VIEW_STATE | DDS_ANY_INSTANCE_STATE),
            "dds_create_readcondition");
  check(dds_waitset_attach(ws_, c, c), "dds_waitset_attach");
  conditions_.push_back(c);
}

int WaitSet::wait(std::chrono::milliseconds timeout) {
  dds_attach_t triggered[16];
  const int n = dds_waitset_wait(ws_, triggered, 16, DDS_MSECS(static_cast<std::int64_t>(timeout.count())));
  check(n, "dds_waitset_wait");
  for (int i = 0; i < std::min(n, 16); ++i) {
    if (triggered[i] == static_cast<dds_attach_t>(guard_)) {
      dds_set_guardcondition(guard_, false);
    }
  }
  return n;
}

void WaitSet::wake() {
  check(dds_set_guardcondition(guard_, true), "dds_set_guardcondition");
}

}  // namespace fleet::transport
