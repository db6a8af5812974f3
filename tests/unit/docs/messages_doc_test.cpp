// docs/messages.md against what it documents: every struct, enum, enumerator and typedef of
// idl/fleet.idl is named in it, every topic the transport declares (traits.hpp) has its row in the
// topic table with its type and QoS profile, and every file it names or links to exists.

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

const fs::path kRoot = FLEET_SOURCE_DIR;

std::string slurp(const fs::path& p) {
  std::ifstream in(p);
  EXPECT_TRUE(in) << "cannot read " << p;
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// Every match of group `group` of `pattern` in `text`.
std::vector<std::string> all(const std::string& text, const std::regex& pattern, int group = 1) {
  std::vector<std::string> out;
  for (std::sregex_iterator it(text.begin(), text.end(), pattern), end; it != end; ++it) {
    out.push_back((*it)[group].str());
  }
  return out;
}

bool namesWord(const std::string& text, const std::string& word) {
  return std::regex_search(text, std::regex("(^|[^A-Za-z0-9_])" + word + "([^A-Za-z0-9_]|$)"));
}

/// The IDL without comments (a name in a comment is not a type).
std::string idlCode() {
  const std::string idl = slurp(kRoot / "idl/fleet.idl");
  return std::regex_replace(idl, std::regex(R"(//[^\n]*)"), "");
}

}  // namespace

TEST(DocsMessages, EveryIdlTypeAndEnumeratorIsNamed) {
  const std::string doc = slurp(kRoot / "docs/messages.md");
  const std::string idl = idlCode();
  const auto types = all(idl, std::regex(R"(\b(?:struct|enum)\s+(\w+))"));
  ASSERT_GE(types.size(), 40U) << "idl/fleet.idl did not parse as expected";
  for (const auto& t : types) {
    EXPECT_TRUE(namesWord(doc, t)) << "docs/messages.md does not name " << t << " (idl/fleet.idl)";
  }
  for (const auto& t : all(idl, std::regex(R"(\btypedef\s+[^;]*\s(\w+)\s*;)"))) {
    EXPECT_TRUE(namesWord(doc, t)) << "docs/messages.md does not name the typedef " << t;
  }
  for (const auto& body : all(idl, std::regex(R"(\benum\s+\w+\s*\{([^}]*)\})"))) {
    for (const auto& value : all(body, std::regex(R"((\w+))"))) {
      EXPECT_TRUE(namesWord(doc, value)) << "docs/messages.md does not name the enumerator " << value;
    }
  }
}

TEST(DocsMessages, EveryTopicHasItsRowWithTypeAndQos) {
  const std::string doc = slurp(kRoot / "docs/messages.md");
  const std::string traits = slurp(kRoot / "libs/transport/include/fleet/transport/traits.hpp");
  const std::regex declared(R"re(FLEET_DECLARE_TRAITS\((\w+),\s*\w+,\s*"(\w+)",\s*qos::(\w+)\()re");
  int topics = 0;
  for (std::sregex_iterator it(traits.begin(), traits.end(), declared), end; it != end; ++it, ++topics) {
    const std::string type = (*it)[1], topic = (*it)[2], qos = (*it)[3];
    std::smatch row;
    const std::regex rowPattern("\\n\\| `" + topic + "` \\| `(\\w+)` \\|[^\\n]*");
    ASSERT_TRUE(std::regex_search(doc, row, rowPattern))
        << "docs/messages.md's topic table has no row for the topic " << topic;
    EXPECT_EQ(row[1].str(), type) << "topic " << topic << ": the table names another type";
    EXPECT_NE(row.str().find("`" + qos), std::string::npos)
        << "topic " << topic << ": the table's row does not name its QoS profile qos::" << qos;
  }
  EXPECT_GE(topics, 18) << "traits.hpp did not parse as expected";
}

TEST(DocsMessages, EveryFileNamedOrLinkedExists) {
  const std::string doc = slurp(kRoot / "docs/messages.md");
  std::set<std::string> missing;
  // Paths in code spans: from the repository's root, or an include path (fleet/...) under a
  // library's or service's include/ folder.
  for (const auto& p : all(doc, std::regex(R"(`([A-Za-z0-9_./-]+\.(?:hpp|cpp|idl|md|yaml|json|py))`)"))) {
    bool found = fs::exists(kRoot / p);
    if (!found && p.rfind("fleet/", 0) == 0) {
      for (const auto* top : {"libs", "services"}) {
        for (const auto& dir : fs::directory_iterator(kRoot / top)) {
          found = found || fs::exists(dir.path() / "include" / p);
        }
      }
    }
    if (!found) {
      missing.insert(p);
    }
  }
  // Markdown links: relative to docs/, anchors dropped.
  for (auto link : all(doc, std::regex(R"(\]\(([^)#:]+)(?:#[^)]*)?\))"))) {
    if (!fs::exists(kRoot / "docs" / link)) {
      missing.insert(link);
    }
  }
  for (const auto& m : missing) {
    ADD_FAILURE() << "docs/messages.md names " << m << ", which does not exist";
  }
}
