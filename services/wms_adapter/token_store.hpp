#pragma once

// The API's bearer tokens: each has a name (who, in the audit log) and scopes (what it may do).
// Kept in a file the operator edits; an edit (or a replacement by rename) takes effect at the next
// request, without a restart. A file that does not parse leaves the tokens as they were and says
// why (lastProblem()). Only SHA-256 digests of the tokens are kept in memory.
//
// File format (docs/operator-guide.md, "Security: HTTP API"), one token a line, '#' comments:
//
//     # name   scopes               token (at least 16 characters)
//     wms      read,submit          6f1c0c5e0b6d4c5e9a3e...
//     floor    read,operate         0d7e1b9a44c1f2aa51b0...
//
// A file of a single line that is not "name scopes token" (the format before scopes: the line is
// the token) is one token named "token" with every scope.

#include <array>
#include <cstdint>
#include <mutex>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "fleet/core/expected.hpp"
#include "http_names.hpp"

namespace fleet::wms {

struct Principal {
  std::string name;
  std::set<Scope> scopes;
};

class TokenStore {
 public:
  using Digest = std::array<unsigned char, 32>;
  struct Entry {
    Principal who;
    Digest digest{};
  };

  /// No tokens: authentication is off (the loopback developer default).
  TokenStore() = default;
  /// Reads `path` now; the error names the file and line.
  static Expected<TokenStore> fromFile(const std::string& path);
  /// One token with every scope (FLEET_WMS_TOKEN), never re-read.
  static TokenStore single(const std::string& name, const std::string& token);
  /// Parses the file's text; `origin` names it in errors.
  static Expected<std::vector<Entry>> parse(std::string_view text, const std::string& origin);

  TokenStore(TokenStore&& o) noexcept;
  TokenStore& operator=(TokenStore&& o) noexcept;

  [[nodiscard]] bool enabled() const;
  /// Who holds `token` (after re-reading the file if it changed), or nothing.
  [[nodiscard]] std::optional<Principal> find(std::string_view token) const;
  /// The entry named `name` (after re-reading the file if it changed), or nothing: what a browser
  /// session made from that token may do, and the digest its cookie is signed with.
  [[nodiscard]] std::optional<Entry> named(std::string_view name) const;
  /// Why the last re-read of the file was refused (empty when it was not).
  [[nodiscard]] std::string lastProblem() const;
  [[nodiscard]] std::uint64_t reloads() const;

  static Digest digestOf(std::string_view token);

 private:
  struct FileStamp {
    std::int64_t mtimeNs = 0;
    std::int64_t size = -1;
    std::uint64_t inode = 0;
    bool operator==(const FileStamp&) const = default;
  };
  static std::optional<FileStamp> stampOf(const std::string& path);
  void refreshLocked() const;

  mutable std::mutex m_;
  std::string path_;  // empty: fixed tokens
  mutable FileStamp stamp_;
  mutable std::vector<Entry> entries_;
  mutable std::string problem_;
  mutable std::uint64_t reloads_ = 0;
};

}  // namespace fleet::wms
