#include "fleet/service/dds_security_check.hpp"

#include <cctype>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>

#include "fleet/core/config.hpp"

namespace fleet::service {
namespace {

bool isNameChar(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_';
}

// ${VAR}, ${VAR:-default} (the default expanded in turn) and $VAR, as Cyclone expands its
// configuration; an unset variable is empty. Other forms are left as written.
std::string expand(const std::string& s, const DdsSecurityInputs& in, int depth = 0) {
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    if (s[i] != '$' || i + 1 >= s.size() || depth > 8) {
      out += s[i++];
      continue;
    }
    if (s[i + 1] == '{') {
      int level = 1;
      std::size_t j = i + 2;
      for (; j < s.size() && level > 0; ++j) {
        level += s[j] == '{' ? 1 : s[j] == '}' ? -1 : 0;
      }
      if (level != 0) {
        out += s.substr(i);
        break;
      }
      const std::string body = s.substr(i + 2, j - i - 3);
      std::size_t n = 0;
      while (n < body.size() && isNameChar(body[n])) {
        ++n;
      }
      const auto value = in.env(body.substr(0, n));
      if (n == body.size()) {
        out += value.value_or("");
      } else if (body.compare(n, 2, ":-") == 0) {
        out += value && !value->empty() ? *value : expand(body.substr(n + 2), in, depth + 1);
      } else {
        out += s.substr(i, j - i);
      }
      i = j;
    } else if (isNameChar(s[i + 1])) {
      std::size_t j = i + 1;
      while (j < s.size() && isNameChar(s[j])) {
        ++j;
      }
      out += in.env(s.substr(i + 1, j - i - 1)).value_or("");
      i = j;
    } else {
      out += s[i++];
    }
  }
  return out;
}

// The text of every <Tag>file:PATH</Tag> of the Security element's files.
void checkSecurityFiles(const std::string& xml, const std::string& origin, const DdsSecurityInputs& in,
                        std::vector<std::string>& problems) {
  static const char* const kTags[] = {"IdentityCA",    "IdentityCertificate", "PrivateKey", "CRL",
                                      "PermissionsCA", "Governance",          "Permissions"};
  for (const char* tag : kTags) {
    const std::string open = std::string("<") + tag + ">";
    const std::string close = std::string("</") + tag + ">";
    for (std::size_t at = xml.find(open); at != std::string::npos; at = xml.find(open, at + 1)) {
      const std::size_t from = at + open.size();
      const std::size_t to = xml.find(close, from);
      if (to == std::string::npos) {
        break;
      }
      std::string value = expand(xml.substr(from, to - from), in);
      const auto first = value.find_first_not_of(" \t\r\n");
      const auto last = value.find_last_not_of(" \t\r\n");
      value = first == std::string::npos ? "" : value.substr(first, last - first + 1);
      if (value.rfind("file:", 0) != 0) {
        continue;  // data:, pkcs11: ... : Cyclone's to judge
      }
      const std::string path = value.substr(5);
      std::string why;
      if (path.find('$') != std::string::npos) {
        continue;
      }
      const auto text = in.readFile(path, why);
      // A systemd unit's SetCredential= placeholder for a key whose LoadCredential= source is missing.
      const bool placeholder = text && (text->empty() || text->rfind("not loaded:", 0) == 0);
      if (placeholder) {
        why = text->empty() ? "the file is empty" : *text;
      }
      if (!text || placeholder) {
        problems.push_back("DDS Security: <" + std::string(tag) + "> " + path + " (in " + origin +
                           ") cannot be read: " + why +
                           "; make the site's files with scripts/dds-security deployment DIR "
                           "(docs/operator-guide.md#security)");
      }
    }
  }
}

// <Name>, <Name/> or <Name attr...> somewhere in the text.
bool hasElement(const std::string& xml, const std::string& name) {
  const std::string open = "<" + name;
  for (std::size_t at = xml.find(open); at != std::string::npos; at = xml.find(open, at + 1)) {
    const std::size_t next = at + open.size();
    if (next < xml.size() &&
        (xml[next] == '>' || xml[next] == '/' || std::isspace(static_cast<unsigned char>(xml[next])) != 0)) {
      return true;
    }
  }
  return false;
}

}  // namespace

std::vector<std::string> ddsSecurityProblems(const DdsSecurityInputs& in) {
  std::vector<std::string> problems;
  const std::string mode = in.env("FLEET_DDS_SECURITY").value_or("");
  if (mode != "" && mode != "required" && mode != "off") {
    problems.push_back("FLEET_DDS_SECURITY=\"" + mode + "\": expected required or off");
  }
  const std::string uri = expand(in.env("CYCLONEDDS_URI").value_or(""), in);
  std::string all;      // every configuration's text, to look for the Security element
  std::string inline_;  // what is not a file: XML written into the variable itself
  std::stringstream items(uri);
  for (std::string item; std::getline(items, item, ',');) {
    const auto first = item.find_first_not_of(" \t\r\n");
    if (first == std::string::npos) {
      continue;
    }
    item = item.substr(first);
    if (item.rfind("file://", 0) != 0) {
      inline_ += item + ",";
      continue;
    }
    const std::string path = item.substr(7);
    std::string why;
    const auto text = in.readFile(path, why);
    if (!text) {
      problems.push_back("CYCLONEDDS_URI names " + path + ", which cannot be read: " + why);
      continue;
    }
    checkSecurityFiles(*text, path, in, problems);
    all += *text;
  }
  if (!inline_.empty()) {
    checkSecurityFiles(inline_, "CYCLONEDDS_URI", in, problems);
    all += inline_;
  }
  if (mode == "required") {
    std::string missing;
    for (const char* part : {"Security", "Authentication", "AccessControl", "Cryptographic"}) {
      if (!hasElement(all, part)) {
        missing += (missing.empty() ? "<" : ", <") + std::string(part) + ">";
      }
    }
    if (!missing.empty()) {
      problems.push_back(
          "FLEET_DDS_SECURITY=required, but the DDS configuration (CYCLONEDDS_URI=\"" + uri + "\") has no " +
          missing +
          ": add the service's security.xml of scripts/dds-security (docs/operator-guide.md#security), or "
          "for development only set FLEET_DDS_SECURITY=off (the dev overlays of deploy/)");
    }
  }
  return problems;
}

void checkDdsSecurity() {
  DdsSecurityInputs in;
  in.env = [](const std::string& name) -> std::optional<std::string> {
    const char* v = std::getenv(name.c_str());
    return v == nullptr ? std::nullopt : std::optional<std::string>(v);
  };
  in.readFile = [](const std::string& path, std::string& why) -> std::optional<std::string> {
    std::ifstream f(path);
    if (!f) {
      why = std::strerror(errno);
      return std::nullopt;
    }
    std::ostringstream s;
    s << f.rdbuf();
    return s.str();
  };
  if (auto problems = ddsSecurityProblems(in); !problems.empty()) {
    throw ConfigError(std::move(problems));
  }
}

}  // namespace fleet::service
