#include "fleet/validation/rejections.hpp"

namespace fleet::validation {

void Rejections::count(const Rejection& r) {
  std::lock_guard lock(m_);
  ++rejected_[r.topic][r.reason];
  ++total_;
}

void Rejections::repaired(const std::string& topic) {
  std::lock_guard lock(m_);
  ++repaired_[topic];
}

std::uint64_t Rejections::total() const {
  std::lock_guard lock(m_);
  return total_;
}

std::uint64_t Rejections::count(const std::string& topic, const std::string& reason) const {
  std::lock_guard lock(m_);
  const auto t = rejected_.find(topic);
  if (t == rejected_.end()) {
    return 0;
  }
  const auto r = t->second.find(reason);
  return r == t->second.end() ? 0 : r->second;
}

std::uint64_t Rejections::repairedCount(const std::string& topic) const {
  std::lock_guard lock(m_);
  const auto t = repaired_.find(topic);
  return t == repaired_.end() ? 0 : t->second;
}

nlohmann::json Rejections::toJson() const {
  std::lock_guard lock(m_);
  return {{"rejected", rejected_}, {"repaired", repaired_}, {"rejected_total", total_}};
}

}  // namespace fleet::validation
