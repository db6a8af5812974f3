// Tokens with names and scopes from a file re-read without a restart, no token in
// A URL, an audit line per state-changing request, and https with a certificate from
// scripts/dds-security.

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>

#include "api_fixture.hpp"

using namespace fleet;
using namespace fleet::wms;
using namespace fleet::wms::testing;
using ::testing::HasSubstr;
namespace fs = std::filesystem;

namespace {

const std::string kTask = R"({"id": "t-1", "kind": "transport", "pickup": "P-1", "dropoff": "D-1"})";
const std::string kReader = "reader-0123456789abcdef";
const std::string kWms = "wms-0123456789abcdef0123";
const std::string kFloor = "floor-0123456789abcdef01";

httplib::Headers bearer(const std::string& token) {
  return {{"Authorization", "Bearer " + token}};
}

class Security : public Api {
 protected:
  void SetUp() override {
    dir_ = fs::temp_directory_path() / ("wms-security-" + std::to_string(std::random_device{}()));
    fs::create_directories(dir_);
    tokenFile_ = (dir_ / "tokens").string();
    writeTokens("# name scopes token\nreader read " + kReader + "\nwms read,submit " + kWms +
                "\nfloor read,operate " + kFloor + "\n");
  }
  void TearDown() override {
    Api::TearDown();
    fs::remove_all(dir_);
  }
  /// Replaces the file as an editor or a deployment tool does: a new file renamed over the old.
  void writeTokens(const std::string& text) {
    const auto tmp = tokenFile_ + ".new";
    std::ofstream(tmp) << text;
    fs::rename(tmp, tokenFile_);
  }
  void startWithTokens(ApiSettings s = {}) {
    s.tokenFile = tokenFile_;
    start(s);
  }
  fs::path dir_;
  std::string tokenFile_;
};

std::vector<json> linesOf(const std::string& path) {
  std::ifstream in(path);
  std::vector<json> out;
  for (std::string l; std::getline(in, l);) {
    out.push_back(json::parse(l));
  }
  return out;
}

}  // namespace

TEST(TokenFile, NamesScopesAndTokensOrAnErrorNamingTheLine) {
  auto t =
      TokenStore::parse("# comment\n\nwms read,submit " + kWms + "\nops operate " + kFloor + "\n", "tokens");
  ASSERT_TRUE(t) << t.error().message;
  ASSERT_EQ(t->size(), 2u);
  EXPECT_EQ((*t)[0].who.name, "wms");
  EXPECT_EQ((*t)[0].who.scopes, (std::set<Scope>{Scope::Read, Scope::Submit}));
  EXPECT_EQ((*t)[1].who.scopes, (std::set<Scope>{Scope::Operate}));
  auto legacy = TokenStore::parse("s3cret\n", "tokens");
  ASSERT_TRUE(legacy);
  EXPECT_EQ((*legacy)[0].who.scopes.size(), 3u) << "a lone token (the old format) has every scope";
  // The old format took the whole first line: a placeholder with spaces (deploy/kube) still loads.
  legacy = TokenStore::parse("REPLACE-ME: kubectl create secret generic x\n", "tokens");
  ASSERT_TRUE(legacy);
  EXPECT_EQ((*legacy)[0].digest, TokenStore::digestOf("REPLACE-ME: kubectl create secret generic x"));
  EXPECT_THAT(TokenStore::parse("wms write " + kWms, "tokens").error().message,
              HasSubstr("tokens:1: scope \"write\""));
  EXPECT_THAT(TokenStore::parse("a read " + kWms + "\nb read short", "tokens").error().message,
              HasSubstr("tokens:2: the token of \"b\" is shorter than 16"));
  EXPECT_THAT(TokenStore::parse("a read " + kWms + "\nb read " + kWms, "tokens").error().message,
              HasSubstr("also another name's"));
  EXPECT_THAT(TokenStore::parse("a read " + kWms + "\na read " + kFloor, "tokens").error().message,
              HasSubstr("appears twice"));
  EXPECT_FALSE(TokenStore::parse("# nothing\n", "tokens"));
}

TEST_F(Security, EachScopeAllowsItsRoutesOnly) {
  startWithTokens();
  EXPECT_EQ(client_->Get("/v1/health")->status, 200) << "probes carry no token";
  EXPECT_EQ(client_->Get("/v1/tasks")->status, 401);
  auto r = post(kTask, bearer(kReader));
  EXPECT_EQ(r->status, 403);
  EXPECT_THAT(r->body, HasSubstr("lacks the \\\"submit\\\" scope"));
  EXPECT_TRUE(gateway_.bodies.empty()) << "a read token stored a task";
  EXPECT_EQ(client_->Get("/v1/tasks", bearer(kReader))->status, 200);
  EXPECT_EQ(post(kTask, bearer(kWms))->status, 201);
  EXPECT_EQ(client_->Post("/v1/tasks/t-1/pause", bearer(kWms), "", "application/json")->status, 403);
  EXPECT_EQ(client_->Post("/v1/tasks/t-1/pause", bearer(kFloor), "", "application/json")->status, 200);
  EXPECT_EQ(client_->Delete("/v1/tasks/t-1", bearer(kFloor))->status, 403);
  EXPECT_EQ(client_->Delete("/v1/tasks/t-1", bearer(kWms))->status, 200);
  EXPECT_EQ(gateway_.controls.size(), 2u) << "only the allowed pause and cancel reached the manager";
}

TEST_F(Security, ATokenFileEditTakesEffectWithoutRestart) {
  startWithTokens();
  ASSERT_EQ(post(kTask, bearer(kWms))->status, 201);
  const std::string rotated = "wms-rotated-0123456789abcdef";
  writeTokens("wms read,submit " + rotated + "\n");
  EXPECT_EQ(client_->Get("/v1/tasks", bearer(kWms))->status, 401) << "the replaced token still works";
  EXPECT_EQ(client_->Get("/v1/tasks", bearer(rotated))->status, 200) << "the new token is not taken";
  // A broken edit keeps the tokens that were there and says why.
  writeTokens("wms read,submit,fly " + rotated + "\n");
  auto m = client_->Get("/v1/metrics", bearer(rotated));
  ASSERT_EQ(m->status, 200);
  EXPECT_THAT(json::parse(m->body)["http"]["token_file_problem"].get<std::string>(),
              HasSubstr("scope \"fly\""));
  EXPECT_EQ(api_->tokens().reloads(), 1u);
}

TEST_F(Security, ATokenInTheUrlIsRefused) {
  startWithTokens();
  for (const std::string& target :
       std::vector<std::string>{"/v1/tasks?access_token=" + kReader, "/v1/tasks?token=" + kReader,
                                "/v1/tasks?state=queued&x=" + kReader, "/v1/health?access_token=x"}) {
    auto r = client_->Get(target);
    ASSERT_TRUE(r);
    EXPECT_EQ(r->status, 400) << target;
    EXPECT_EQ(json::parse(r->body)["error"], "token_in_url") << target;
    // Even with a valid header: the token in the URL has leaked and the request says so.
    EXPECT_EQ(client_->Get(target, bearer(kReader))->status, 400) << target;
  }
  EXPECT_EQ(client_->Get("/v1/tasks?state=queued", bearer(kReader))->status, 200);
}

TEST_F(Security, TheAuditLogHoldsOneLinePerStateChangingRequest) {
  ApiSettings s;
  s.auditLog = (dir_ / "audit.log").string();
  startWithTokens(s);
  ASSERT_EQ(post(kTask, bearer(kWms))->status, 201);
  ASSERT_EQ(post(kTask)->status, 401);
  ASSERT_EQ(post(kTask, bearer(kReader))->status, 403);
  ASSERT_EQ(client_->Get("/v1/tasks", bearer(kReader))->status, 200);  // reads are not audited
  ASSERT_EQ(client_->Post("/v1/tasks/t-1/pause", bearer(kFloor), "", "application/json")->status, 200);
  ASSERT_EQ(client_->Delete("/v1/tasks/t-1", bearer(kWms))->status, 200);
  const auto lines = linesOf(s.auditLog);
  ASSERT_EQ(lines.size(), 5u);
  EXPECT_EQ(lines[0]["who"], "wms");
  EXPECT_EQ(lines[0]["method"], "POST");
  EXPECT_EQ(lines[0]["path"], "/v1/tasks");
  EXPECT_EQ(lines[0]["status"], 201);
  EXPECT_EQ(lines[0]["outcome"], "done");
  EXPECT_EQ(lines[0]["what"]["tasks"], json::array({"t-1"}));
  EXPECT_TRUE(lines[0]["time"].get<std::string>().ends_with("Z"));
  EXPECT_EQ(lines[1]["who"], "-");
  EXPECT_EQ(lines[1]["status"], 401);
  EXPECT_EQ(lines[1]["outcome"], "refused");
  EXPECT_EQ(lines[2]["who"], "reader");
  EXPECT_EQ(lines[2]["status"], 403);
  EXPECT_EQ(lines[3]["who"], "floor");
  EXPECT_EQ(lines[3]["what"]["action"], "pause");
  EXPECT_EQ(lines[4]["what"], json::parse(R"({"task": "t-1", "action": "cancel"})"));
  for (const auto& l : lines) {
    EXPECT_EQ(l.dump().find("0123456789abcdef"), std::string::npos) << "a token in the audit log";
  }
  // Moved away by logrotate: the next line starts a new file at the path.
  fs::rename(s.auditLog, s.auditLog + ".1");
  ASSERT_EQ(post(kTask, bearer(kWms))->status, 200);
  EXPECT_EQ(linesOf(s.auditLog).size(), 1u);
}

TEST_F(Security, HttpsWithACertificateFromTheSiteScript) {
  const auto ca = dir_ / "site";
  const std::string cmd = std::string(FLEET_SOURCE_DIR) + "/scripts/dds-security https " + ca.string() +
                          " wms-adapter > /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  ApiSettings s;
  s.tls.certificateFile = (ca / "https/wms-adapter/cert.pem").string();
  s.tls.privateKeyFile = (ca / "https/wms-adapter/key.pem").string();
  startWithTokens(s);
  httplib::SSLClient tls("localhost", api_->port());
  tls.set_ca_cert_path((ca / "ca.pem").string().c_str());
  tls.enable_server_certificate_verification(true);
  auto r = tls.Post("/v1/tasks", bearer(kWms), kTask, "application/json");
  ASSERT_TRUE(r) << "https failed: " << httplib::to_string(r.error());
  EXPECT_EQ(r->status, 201);
  auto session = tls.Post("/v1/session", bearer(kFloor), "", "text/plain");
  ASSERT_TRUE(session);
  EXPECT_EQ(session->status, 201);
  EXPECT_THAT(session->get_header_value("Set-Cookie"), HasSubstr("; Secure"))
      << "a dashboard session made over https must never be sent over plain http";
  EXPECT_FALSE(client_->Get("/v1/health")) << "plain http is served on the https port";
  httplib::SSLClient untrusted("localhost", api_->port());
  untrusted.enable_server_certificate_verification(true);
  EXPECT_FALSE(untrusted.Get("/v1/health")) << "a client without the site CA trusted the certificate";
}

TEST(ApiConfig, AnUnusableTokenFileOrHalfATlsPairIsAConfigError) {
  const auto dir = fs::temp_directory_path() / ("wms-config-" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  std::ofstream(dir / "tokens") << "wms read,sumbit " << kWms << "\n";
  auto cfg = Config::fromJson(
      json{{"http", {{"token_file", (dir / "tokens").string()}, {"tls_certificate", "/x/cert.pem"}}}},
      "wms.json");
  readApiSettings(cfg);
  try {
    cfg.finish();
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("tokens:1: scope \"sumbit\""));
    EXPECT_THAT(e.what(), HasSubstr("tls_key"));
  }
  fs::remove_all(dir);
}

TEST(ApiConfig, RequiredTlsRefusesPlainHttp) {
  ::setenv("FLEET_WMS_TLS", "required", 1);
  auto plain = Config::fromJson(json{{"http", {{"host", "127.0.0.1"}}}}, "wms.json");
  readApiSettings(plain);
  try {
    plain.finish();
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("http.tls_certificate"));
    EXPECT_THAT(e.what(), HasSubstr("FLEET_WMS_TLS=required"));
  }
  auto https = Config::fromJson(
      json{{"http", {{"host", "127.0.0.1"}, {"tls_certificate", "/c.pem"}, {"tls_key", "/k.pem"}}}},
      "wms.json");
  EXPECT_TRUE(readApiSettings(https).tls.enabled());
  EXPECT_NO_THROW(https.finish());  // the files themselves are checked when the server starts
  ::setenv("FLEET_WMS_TLS", "maybe", 1);
  auto odd = Config::fromJson(json{{"http", {{"host", "127.0.0.1"}}}}, "wms.json");
  readApiSettings(odd);
  EXPECT_THROW(odd.finish(), ConfigError);
  ::setenv("FLEET_WMS_TLS", "off", 1);
  auto off = Config::fromJson(json{{"http", {{"host", "127.0.0.1"}}}}, "wms.json");
  readApiSettings(off);
  EXPECT_NO_THROW(off.finish());
  ::unsetenv("FLEET_WMS_TLS");
}

TEST(ApiConfig, AnOpenHostWithoutTokensIsRefusedUnlessAllowedOutright) {
  ::unsetenv("FLEET_WMS_TOKEN");
  auto open = Config::fromJson(json{{"http", {{"host", "0.0.0.0"}}}}, "wms.json");
  readApiSettings(open);
  try {
    open.finish();
    ADD_FAILURE() << "no ConfigError";
  } catch (const ConfigError& e) {
    EXPECT_THAT(e.what(), HasSubstr("http.host"));
    EXPECT_THAT(e.what(), HasSubstr("allow_unauthenticated"));
  }
  auto allowed =
      Config::fromJson(json{{"http", {{"host", "10.1.2.3"}, {"allow_unauthenticated", true}}}}, "wms.json");
  EXPECT_TRUE(readApiSettings(allowed).allowUnauthenticated);
  EXPECT_NO_THROW(allowed.finish());
  for (const char* host : {"127.0.0.1", "127.0.0.53", "::1", "localhost"}) {
    auto local = Config::fromJson(json{{"http", {{"host", host}}}}, "wms.json");
    readApiSettings(local);
    EXPECT_NO_THROW(local.finish()) << host;
  }
}

TEST(ApiConfig, AMissingCertificateAMismatchedKeyOrAnUnwritableAuditLogIsAConfigErrorNamingIt) {
  const auto dir = fs::temp_directory_path() / ("wms-tls-" + std::to_string(std::random_device{}()));
  fs::create_directories(dir);
  const std::string cmd = std::string(FLEET_SOURCE_DIR) + "/scripts/dds-security https " +
                          (dir / "site").string() +
                          " wms-adapter > /dev/null && openssl genpkey -algorithm EC -pkeyopt "
                          "ec_paramgen_curve:P-256 -out " +
                          (dir / "other.pem").string() + " 2> /dev/null";
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const StationMap st = stations();
  FakeGateway gateway;
  FleetView view;
  WallClock clock;
  auto problemOf = [&](const ApiSettings& s) -> std::string {
    try {
      HttpApi api(s, st, gateway, view, clock);
      return "";
    } catch (const ConfigError& e) {  // main() exits 2 on a ConfigError
      return e.what();
    } catch (const std::exception& e) {
      return std::string("not a ConfigError: ") + e.what();
    }
  };
  ApiSettings s;
  s.tls.certificateFile = (dir / "missing.pem").string();
  s.tls.privateKeyFile = (dir / "site/https/wms-adapter/key.pem").string();
  EXPECT_THAT(problemOf(s),
              ::testing::StartsWith("invalid configuration: http.tls_certificate: cannot use \"" +
                                    s.tls.certificateFile));
  s.tls.certificateFile = (dir / "site/https/wms-adapter/cert.pem").string();
  s.tls.privateKeyFile = (dir / "other.pem").string();
  const auto mismatch = problemOf(s);
  EXPECT_THAT(mismatch, ::testing::StartsWith("invalid configuration: http.tls_key: "));
  EXPECT_THAT(mismatch, HasSubstr(s.tls.privateKeyFile));
  EXPECT_THAT(mismatch, HasSubstr("mismatch"));
  s.tls.privateKeyFile = (dir / "site/https/wms-adapter/key.pem").string();
  EXPECT_EQ(problemOf(s), "") << "the matching pair";
  ApiSettings a;
  a.auditLog = (dir / "no-such-dir/audit.log").string();
  EXPECT_THAT(problemOf(a),
              ::testing::StartsWith("invalid configuration: http.audit_log: cannot open \"" + a.auditLog));
  fs::remove_all(dir);
}
