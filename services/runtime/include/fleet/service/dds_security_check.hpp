#pragma once

// Before a service joins the DDS domain: the files its Cyclone DDS configuration needs for DDS
// Security are there, and, where the deployment requires DDS Security (FLEET_DDS_SECURITY=required,
// set by deploy/), the configuration turns it on. A missing certificate, key or signed document
// otherwise ends in Cyclone's "dds_create_participant failed"; this names the file (exit 2).

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace fleet::service {

/// What the check reads: an environment variable (nullopt when unset) and a file's text (nullopt
/// when it cannot be read, with the reason in `why`).
struct DdsSecurityInputs {
  std::function<std::optional<std::string>(const std::string&)> env;
  std::function<std::optional<std::string>(const std::string& path, std::string& why)> readFile;
};

/// Every problem of the DDS configuration named by CYCLONEDDS_URI under FLEET_DDS_SECURITY
/// ("required", "off" or unset): unreadable configuration files, unreadable files named by a
/// <Security> element (${VAR} and ${VAR:-default} expanded as Cyclone does), and, when required, a
/// configuration without authentication, access control and cryptography. Empty: all is well.
std::vector<std::string> ddsSecurityProblems(const DdsSecurityInputs& in);

/// ddsSecurityProblems() on the process's environment and files; throws ConfigError (exit 2) with
/// the problems.
void checkDdsSecurity();

}  // namespace fleet::service
