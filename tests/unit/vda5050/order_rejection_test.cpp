#include "fleet/vda5050/order_rejection.hpp"

#include <gtest/gtest.h>

namespace fleet::vda5050 {
namespace {

VehicleError error(std::string type, std::vector<std::pair<std::string, std::string>> refs,
                   std::optional<std::string> description = "why") {
  return {std::move(type), "WARNING", std::move(description), std::move(refs)};
}

TEST(Vda5050OrderRejection, AnOrderErrorNamingTheOrderAndUpdateIsItsRejection) {
  State s;
  s.orderId = "t1-1";
  s.errors = {error("noRouteError", {{"orderId", "t1-2"}, {"orderUpdateId", "0"}}, "starts at 'n1146'")};
  const auto r = findOrderRejection(s, "t1-2", 0);
  ASSERT_TRUE(r);
  EXPECT_EQ(r->errorType, "noRouteError");
  EXPECT_EQ(r->description, "starts at 'n1146'");
  EXPECT_FALSE(findOrderRejection(s, "t1-3", 0)) << "another order";
  EXPECT_FALSE(findOrderRejection(s, "t1-2", 1)) << "another update";
}

TEST(Vda5050OrderRejection, EveryOrderErrorTypeCountsOthersDoNot) {
  for (const char* type : {"validationError", "orderError", "orderUpdateError", "noRouteError"}) {
    State s;
    s.errors = {error(type, {{"orderId", "o"}})};
    EXPECT_TRUE(findOrderRejection(s, "o", 3)) << type << ": without an orderUpdateId it names the order";
  }
  State s;
  s.errors = {error("batteryLowError", {{"orderId", "o"}})};
  EXPECT_FALSE(findOrderRejection(s, "o", 0));
}

TEST(Vda5050OrderRejection, ATakenOrderIsNotRejectedWhateverOldErrorsSay) {
  State s;
  s.orderId = "o";
  s.orderUpdateId = 2;
  s.errors = {error("orderUpdateError", {{"orderId", "o"}, {"orderUpdateId", "2"}})};
  EXPECT_FALSE(findOrderRejection(s, "o", 2));
  EXPECT_FALSE(findOrderRejection(s, "o", 1));
  s.errors.push_back(error("orderUpdateError", {{"orderId", "o"}, {"orderUpdateId", "3"}}));
  EXPECT_TRUE(findOrderRejection(s, "o", 3)) << "the vehicle has update 2 and rejected 3";
}

TEST(Vda5050OrderRejection, ErrorsWithMissingOrOddFieldsAreReadWithoutHarm) {
  State s;
  s.errors = {error("noRouteError", {}),                                                     // names nothing
              error("orderError", {{"orderId", ""}}),                                        // empty id
              error("orderError", {{"orderId", "o"}, {"orderUpdateId", "x7"}}),              // not a number
              error("orderError", {{"orderId", "o"}, {"orderUpdateId", "99999999999999"}}),  // too large
              error("", {{"orderId", "o"}})};
  EXPECT_FALSE(findOrderRejection(s, "o", 0));
  EXPECT_FALSE(findOrderRejection(s, "", 0));
  s.errors.push_back(error("validationError", {{"orderId", "o"}}, std::nullopt));
  const auto r = findOrderRejection(s, "o", 0);
  ASSERT_TRUE(r);
  EXPECT_FALSE(r->description.empty()) << "a rejection without a description still says so";
}

}  // namespace
}  // namespace fleet::vda5050
