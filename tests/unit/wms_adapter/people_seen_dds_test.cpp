// The WMS adapter's DDS side with the people robots see: PeopleSeen samples published on a loopback
// domain of their own reach GET /v1/robots/{id}; malformed ones (a NaN position, a robot the adapter
// has no state of, more people than the topic's bound) are refused and counted, and the adapter
// goes on serving.

#include <gtest/gtest.h>
#include <httplib.h>

#include <chrono>
#include <functional>
#include <thread>

#include "dds_gateway.hpp"
#include "fleet/transport/dds.hpp"
#include "http_api.hpp"
#include "test_process.hpp"

using namespace fleet;
using namespace fleet::wms;
using nlohmann::json;
using namespace std::chrono_literals;

namespace {

/// Polls `ok` every 50 ms for up to 10 s (discovery and delivery on a loaded machine).
bool eventually(const std::function<bool()>& ok) {
  const auto until = std::chrono::steady_clock::now() + 10s;
  while (std::chrono::steady_clock::now() < until) {
    if (ok()) {
      return true;
    }
    std::this_thread::sleep_for(50ms);
  }
  return ok();
}

msg::RobotState stateOf(const std::string& id) {
  msg::RobotState r;
  r.robot_id = id;
  r.pose = {1.0, 1.0, 0.0};
  r.radius = 0.3F;
  r.stamp_ns = 1;
  return r;
}

}  // namespace

TEST(PeopleSeenOverDds, ReachTheRobotApiAndMalformedSamplesAreRefusedAndCounted) {
  setenv("FLEET_DDS_DOMAIN", std::to_string(test::uniqueDomain()).c_str(), 1);
  transport::Participant adapterSide;
  FleetView view;
  DdsGateway gateway(adapterSide, view);
  ApiSettings s;
  s.port = 0;
  StationMap stations = *StationMap::fromJson(
      json::parse(R"({"stations": [{"name": "P-1", "x": 1, "y": 1, "kinds": ["pickup"]}]})"));
  WallClock clock;
  HttpApi api(s, stations, gateway, view, clock);
  ASSERT_TRUE(api.bind());
  std::thread server([&] { api.serve(); });
  httplib::Client client("127.0.0.1", api.port());
  auto robotJson = [&](const std::string& id) {
    auto r = client.Get("/v1/robots/" + id);
    return r && r->status == 200 ? json::parse(r->body) : json();
  };
  auto rejected = [&](const std::string& reason) {
    auto r = client.Get("/v1/metrics");
    if (!r || r->status != 200) {
      return std::uint64_t{0};
    }
    const json j = json::parse(r->body)["samples"];
    return j.contains("rejected") && j["rejected"].contains("PeopleSeen")
               ? j["rejected"]["PeopleSeen"].value(reason, std::uint64_t{0})
               : std::uint64_t{0};
  };

  transport::Participant agentSide;
  transport::Writer<msg::RobotState> states(agentSide);
  transport::Writer<msg::PeopleSeen> people(agentSide);
  ASSERT_TRUE(eventually([&] {
    states.write(stateOf("r1"));
    return !robotJson("r1").is_null();
  })) << "the robot's state never reached the adapter";

  ASSERT_TRUE(eventually([&] {
    people.write({"r1", 1, {{2.5F, 3.0F, 0.4F, 0.0F, 0.25F, true}}});
    const json r = robotJson("r1");
    return !r.is_null() && r["people_seen"].size() == 1;
  })) << "the people seen never reached GET /v1/robots/r1";
  EXPECT_DOUBLE_EQ(robotJson("r1")["people_seen"][0]["x"].get<double>(), 2.5);

  ASSERT_TRUE(eventually([&] {
    people.write({"r1", 2, {{std::numeric_limits<float>::quiet_NaN(), 3.0F, 0.0F, 0.0F, 0.25F, false}}});
    return rejected("non_finite") > 0;
  }));
  EXPECT_DOUBLE_EQ(robotJson("r1")["people_seen"][0]["x"].get<double>(), 2.5) << "the last good list stays";
  ASSERT_TRUE(eventually([&] {
    people.write({"ghost", 3, {{1.0F, 1.0F, 0.0F, 0.0F, 0.25F, false}}});
    return rejected("unknown_robot") > 0;
  }));
  EXPECT_TRUE(robotJson("ghost").is_null());

  // Over the IDL bound: our writers refuse to send it, and so does Cyclone's for one written raw
  // (dds_write fails, Cyclone 0.10.2); should one get through, the reader's deserializer or the
  // validation layer (too_large, see SampleChecks.PeopleSeenMustBeFiniteBoundedAndNamed) refuses it.
  fleet_PeopleSeen raw{};
  std::snprintf(raw.robot_id, sizeof raw.robot_id, "%s", "r1");
  std::vector<fleet_SeenPerson> crowd(msg::kMaxPeopleSeen + 1,
                                      fleet_SeenPerson{9.0F, 9.0F, 0, 0, 0.25F, false});
  raw.people._buffer = crowd.data();
  raw.people._length = raw.people._maximum = static_cast<std::uint32_t>(crowd.size());
  raw.stamp_ns = 4;
  const dds_return_t rawWritten = dds_write(people.handleFor(msg::PeopleSeen{"r1", 4, {}}), &raw);
  std::this_thread::sleep_for(300ms);
  EXPECT_NE(robotJson("r1")["people_seen"].size(), crowd.size())
      << "dds_write returned " << rawWritten << "; refused as too_large " << rejected("too_large")
      << " times";

  EXPECT_THROW(people.write({"r1", 5, std::vector<msg::SeenPerson>(msg::kMaxPeopleSeen + 1)}),
               transport::MessageError);

  // Still serving, with the good list.
  ASSERT_TRUE(eventually([&] {
    people.write({"r1", 6, {{4.0F, 4.0F, 0.0F, 0.0F, 0.25F, false}, {5.0F, 5.0F, 0.0F, 0.0F, 0.25F, false}}});
    return robotJson("r1")["people_seen"].size() == 2;
  }));
  // A list naming r1 from r2's writer (partition robot/r2): dropped and counted, r1's list stays.
  const dds_entity_t r2Writer = people.handleFor(msg::PeopleSeen{"r2", 7, {}});
  ASSERT_TRUE(eventually([&] {
    fleet_PeopleSeen disguised{};
    std::snprintf(disguised.robot_id, sizeof disguised.robot_id, "%s", "r1");
    disguised.stamp_ns = 7;
    (void)dds_write(r2Writer, &disguised);
    return rejected("foreign_robot") > 0;
  }));
  EXPECT_EQ(robotJson("r1")["people_seen"].size(), 2U);
  api.stop();
  server.join();
}
