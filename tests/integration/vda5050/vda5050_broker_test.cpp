// The simulated vehicle's MQTT side against a real Mosquitto broker of the test's own: credentials,
// the ACL's per-vehicle subtree, orders in and state out, the last will, a broker restart.

#include <gtest/gtest.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <functional>
#include <mutex>
#include <thread>

#include "fleet/mqtt/client.hpp"
#include "fleet/sim/vda5050_link.hpp"
#include "fleet/sim/vda5050_vehicle.hpp"
#include "fleet/vda5050/connection.hpp"
#include "fleet/vda5050/order.hpp"
#include "fleet/vda5050/order_builder.hpp"
#include "fleet/vda5050/state.hpp"
#include "fleet/vda5050/vehicle_registry.hpp"
#include "mosquitto_broker.hpp"

namespace fleet {
namespace {

using namespace std::chrono_literals;
using test::BrokerVehicle;
using test::MosquittoBroker;

bool waitFor(const std::function<bool()>& pred, std::chrono::milliseconds timeout = 10s) {
  const auto end = std::chrono::steady_clock::now() + timeout;
  while (std::chrono::steady_clock::now() < end) {
    if (pred()) {
      return true;
    }
    std::this_thread::sleep_for(10ms);
  }
  return pred();
}

/// A master-control client that records what arrives on its subscriptions.
struct Recorder {
  std::mutex mutex;
  std::vector<std::pair<std::string, std::string>> messages;
  std::unique_ptr<mqtt::Client> client;

  Recorder(int port, const std::string& user, const std::string& password, const std::string& id) {
    mqtt::ClientOptions o;
    o.port = port;
    o.client_id = id;
    o.username = user;
    o.password = password;
    auto c = mqtt::Client::start(o, [this](const std::string& t, const std::string& p) {
      std::lock_guard lock(mutex);
      messages.emplace_back(t, p);
    });
    if (!c) {
      throw std::runtime_error(c.error().message);
    }
    client = std::move(*c);
  }
  std::vector<std::string> on(const std::string& topic) {
    std::lock_guard lock(mutex);
    std::vector<std::string> out;
    for (const auto& [t, p] : messages) {
      if (t == topic) {
        out.push_back(p);
      }
    }
    return out;
  }
};

const std::vector<BrokerVehicle> kVehicles = {{"acme", "A1", "pw-a1"}, {"acme", "A2", "pw-a2"}};

sim::Vda5050LinkOptions linkOptions(const MosquittoBroker& broker, const std::string& serial) {
  sim::Vda5050LinkOptions lo;
  lo.port = broker.port();
  lo.manufacturer = "acme";
  lo.serial = serial;
  for (const auto& v : kVehicles) {
    if (v.serial == serial) {
      lo.username = v.user();
      lo.password = v.password;
    }
  }
  return lo;
}

TEST(Vda5050Broker, TheAclConfinesEachVehicleToItsSubtree) {
  MosquittoBroker broker(kVehicles);
  ASSERT_NE(broker.port(), 1883);
  Recorder master(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "master");
  master.client->subscribe("uagv/#", 0);
  Recorder a1(broker.port(), "acme-A1", "pw-a1", "acme-A1");
  a1.client->subscribe("uagv/v2/acme/A2/#", 0);  // someone else's orders: the broker denies it
  ASSERT_TRUE(waitFor([&] { return master.client->connected() && a1.client->connected(); }));
  std::this_thread::sleep_for(200ms);  // let the subscriptions settle

  ASSERT_TRUE(a1.client->publish("uagv/v2/acme/A2/state", "{\"forged\":true}", 1, false));
  ASSERT_TRUE(a1.client->publish("uagv/v2/acme/A1/state", "{\"own\":true}", 1, false));
  ASSERT_TRUE(master.client->publish("uagv/v2/acme/A2/order", "{\"for\":\"A2\"}", 1, false));
  ASSERT_TRUE(waitFor([&] { return master.on("uagv/v2/acme/A1/state").size() == 1; }));
  ASSERT_TRUE(waitFor([&] { return master.on("uagv/v2/acme/A2/order").size() == 1; }));
  std::this_thread::sleep_for(300ms);
  EXPECT_TRUE(master.on("uagv/v2/acme/A2/state").empty()) << "A1 wrote into A2's subtree";
  EXPECT_TRUE(a1.on("uagv/v2/acme/A2/order").empty()) << "A1 read A2's orders";
}

TEST(Vda5050Broker, OverTlsTheVehicleConnectsAndAPlainClientCannot) {
  MosquittoBroker broker(kVehicles, /*tls=*/true);
  auto lo = linkOptions(broker, "A1");
  lo.tls_ca_file = broker.caFile();
  auto link = sim::Vda5050Link::start(lo);
  ASSERT_TRUE(link) << link.error().message;
  ASSERT_TRUE(waitFor([&] { return (*link)->connected(); })) << "see " << broker.logFile();

  Recorder plain(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "plain");
  std::this_thread::sleep_for(1s);
  EXPECT_FALSE(plain.client->connected()) << "a client without TLS got in";

  mqtt::ClientOptions bad;
  bad.port = broker.port();
  bad.client_id = "x";
  bad.tls_ca_file = "/nonexistent/ca.crt";
  EXPECT_FALSE(mqtt::Client::start(bad, {}));
}

TEST(Vda5050Broker, AClientStartedBeforeTheBrokerConnectsWhenItComesUp) {
  MosquittoBroker broker(kVehicles);
  broker.stop();
  Recorder early(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "early");
  std::this_thread::sleep_for(1500ms);  // a failed first attempt or two
  EXPECT_FALSE(early.client->connected());
  broker.start();
  EXPECT_TRUE(waitFor([&] { return early.client->connected(); }, 15s));
}

TEST(Vda5050Broker, WrongCredentialsAreRefused) {
  MosquittoBroker broker(kVehicles);
  Recorder intruder(broker.port(), "acme-A1", "guessed", "intruder");
  ASSERT_TRUE(waitFor([&] { return intruder.client->refusals() > 0; }));
  EXPECT_FALSE(intruder.client->connected());
}

TEST(Vda5050Broker, AnOrderThroughTheBrokerMovesTheVehicleAndStateComesBack) {
  MosquittoBroker broker(kVehicles);
  Recorder master(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "master");
  master.client->subscribe("uagv/v2/acme/A1/#", 0);
  auto link = sim::Vda5050Link::start(linkOptions(broker, "A1"));
  ASSERT_TRUE(link) << link.error().message;
  sim::Vda5050VehicleConfig vc;
  vc.manufacturer = "acme";
  vc.serial = "A1";
  vc.mapId = "small";
  sim::Vda5050Vehicle vehicle(vc, Pose2{});
  ASSERT_TRUE(waitFor([&] { return master.client->connected() && (*link)->connected(); }));

  // ONLINE is announced (retained) on connect.
  (void)(*link)->take(0);
  ASSERT_TRUE(waitFor([&] { return !master.on("uagv/v2/acme/A1/connection").empty(); }));
  EXPECT_EQ(vda5050::parseConnection(master.on("uagv/v2/acme/A1/connection").back())->connectionState,
            "ONLINE");

  vda5050::Order o;
  o.header = {1, vda5050::isoTimestamp(0), vda5050::kVersion, "acme", "A1"};
  o.orderId = "o1";
  for (int i = 0; i < 3; ++i) {
    o.nodes.push_back({"n" + std::to_string(i),
                       static_cast<std::uint32_t>(2 * i),
                       true,
                       vda5050::NodePosition{static_cast<double>(i), 0.0, {}, {}, {}, "small"},
                       {}});
    if (i > 0) {
      o.edges.push_back({"e" + std::to_string(i),
                         static_cast<std::uint32_t>(2 * i - 1),
                         true,
                         "n" + std::to_string(i - 1),
                         "n" + std::to_string(i),
                         {},
                         {},
                         {}});
    }
  }
  ASSERT_TRUE(master.client->publish("uagv/v2/acme/A1/order", vda5050::toJson(o).dump(), 0, false));
  master.client->publish("uagv/v2/acme/A1/order", "{\"orderId\": 3}", 0, false);  // refused, counted

  // The simulator's loop, at 10 Hz of simulated time, as fast as it goes.
  Pose2 pose;
  double t = 0.0;
  std::size_t refused = 0;
  bool accepted = false;
  for (int k = 0; k < 400; ++k) {
    auto in = (*link)->take(0);
    refused += in.refused.size();
    for (const auto& order : in.orders) {
      accepted = accepted || vehicle.onOrder(order).decision == vda5050::OrderDecision::kAcceptNew;
    }
    const auto c = vehicle.step(t, pose, false);
    pose.x += c.v * std::cos(pose.theta) * 0.1;
    pose.theta += c.w * 0.1;
    t += 0.1;
    if (vehicle.stateDue(t)) {
      (*link)->publish(vehicle.takeState(t, 0));
    }
    if (accepted && vehicle.lastNodeId() == "n2" && refused > 0) {
      break;
    }
    std::this_thread::sleep_for(5ms);
  }
  EXPECT_TRUE(accepted);
  EXPECT_EQ(refused, 1U);
  EXPECT_EQ(vehicle.lastNodeId(), "n2");
  (*link)->publish(vehicle.takeState(t, 0));
  ASSERT_TRUE(waitFor([&] {
    const auto states = master.on("uagv/v2/acme/A1/state");
    if (states.empty()) {
      return false;
    }
    const auto s = vda5050::parseState(states.back());
    return s && s->lastNodeId == "n2";
  }));
}

TEST(Vda5050Broker, TheLastWillSaysConnectionBrokenWhenTheVehicleVanishes) {
  MosquittoBroker broker(kVehicles);
  Recorder master(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "master");
  master.client->subscribe("uagv/v2/acme/A2/connection", 1);
  ASSERT_TRUE(waitFor([&] { return master.client->connected(); }));
  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    auto link = sim::Vda5050Link::start(linkOptions(broker, "A2"));
    for (int i = 0; i < 500 && link && !(*link)->connected(); ++i) {
      std::this_thread::sleep_for(10ms);
    }
    if (link) {
      (void)(*link)->take(0);  // ONLINE
      std::this_thread::sleep_for(200ms);
    }
    _exit(0);  // no clean disconnect: the broker must publish the will
  }
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  ASSERT_TRUE(waitFor([&] {
    const auto c = master.on("uagv/v2/acme/A2/connection");
    return !c.empty() && vda5050::parseConnection(c.back())->connectionState == "CONNECTIONBROKEN";
  })) << "no last will";
  EXPECT_EQ(vda5050::parseConnection(master.on("uagv/v2/acme/A2/connection").front())->connectionState,
            "ONLINE");
}

TEST(Vda5050Broker, TheVehicleReconnectsAfterABrokerRestart) {
  MosquittoBroker broker(kVehicles);
  auto link = sim::Vda5050Link::start(linkOptions(broker, "A1"));
  ASSERT_TRUE(link) << link.error().message;
  ASSERT_TRUE(waitFor([&] { return (*link)->connected(); }));
  (void)(*link)->take(0);
  broker.stop();
  ASSERT_TRUE(waitFor([&] { return !(*link)->connected(); }));
  broker.start();
  ASSERT_TRUE(waitFor([&] { return (*link)->connected(); }, 15s));
  // Orders reach it again: its subscriptions were renewed on reconnect.
  Recorder master(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "master");
  master.client->subscribe("uagv/v2/acme/A1/connection", 1);
  ASSERT_TRUE(waitFor([&] { return master.client->connected(); }));
  (void)(*link)->take(0);  // announces ONLINE again (retained)
  ASSERT_TRUE(waitFor([&] { return !master.on("uagv/v2/acme/A1/connection").empty(); }));
  vda5050::InstantActions ia;
  ia.header = {1, vda5050::isoTimestamp(0), vda5050::kVersion, "acme", "A1"};
  ia.actions = {{"startPause", "p1", "HARD", {}, {}}};
  bool got = false;
  for (int i = 0; i < 100 && !got; ++i) {
    master.client->publish("uagv/v2/acme/A1/instantActions", vda5050::toJson(ia).dump(), 0, false);
    std::this_thread::sleep_for(50ms);
    got = !(*link)->take(0).instant_actions.empty();
  }
  EXPECT_TRUE(got);
}

// The master control's core (order builder + vehicle registry) against the simulated vehicle,
// all through the broker: releases become an order and a stitched update, the vehicle's state
// comes back online; then bad input, a broker restart and the last will.
TEST(Vda5050Broker, MasterControlCoreDrivesTheVehicleAndSurvivesBadInput) {
  MosquittoBroker broker(kVehicles);
  std::mutex mutex;
  vda5050::VehicleRegistry registry("uagv", "small", {{"acme", "A1", "v1"}, {"acme", "A2", "v2"}});
  std::vector<std::string> refused;
  Recorder master(broker.port(), MosquittoBroker::kMasterUser, MosquittoBroker::kMasterPassword, "master");
  // The registry sees what the recorder sees; fed from the test thread below.
  std::size_t fed = 0;
  const auto feed = [&] {
    std::lock_guard lock(master.mutex);
    for (; fed < master.messages.size(); ++fed) {
      const auto out = registry.onMessage(master.messages[fed].first, master.messages[fed].second);
      if (!out.accepted) {
        refused.push_back(out.reason);
      }
    }
  };
  master.client->subscribe("uagv/v2/+/+/state", 0);
  master.client->subscribe("uagv/v2/+/+/connection", 1);
  master.client->subscribe("uagv/v2/+/+/factsheet", 0);

  const pid_t child = fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    // The vehicle in its own process, so that it can vanish without a clean disconnect.
    auto link = sim::Vda5050Link::start(linkOptions(broker, "A1"));
    sim::Vda5050VehicleConfig vc;
    vc.manufacturer = "acme";
    vc.serial = "A1";
    vc.mapId = "small";
    sim::Vda5050Vehicle vehicle(vc, Pose2{});
    Pose2 pose;
    double t = 0.0;
    for (int k = 0; k < 3000 && link; ++k) {  // at most 30 s of wall time
      auto in = (*link)->take(0);
      for (const auto& o : in.orders) {
        (void)vehicle.onOrder(o);
      }
      const auto c = vehicle.step(t, pose, false);
      pose.x += c.v * std::cos(pose.theta) * 0.1;
      pose.y += c.v * std::sin(pose.theta) * 0.1;
      pose.theta += c.w * 0.1;
      t += 0.1;
      if (vehicle.stateDue(t) && (*link)->connected()) {
        (*link)->publish(vehicle.takeState(t, 0));
      }
      if (vehicle.lastNodeId() == "n4") {
        std::this_thread::sleep_for(300ms);
        _exit(0);  // vanish: the broker publishes the last will
      }
      std::this_thread::sleep_for(10ms);
    }
    _exit(1);
  }
  const auto health = [&] { return registry.find("v1")->health; };
  ASSERT_TRUE(waitFor([&] {
    feed();
    return health() == vda5050::VehicleHealth::kOnline;
  })) << "no state from the vehicle";

  // Bad input through the broker: a state failing the schema, an unknown serial, another map.
  master.client->publish("uagv/v2/acme/A1/state", R"({"headerId": 1})", 0, false);
  master.client->publish("uagv/v2/acme/Z9/state", "{}", 0, false);
  ASSERT_TRUE(waitFor([&] {
    feed();
    return registry.refusals().count("bad_message") && registry.refusals().count("unknown_serial");
  }));
  // ... the vehicle's next good state brings it back.
  ASSERT_TRUE(waitFor([&] {
    feed();
    return health() == vda5050::VehicleHealth::kOnline;
  }));
  EXPECT_EQ(registry.find("v2")->health, vda5050::VehicleHealth::kUnknown) << "A2 untouched";

  // A broker restart in the middle: both sides reconnect.
  broker.stop();
  broker.start();
  ASSERT_TRUE(waitFor([&] { return master.client->connected(); }, 15s));

  // Releases as the traffic layer gives them: base n0..n2 then more, with a drop at n4.
  vda5050::OrderBuilder builder({"acme", "A1", "small", 0.2});
  const auto node = [](int n) { return vda5050::ReleaseNode{n, static_cast<double>(n), 0.0}; };
  vda5050::ReleaseInput rel;
  rel.base = {node(0), node(1), node(2)};
  rel.horizon = {node(3)};
  rel.actions = {{4, {"drop", "t1-drop", "HARD", {}, {}}}};
  auto first = builder.start("t1", rel, 0);
  ASSERT_TRUE(first) << first.error().message;
  registry.ordered("v1", *first);
  // Sent again every half second until the vehicle has it: after the restart its subscription
  // may lag, and a repeated order is a duplicate the vehicle discards.
  auto resent = std::chrono::steady_clock::now() - 1s;
  const auto sendUntilHeld = [&](const vda5050::Order& o) {
    if (std::chrono::steady_clock::now() - resent > 500ms) {
      master.client->publish("uagv/v2/acme/A1/order", vda5050::toJson(o).dump(), 0, false);
      resent = std::chrono::steady_clock::now();
    }
  };
  ASSERT_TRUE(waitFor(
      [&] {
        feed();
        const auto* v = registry.find("v1");
        if (!v->state || v->state->orderId != "t1") {
          sendUntilHeld(*first);
        }
        return v->state && v->state->lastNodeId == "n2" && v->state->newBaseRequest.value_or(false);
      },
      20s))
      << "the vehicle did not reach the base end";
  rel.base = {node(2), node(3), node(4)};
  rel.horizon = {};
  auto update = builder.extend(rel, registry.find("v1")->state->lastNodeSequenceId, 0);
  ASSERT_TRUE(update && update->has_value());
  registry.ordered("v1", **update);
  resent = std::chrono::steady_clock::now() - 1s;

  // It drives on to n4, then vanishes: the last will marks it offline.
  ASSERT_TRUE(waitFor(
      [&] {
        feed();
        const auto* v = registry.find("v1");
        if (v->health == vda5050::VehicleHealth::kOnline && v->state->orderUpdateId == 0) {
          sendUntilHeld(**update);
        }
        return health() == vda5050::VehicleHealth::kOffline;
      },
      20s))
      << "health " << vda5050::toString(health()) << " (" << registry.find("v1")->reason << ")";
  EXPECT_EQ(registry.find("v1")->state->lastNodeId, "n4");
  EXPECT_EQ(registry.find("v1")->state->orderUpdateId, 1U);
  int status = 0;
  ASSERT_EQ(waitpid(child, &status, 0), child);
  EXPECT_EQ(WEXITSTATUS(status), 0);
  EXPECT_FALSE(registry.refusals().count("node_never_ordered"));
}

}  // namespace
}  // namespace fleet
