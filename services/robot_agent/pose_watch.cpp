#include "pose_watch.hpp"

#include <cstdio>

namespace fleet::agent {

PoseWatch::Change PoseWatch::update(std::int64_t nowNs, std::uint64_t extracted, std::uint64_t accepted) {
  if (!window_.empty() && (nowNs < window_.back().ns || extracted < window_.back().extracted ||
                           accepted < window_.back().accepted)) {
    window_.clear();  // the counts or the clock started again: judge afresh
  }
  window_.push_back({nowNs, extracted, accepted});
  const auto span = static_cast<std::int64_t>(p_.windowS * 1e9);
  // The front stays the latest sample at or before the window's start.
  while (window_.size() > 1 && window_[1].ns <= nowNs - span)
    window_.pop_front();
  if (nowNs - window_.front().ns < span)
    return Change::kNone;  // not a whole window seen yet
  const std::uint64_t e = extracted - window_.front().extracted;
  const std::uint64_t a = accepted - window_.front().accepted;
  if (e < p_.minLines)
    return Change::kNone;
  extracted_ = e;
  accepted_ = a;
  const double share = static_cast<double>(a) / static_cast<double>(e);
  if (!doubted_ && share < p_.doubtBelow) {
    doubted_ = true;
    ++doubts_;
    return Change::kDoubted;
  }
  if (doubted_ && share > p_.trustAbove) {
    doubted_ = false;
    return Change::kTrusted;
  }
  return Change::kNone;
}

std::string PoseWatch::why() const {
  char buf[160];
  std::snprintf(buf, sizeof buf,
                "localization doubtful: %llu of %llu laser lines matched the site's walls in the last %.1f s",
                static_cast<unsigned long long>(accepted_), static_cast<unsigned long long>(extracted_),
                p_.windowS);
  return buf;
}

}  // namespace fleet::agent
