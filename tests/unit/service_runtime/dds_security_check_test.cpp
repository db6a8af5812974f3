// The check before a service joins DDS: missing security files are named, and a deployment that
// requires DDS Security (FLEET_DDS_SECURITY=required) refuses a configuration without it.

#include "fleet/service/dds_security_check.hpp"

#include <gtest/gtest.h>

#include <map>

using fleet::service::DdsSecurityInputs;
using fleet::service::ddsSecurityProblems;

namespace {

const char* const kSecurity = R"(<CycloneDDS><Domain id="any"><Security>
  <Authentication>
    <IdentityCA>file:${FLEET_DDS_SECURITY_DIR:-/site}/ca.pem</IdentityCA>
    <IdentityCertificate>file:${FLEET_DDS_SECURITY_DIR:-/site}/agents/cert.pem</IdentityCertificate>
    <PrivateKey>file:${FLEET_DDS_SECURITY_DIR:-/site}/agents/key.pem</PrivateKey>
  </Authentication>
  <AccessControl>
    <Governance>file:${FLEET_DDS_SECURITY_DIR:-/site}/governance.p7s</Governance>
  </AccessControl>
  <Cryptographic/>
</Security></Domain></CycloneDDS>)";

struct World {
  std::map<std::string, std::string> env;
  std::map<std::string, std::string> files;
  DdsSecurityInputs inputs() const {
    DdsSecurityInputs in;
    in.env = [this](const std::string& n) -> std::optional<std::string> {
      auto it = env.find(n);
      return it == env.end() ? std::nullopt : std::optional<std::string>(it->second);
    };
    in.readFile = [this](const std::string& p, std::string& why) -> std::optional<std::string> {
      auto it = files.find(p);
      if (it == files.end()) {
        why = "No such file or directory";
        return std::nullopt;
      }
      return it->second;
    };
    return in;
  }
  void site(const std::string& dir) {
    for (const char* f : {"/ca.pem", "/agents/cert.pem", "/agents/key.pem", "/governance.p7s"}) {
      files[dir + f] = "x";
    }
  }
};

}  // namespace

TEST(DdsSecurityCheck, NothingSetIsFine) {
  World w;
  EXPECT_TRUE(ddsSecurityProblems(w.inputs()).empty());
}

TEST(DdsSecurityCheck, ACompleteSiteIsFine) {
  World w;
  w.env["CYCLONEDDS_URI"] = "file:///p.xml,file:///run/dds/agents/security.xml";
  w.env["FLEET_DDS_SECURITY"] = "required";
  w.env["FLEET_DDS_SECURITY_DIR"] = "/run/dds";
  w.files["/p.xml"] = "<CycloneDDS/>";
  w.files["/run/dds/agents/security.xml"] = kSecurity;
  w.site("/run/dds");
  EXPECT_TRUE(ddsSecurityProblems(w.inputs()).empty());
}

TEST(DdsSecurityCheck, AMissingKeyIsNamedWithTheVariableExpanded) {
  World w;
  w.env["CYCLONEDDS_URI"] = "file:///s.xml";
  w.files["/s.xml"] = kSecurity;
  w.site("/site");  // FLEET_DDS_SECURITY_DIR unset: the default of the file
  w.files.erase("/site/agents/key.pem");
  const auto p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("<PrivateKey> /site/agents/key.pem (in /s.xml) cannot be read"), std::string::npos)
      << p[0];
  EXPECT_NE(p[0].find("scripts/dds-security"), std::string::npos) << p[0];
}

TEST(DdsSecurityCheck, AMissingConfigurationFileIsNamed) {
  World w;
  w.env["CYCLONEDDS_URI"] = "file:///run/dds/agents/security.xml";
  const auto p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("/run/dds/agents/security.xml, which cannot be read"), std::string::npos) << p[0];
}

TEST(DdsSecurityCheck, RequiredRefusesAConfigurationWithoutSecurity) {
  World w;
  w.env["FLEET_DDS_SECURITY"] = "required";
  w.env["CYCLONEDDS_URI"] = "file:///p.xml";
  w.files["/p.xml"] = "<CycloneDDS/>";
  auto p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("FLEET_DDS_SECURITY=required"), std::string::npos) << p[0];
  EXPECT_NE(p[0].find("<Security>"), std::string::npos) << p[0];
  w.env.erase("CYCLONEDDS_URI");  // the built-in loopback configuration has none either
  EXPECT_EQ(ddsSecurityProblems(w.inputs()).size(), 1u);
  w.env["FLEET_DDS_SECURITY"] = "off";
  EXPECT_TRUE(ddsSecurityProblems(w.inputs()).empty());
}

TEST(DdsSecurityCheck, SecurityWithoutCryptographyIsNotEnough) {
  World w;
  w.env["FLEET_DDS_SECURITY"] = "required";
  w.env["CYCLONEDDS_URI"] = "<Security><Authentication/><AccessControl/></Security>";
  const auto p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("<Cryptographic>"), std::string::npos) << p[0];
}

TEST(DdsSecurityCheck, AnUnknownModeIsRefused) {
  World w;
  w.env["FLEET_DDS_SECURITY"] = "yes";
  const auto p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("expected required or off"), std::string::npos) << p[0];
}

TEST(DdsSecurityCheck, AnEmptyKeyOrASystemdPlaceholderIsNamed) {
  World w;
  w.env["CYCLONEDDS_URI"] = "file:///s.xml";
  w.files["/s.xml"] = kSecurity;
  w.site("/site");
  w.files["/site/agents/key.pem"] = "";
  auto p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("/site/agents/key.pem (in /s.xml) cannot be read: the file is empty"),
            std::string::npos)
      << p[0];
  // The unit's SetCredential= fallback when its LoadCredential= source is missing.
  w.files["/site/agents/key.pem"] = "not loaded: /etc/fleet/dds/agents/key.pem is missing";
  p = ddsSecurityProblems(w.inputs());
  ASSERT_EQ(p.size(), 1u);
  EXPECT_NE(p[0].find("cannot be read: not loaded: /etc/fleet/dds/agents/key.pem is missing"),
            std::string::npos)
      << p[0];
}
