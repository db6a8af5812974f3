// A VDA 5050 vehicle charges through the whole stack (`fleetctl loadtest --vda5050` on the
// low-battery scenario: one robot, a VDA 5050 vehicle, starting just above the battery threshold).
// It finishes its transport task; the fleet manager sends it to a charger; at the charger the
// bridge sends startCharging, and the simulated world charges it only from then on; the manager
// ends the charge task at its charge_until (0.9), the bridge sends stopCharging, and the vehicle
// drives home. No order is rejected (none reaches it while it charges), no contact.

#include <gtest/gtest.h>
#include <sqlite3.h>
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <sstream>
#include <string>
#include <vector>

#include "test_process.hpp"

namespace fs = std::filesystem;
using nlohmann::json;

TEST(Vda5050Charging, AVehicleLowOnBatteryChargesAtAChargerAndGoesOnAfterwards) {
  const fs::path out = fs::temp_directory_path() / ("vda5050-charge-" + std::to_string(getpid()));
  fs::remove_all(out);
  fleet::test::ChildProcess run(
      FLEET_BINARY_DIR "/services/fleetctl/fleetctl",
      {"loadtest", "--scenario", FLEET_SOURCE_DIR "/sim/scenarios/low_battery.json", "--vda5050", "1",
       "--tasks", "1", "--duration",
       "210",  // the charge task ends near 165 s (charging at 2 %/s from ~0.15)
       "--out", out.string(), "--domain", std::to_string(fleet::test::uniqueDomain()), "--report-script", "",
       "--wall-limit", "300"});
  ASSERT_EQ(run.wait(std::chrono::seconds(340)), 0) << "see " << out;
  const json r = json::parse(std::ifstream(out / "loadtest.json"));
  EXPECT_EQ(r["accounting"]["done"], 1) << r["accounting"].dump();
  EXPECT_EQ(r["safety"]["contacts"]["robot_shelf"], 0);
  const json sim = json::parse(std::ifstream(out / "sim_summary.json"));
  EXPECT_EQ(sim["vda5050"]["rejected_orders"], 0) << "an order reached the vehicle while it charged";
  EXPECT_GT(sim["per_robot"]["r1"]["battery"].get<double>(), 0.85) << sim["per_robot"].dump();
  EXPECT_LT(sim["per_robot"]["r1"]["battery"].get<double>(), 0.95) << "charged on after the manager ended it";

  // The charge task, as the fleet manager recorded it.
  sqlite3* db = nullptr;
  ASSERT_EQ(sqlite3_open_v2((out / "fleet.db").c_str(), &db, SQLITE_OPEN_READONLY, nullptr), SQLITE_OK);
  sqlite3_stmt* q = nullptr;
  ASSERT_EQ(sqlite3_prepare_v2(db,
                               "select task_id, to_state, robot, reason from transitions where task_id like "
                               "'charge.%' order by seq",
                               -1, &q, nullptr),
            SQLITE_OK);
  std::vector<std::string> states;
  std::string doneReason;
  while (sqlite3_step(q) == SQLITE_ROW) {
    const std::string to = reinterpret_cast<const char*>(sqlite3_column_text(q, 1));
    states.push_back(to);
    if (to == "done" && sqlite3_column_text(q, 3) != nullptr) {
      doneReason = reinterpret_cast<const char*>(sqlite3_column_text(q, 3));
    }
  }
  sqlite3_finalize(q);
  sqlite3_close(db);
  ASSERT_FALSE(states.empty()) << "no charge task";
  EXPECT_EQ(states.back(), "done");
  EXPECT_EQ(std::count(states.begin(), states.end(), "requeued"), 0) << "startCharging failed";
  EXPECT_NE(doneReason.find("charged to"), std::string::npos) << doneReason;

  // The bridge said what it did.
  std::ostringstream log;
  log << std::ifstream(out / "vda5050_bridge.log").rdbuf();
  const std::string text = log.str();
  EXPECT_EQ(text.find("startCharging failed"), std::string::npos);
  if (!::testing::Test::HasFailure()) {
    fs::remove_all(out);  // kept for a look when something failed
  }
}
