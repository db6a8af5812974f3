// docs/openapi.yaml is the WMS adapter's contract: the server serves exactly the paths and methods
// it lists, with the scopes it gives (x-scope), and each operation has an operationId and tags.
// (Every response the API tests receive is checked against its schemas by the fixtures'
// SpecWatch; the checks themselves are tested here.)

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <regex>
#include <set>

#include "api_fixture.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using fleet::test::OpenApiContract;
using fleet::test::SchemaCheck;
using nlohmann::json;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

namespace {

/// A route's regex as a path template with "{}" for each parameter, or nothing when the pattern
/// holds more than the literal path and "([^/]+)" groups (a form this test cannot compare).
std::optional<std::string> templateOfRoute(const std::string& pattern) {
  const std::string t = std::regex_replace(pattern, std::regex(R"(\(\[\^/\]\+\))"), "{}");
  if (t.find_first_of("()[]*+?\\|^$") != std::string::npos) {
    return std::nullopt;
  }
  return t;
}

std::string templateOfSpecPath(const std::string& path) {
  return std::regex_replace(path, std::regex(R"(\{[^}]+\})"), "{}");
}

const std::string kRobot = R"({"id": "r1", "pose": {"x": 1, "y": 2, "theta": 0}, "heading_deg": 0, "v": 0,
  "w": 0, "mode": "idle", "activity": "no_task", "fault": false, "paused": false, "battery": 0.5, "task": "", "radius": 0.3,
  "position_sigma": 0.01, "stamp_ns": 5, "people_seen": [], "people_seen_stamp_ns": null})";

class ApiContract : public Api {};

}  // namespace

TEST_F(ApiContract, EveryRouteIsInTheSpecAndEverySpecPathIsARoute) {
  const HttpApi api({}, stations_, gateway_, view_, clock_);
  std::map<std::string, std::string> served;  // "GET /v1/tasks/{}" -> scope
  for (const auto& r : api.routeTable()) {
    const auto t = templateOfRoute(r.pattern);
    ASSERT_TRUE(t) << r.method << " route \"" << r.pattern
                   << "\" is not a path with ([^/]+) parameters: register one route per documented path";
    served[r.method + " " + *t] = toString(r.scope);
  }
  std::map<std::string, std::string> documented;
  for (const auto& op : OpenApiContract::shipped().operations()) {
    documented[op.method + " " + templateOfSpecPath(op.path)] = op.spec->value("x-scope", "(no x-scope)");
  }
  for (const auto& [route, scope] : served) {
    if (!documented.contains(route)) {
      ADD_FAILURE() << "the server serves " << route << " but docs/openapi.yaml does not list it";
    } else {
      EXPECT_EQ(documented[route], scope)
          << route << ": docs/openapi.yaml's x-scope differs from the route's";
    }
  }
  for (const auto& [op, scope] : documented) {
    EXPECT_TRUE(served.contains(op)) << "docs/openapi.yaml lists " << op
                                     << " but the server has no such route";
  }
  EXPECT_GE(served.size(), 20U);
}

TEST_F(ApiContract, EveryOperationHasAnOperationIdAndTags) {
  std::set<std::string> ids;
  for (const auto& op : OpenApiContract::shipped().operations()) {
    const std::string where = op.method + " " + op.path;
    ASSERT_TRUE(op.spec->contains("operationId")) << where << " has no operationId";
    EXPECT_TRUE(ids.insert(op.spec->at("operationId").get<std::string>()).second)
        << where << ": operationId used twice";
    ASSERT_TRUE(op.spec->contains("tags") && !op.spec->at("tags").empty()) << where << " has no tags";
  }
}

TEST_F(ApiContract, AResponseThatBreaksTheSpecIsNamedWithItsField) {
  const auto& spec = OpenApiContract::shipped();
  auto check = [&](const std::string& method, const std::string& path, int status, const std::string& type,
                   const std::string& body) { return spec.checkResponse(method, path, status, type, body); };
  const std::string robots = R"({"robots": [)" + kRobot + R"(], "count": 1})";
  EXPECT_THAT(check("GET", "/v1/robots", 200, "application/json", robots), IsEmpty());
  EXPECT_THAT(check("GET", "/v1/robots/r1", 200, "application/json; charset=utf-8", kRobot), IsEmpty());

  json flying = json::parse(robots);
  flying["robots"][0]["mode"] = "flying";
  EXPECT_THAT(check("GET", "/v1/robots", 200, "application/json", flying.dump()),
              ElementsAre(AllOf(HasSubstr("GET /v1/robots -> 200"), HasSubstr("$.robots[0].mode"),
                                HasSubstr("\"flying\" is not one of"))));
  json missing = json::parse(robots);
  missing.erase("count");
  EXPECT_THAT(check("GET", "/v1/robots", 200, "application/json", missing.dump()),
              ElementsAre(HasSubstr("$.count: required but missing")));
  EXPECT_THAT(check("GET", "/v1/health", 200, "application/json",
                    R"({"status": "ok", "fleet_manager": "online", "uptime": 3})"),
              ElementsAre(HasSubstr("$.uptime: not in the schema")));
  EXPECT_THAT(check("GET", "/v1/tasks/t-1", 200, "application/json", R"({"id": "t-1", "state": "queued"})"),
              ElementsAre(AllOf(HasSubstr("/v1/tasks/t-1"), HasSubstr("$.updated_ns: required"))));
  EXPECT_THAT(check("GET", "/v1/tasks", 200, "text/plain", "tasks"), ElementsAre(HasSubstr("content type")));
  EXPECT_THAT(check("GET", "/v1/tasks", 200, "application/json", "{"), ElementsAre(HasSubstr("not JSON")));
  EXPECT_THAT(check("GET", "/", 302, "text/plain", "moved"), ElementsAre(HasSubstr("no body")));
  // A status the operation does not list falls to its default: the error body.
  EXPECT_THAT(
      check("GET", "/v1/robots", 413, "application/json", R"({"error": "too_large", "message": "x"})"),
      IsEmpty());
  EXPECT_THAT(check("GET", "/v1/robots", 413, "application/json", R"({"message": "x"})"),
              ElementsAre(HasSubstr("$.error: required but missing")));
  // No route: the server's error body too.
  EXPECT_THAT(check("GET", "/v2/nothing", 404, "application/json", R"({"error": "not_found"})"), IsEmpty());
  // oneOf: a single result or a batch, not both and not neither.
  EXPECT_THAT(
      check("POST", "/v1/tasks", 200, "application/json", R"({"results": [{"id": "a", "status": 200}]})"),
      IsEmpty());
  EXPECT_THAT(
      check("POST", "/v1/tasks", 200, "application/json", R"({"results": [{"id": "a", "status": "ok"}]})"),
      ElementsAre(HasSubstr("matches none"), HasSubstr("$.results[0].status: expected integer")));
}

TEST_F(ApiContract, TheSchemaCheckerRefusesWhatItDoesNotUnderstand) {
  const json doc = json::parse(R"({"components": {"schemas": {
    "N": {"type": "integer", "nullable": true, "minimum": 0},
    "Odd": {"type": "string", "format": "uuid"}}}})");
  const SchemaCheck check(doc);
  EXPECT_THAT(check.problems(nullptr, {{"$ref", "#/components/schemas/N"}}), IsEmpty());
  EXPECT_THAT(check.problems(-1, {{"$ref", "#/components/schemas/N"}}),
              ElementsAre(HasSubstr("below the minimum")));
  EXPECT_THAT(check.problems("x", {{"$ref", "#/components/schemas/Odd"}}),
              ElementsAre(HasSubstr("\"format\" is not understood")));
  EXPECT_THAT(check.problems(1, {{"$ref", "#/components/schemas/Gone"}}),
              ElementsAre(HasSubstr("names nothing")));
}

TEST_F(ApiContract, YamlScalarsReadAsNodeReadsThem) {
  const auto j =
      fleet::test::yamlToJson(YAML::Load(R"({a: 1, b: "1", c: true, d: 'off', e: off, f: 2.5, g: null})"));
  EXPECT_EQ(j, json::parse(R"({"a": 1, "b": "1", "c": true, "d": "off", "e": "off", "f": 2.5, "g": null})"));
}
