// A DDS sample as a service receives it: CDR bytes from the network, checked and read by Cyclone
// (dds_stream_normalize_data, dds_stream_read: what the reader does with a received sample), copied
// into our C++ struct (libs/transport Traits<T>::fromC) and passed through the service's edge
// (validation::admit). The first byte picks the topic type, its byte order and XCDR version; the
// rest is the serialized sample. Properties besides "no crash": a sample the edge admits is admitted
// again, and it can be written back (toC throws for nothing the edge let through).

#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <vector>

#include "dds/ddsi/ddsi_cdrstream.h"
#include "dds/ddsi/q_protocol.h"
#include "fleet/transport/dds.hpp"
#include "fleet/transport/traits.hpp"
#include "fleet/validation/rejections.hpp"
#include "fleet/validation/sample_checks.hpp"
#include "fuzz_check.hpp"

namespace {

namespace msg = fleet::msg;
namespace transport = fleet::transport;
namespace validation = fleet::validation;
using fleet::fuzz::require;

template <class M>
void receive(std::vector<char>& bytes, bool bswap, std::uint32_t xcdr, std::uint32_t size) {
  using Traits = transport::Traits<M>;
  const dds_topic_descriptor_t* d = Traits::descriptor();
  std::uint32_t offset = 0;
  // Cyclone refuses malformed CDR here, before anything of ours sees it.
  if (dds_stream_normalize_data(bytes.data(), &offset, size, bswap, xcdr, d->m_ops) == nullptr) {
    return;
  }
  dds_istream_t is;
  dds_istream_init(&is, size, bytes.data(), xcdr);
  void* c = std::calloc(1, d->m_size);
  dds_stream_read(&is, static_cast<char*>(c), d->m_ops);
  dds_istream_fini(&is);
  M m = Traits::fromC(*static_cast<const typename Traits::C*>(c));
  dds_stream_free_sample(c, d->m_ops);
  std::free(c);
  if constexpr (requires { validation::check(m); }) {
    validation::Rejections counters;
    if (!validation::admit(m, counters)) {
      require(counters.total() == 1, "a refused sample is counted once");
      return;
    }
    require(!validation::check(m).has_value(), "an admitted sample stays admitted");
  }
  typename Traits::C out{};
  transport::Arena arena;
  try {
    Traits::toC(m, out, arena);
  } catch (const transport::MessageError& e) {
    std::fprintf(stderr, "toC: %s\n", e.what());
    require(false, "a received sample can be written back");
  }
}

using Receive = void (*)(std::vector<char>&, bool, std::uint32_t, std::uint32_t);
constexpr Receive kTopics[] = {receive<msg::Task>,           receive<msg::TaskAck>,
                               receive<msg::TaskEvent>,      receive<msg::TaskAssignment>,
                               receive<msg::TaskStatus>,     receive<msg::RobotState>,
                               receive<msg::PredictedDiscs>, receive<msg::RiskMap>,
                               receive<msg::SensorFrame>,    receive<msg::VelocityCommand>,
                               receive<msg::Clock>,          receive<msg::StepDone>,
                               receive<msg::GroundTruth>,    receive<msg::Roadmap>,
                               receive<msg::TrafficRelease>, receive<msg::TrafficProgress>,
                               receive<msg::PeopleSeen>,     receive<msg::TrafficClosure>};
constexpr std::size_t kTopicCount = sizeof(kTopics) / sizeof(kTopics[0]);

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 2 || size > (std::size_t{1} << 24)) {  // Cyclone never hands over an empty payload
    return 0;
  }
  // Byte 0: bits 0-4 the topic, bit 5 byte-swapped, bit 6 XCDR2.
  const std::size_t topic = (data[0] & 0x1f) % kTopicCount;
  const bool bswap = (data[0] & 0x20) != 0;
  const std::uint32_t xcdr = (data[0] & 0x40) != 0 ? CDR_ENC_VERSION_2 : CDR_ENC_VERSION_1;
  // Normalizing works in place and reads 4- and 8-byte words: a copy, aligned as a receive buffer.
  // Four more bytes, zero, past the sample: Cyclone 0.10.2 checks one received 8-byte value for 4
  // bytes (XCDR2 alignment) and reads 8, so an 8-byte member that ends a sample is read 4 bytes
  // past it (fixed upstream in Cyclone 11.0, commit 9dd9e75; docs/operator-guide.md#fuzzing). In
  // Cyclone's own receive buffer those 4 bytes are heap bytes next to the sample, never a page
  // away; what we can avoid, arrays of 8-byte values read up to 36 bytes past, idl/fleet.idl does.
  std::vector<char> bytes(size - 1 + 4, 0);
  std::memcpy(bytes.data(), data + 1, size - 1);
  kTopics[topic](bytes, bswap, xcdr, static_cast<std::uint32_t>(size - 1));
  return 0;
}
