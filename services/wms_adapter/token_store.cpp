#include "token_store.hpp"

#include <openssl/crypto.h>
#include <openssl/evp.h>
#include <spdlog/spdlog.h>
#include <sys/stat.h>

#include <fstream>
#include <regex>
#include <sstream>

namespace fleet::wms {
namespace {

constexpr std::size_t kMinTokenLength = 16;

std::vector<std::string> fieldsOf(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> out;
  for (std::string f; in >> f;) {
    out.push_back(f);
  }
  return out;
}

std::set<Scope> allScopes() {
  return {Scope::Read, Scope::Submit, Scope::Operate};
}

}  // namespace

TokenStore::Digest TokenStore::digestOf(std::string_view token) {
  Digest d{};
  unsigned int n = 0;
  EVP_Digest(token.data(), token.size(), d.data(), &n, EVP_sha256(), nullptr);
  return d;
}

Expected<std::vector<TokenStore::Entry>> TokenStore::parse(std::string_view text, const std::string& origin) {
  std::vector<Entry> out;
  std::vector<std::vector<std::string>> lines;
  std::vector<int> numbers;
  std::istringstream in{std::string(text)};
  int number = 0;
  for (std::string line; std::getline(in, line);) {
    ++number;
    auto f = fieldsOf(line);
    if (f.empty() || f[0][0] == '#') {
      continue;
    }
    lines.push_back(std::move(f));
    numbers.push_back(number);
  }
  if (lines.empty()) {
    return unexpected("no_tokens", origin + ": no token in the file");
  }
  if (lines.size() == 1 && lines[0].size() != 3) {
    // The format before names and scopes: the line is the token, spaces and all.
    std::string token;
    for (const auto& f : lines[0]) {
      token += (token.empty() ? "" : " ") + f;
    }
    return std::vector<Entry>{{{"token", allScopes()}, digestOf(token)}};
  }
  static const std::regex kName("[A-Za-z0-9._-]{1,64}");
  std::set<std::string> names;
  std::set<Digest> digests;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const auto& f = lines[i];
    const std::string at = origin + ":" + std::to_string(numbers[i]) + ": ";
    if (f.size() != 3) {
      return unexpected("invalid",
                        at + "expected \"name scopes token\", found " + std::to_string(f.size()) + " fields");
    }
    if (!std::regex_match(f[0], kName)) {
      return unexpected("invalid", at + "name \"" + f[0] + "\": 1 to 64 of A-Z a-z 0-9 . _ -");
    }
    if (!names.insert(f[0]).second) {
      return unexpected("invalid", at + "name \"" + f[0] + "\" appears twice");
    }
    Entry e;
    e.who.name = f[0];
    std::istringstream scopes(f[1]);
    for (std::string s; std::getline(scopes, s, ',');) {
      const auto scope = parseScope(s);
      if (!scope) {
        return unexpected("invalid", at + "scope \"" + s + "\" is not one of read, submit, operate");
      }
      e.who.scopes.insert(*scope);
    }
    if (e.who.scopes.empty()) {
      return unexpected("invalid", at + "no scope given");
    }
    if (f[2].size() < kMinTokenLength) {
      return unexpected("invalid", at + "the token of \"" + f[0] + "\" is shorter than " +
                                       std::to_string(kMinTokenLength) + " characters");
    }
    e.digest = digestOf(f[2]);
    if (!digests.insert(e.digest).second) {
      return unexpected("invalid", at + "the token of \"" + f[0] + "\" is also another name's");
    }
    out.push_back(std::move(e));
  }
  return out;
}

std::optional<TokenStore::FileStamp> TokenStore::stampOf(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) {
    return std::nullopt;
  }
  return FileStamp{static_cast<std::int64_t>(st.st_mtim.tv_sec) * 1'000'000'000 + st.st_mtim.tv_nsec,
                   static_cast<std::int64_t>(st.st_size), static_cast<std::uint64_t>(st.st_ino)};
}

Expected<TokenStore> TokenStore::fromFile(const std::string& path) {
  TokenStore s;
  s.path_ = path;
  const auto stamp = stampOf(path);
  std::ifstream in(path);
  if (!stamp || !in) {
    return unexpected("unreadable", "cannot read the token file \"" + path + "\"");
  }
  std::stringstream text;
  text << in.rdbuf();
  auto entries = parse(text.str(), path);
  if (!entries) {
    return unexpected(entries.error());
  }
  s.entries_ = std::move(*entries);
  s.stamp_ = *stamp;
  return s;
}

TokenStore TokenStore::single(const std::string& name, const std::string& token) {
  TokenStore s;
  s.entries_.push_back({{name, allScopes()}, digestOf(token)});
  return s;
}

TokenStore::TokenStore(TokenStore&& o) noexcept {
  *this = std::move(o);
}

TokenStore& TokenStore::operator=(TokenStore&& o) noexcept {
  if (this != &o) {
    std::scoped_lock lock(m_, o.m_);
    path_ = std::move(o.path_);
    stamp_ = o.stamp_;
    entries_ = std::move(o.entries_);
    problem_ = std::move(o.problem_);
    reloads_ = o.reloads_;
  }
  return *this;
}

void TokenStore::refreshLocked() const {
  if (path_.empty()) {
    return;
  }
  // A stat per request: cheap next to the request, and an edit counts from the next one on.
  const auto stamp = stampOf(path_);
  if (!stamp) {
    problem_ = "cannot read the token file \"" + path_ + "\"; the tokens read before stay";
    return;
  }
  if (*stamp == stamp_) {
    return;
  }
  std::ifstream in(path_);
  std::stringstream text;
  text << in.rdbuf();
  auto entries = parse(text.str(), path_);
  stamp_ = *stamp;  // a bad file is reported once, not re-parsed on every request
  if (!entries) {
    problem_ = entries.error().message + "; the tokens read before stay";
    spdlog::warn("wms adapter: token file: {}", problem_);
    return;
  }
  entries_ = std::move(*entries);
  problem_.clear();
  ++reloads_;
  spdlog::info("wms adapter: token file \"{}\" re-read: {} tokens", path_, entries_.size());
}

bool TokenStore::enabled() const {
  std::lock_guard lock(m_);
  return !path_.empty() || !entries_.empty();
}

std::optional<Principal> TokenStore::find(std::string_view token) const {
  const Digest d = digestOf(token);
  std::lock_guard lock(m_);
  refreshLocked();
  std::optional<Principal> found;
  // Compare every digest in constant time: how long this takes says nothing about the tokens.
  for (const auto& e : entries_) {
    if (CRYPTO_memcmp(e.digest.data(), d.data(), d.size()) == 0) {
      found = e.who;
    }
  }
  return found;
}

std::optional<TokenStore::Entry> TokenStore::named(std::string_view name) const {
  std::lock_guard lock(m_);
  refreshLocked();
  for (const auto& e : entries_) {
    if (e.who.name == name) {
      return e;
    }
  }
  return std::nullopt;
}

std::string TokenStore::lastProblem() const {
  std::lock_guard lock(m_);
  return problem_;
}

std::uint64_t TokenStore::reloads() const {
  std::lock_guard lock(m_);
  return reloads_;
}

}  // namespace fleet::wms
