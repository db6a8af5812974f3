// What Cyclone DDS does with a received sample before our code sees it (normalize, then read), for
// our own types: a sample cut short must be refused, or read no further than where it ends. Cyclone
// 0.10.2 (Debian 12) under-checks XCDR2 arrays of 8-byte values; idl/fleet.idl avoids them.

#include <gtest/gtest.h>

#include <cstdint>
#include <cstring>
#include <vector>

#include "dds/ddsi/ddsi_cdrstream.h"
#include "dds/ddsi/q_protocol.h"
#include "fleet/transport/dds.hpp"
#include "fleet/transport/traits.hpp"

using namespace fleet;
using namespace fleet::transport;

namespace {

/// The XCDR2 serialization of `m` as a writer sends it (after the 4-byte encapsulation header).
template <class M>
std::vector<char> serialize(const M& m) {
  typename Traits<M>::C c{};
  Arena arena;
  Traits<M>::toC(m, c, arena);
  dds_ostream_t os;
  dds_ostream_init(&os, 0, CDR_ENC_VERSION_2);
  dds_stream_write(&os, reinterpret_cast<const char*>(&c), Traits<M>::descriptor()->m_ops);
  std::vector<char> out(os.m_buffer, os.m_buffer + os.m_index);
  dds_ostream_fini(&os);
  return out;
}

/// How far Cyclone reads into a received buffer of `length` bytes holding `bytes`' first bytes,
/// or -1 when it refuses the sample. The buffer has 8 spare bytes so that reading a little past
/// the sample shows in the result, not as a crash.
template <class M>
std::int64_t readExtent(const std::vector<char>& bytes, std::uint32_t length) {
  const dds_topic_descriptor_t* d = Traits<M>::descriptor();
  std::vector<char> buffer(length + 8, 0);
  std::memcpy(buffer.data(), bytes.data(), length);
  std::uint32_t offset = 0;
  if (dds_stream_normalize_data(buffer.data(), &offset, length, false, CDR_ENC_VERSION_2, d->m_ops) ==
      nullptr) {
    return -1;
  }
  dds_istream_t is;
  dds_istream_init(&is, length, buffer.data(), CDR_ENC_VERSION_2);
  std::vector<char> sample(d->m_size, 0);
  dds_stream_read(&is, sample.data(), d->m_ops);
  const std::int64_t extent = is.m_index;
  dds_istream_fini(&is);
  dds_stream_free_sample(sample.data(), d->m_ops);
  return extent;
}

}  // namespace

// The fuzzer's finding (tests/fuzz/corpus/dds_sample/robot_state_covariance_past_the_end.xcdr2):
// with `double covariance[9]`, a RobotState whose delimiter header ends 5 doubles into the
// covariance was accepted and then read 32 bytes past its end.
TEST(ReceivedCdr, RobotStateCutShortIsNeverReadPastItsEnd) {
  msg::RobotState s{"r-1", 5,    {1.5, 2.5, -3.0},       {1, 2, 3, 4, 5, 6, 7, 8, 9},
                    0.7,   -0.2, msg::RobotMode::Moving, 0.5f,
                    "T-1", 0.3f};
  const auto full = serialize(s);
  ASSERT_EQ(readExtent<msg::RobotState>(full, static_cast<std::uint32_t>(full.size())),
            static_cast<std::int64_t>(full.size()));
  for (std::uint32_t length = 8; length < full.size(); length += 4) {
    auto cut = full;
    const std::uint32_t body = length - 4;  // the appendable type's delimiter header: bytes after it
    std::memcpy(cut.data(), &body, 4);
    const auto extent = readExtent<msg::RobotState>(cut, length);
    // Cyclone 0.10.2 checks one 8-byte value for 4 bytes, so a double that ends the sample may be
    // read 4 bytes past it (fixed upstream in 11.0); anything more is the array bug.
    EXPECT_LE(extent, static_cast<std::int64_t>(length) + 4) << "cut after " << length << " bytes";
  }
}
