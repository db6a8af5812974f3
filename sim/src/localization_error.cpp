#include "fleet/sim/localization_error.hpp"

#include <algorithm>
#include <cmath>

#include "fleet/core/angles.hpp"

namespace fleet::sim {

LocalizationErrorLog::LocalizationErrorLog(double binS, std::vector<std::pair<double, double>> hidden)
    : binS_(binS > 0.0 ? binS : 1.0), hidden_(std::move(hidden)) {}

bool LocalizationErrorLog::hiddenAt(double t) const {
  return std::any_of(hidden_.begin(), hidden_.end(),
                     [&](const auto& h) { return t >= h.first && t < h.second; });
}

void LocalizationErrorLog::truth(std::int64_t tNs, const std::vector<Pose2>& poses) {
  if (history_.size() < kHistory) {
    history_.emplace_back(tNs, poses);
    return;
  }
  history_[next_] = {tNs, poses};
  next_ = (next_ + 1) % kHistory;
}

void LocalizationErrorLog::estimate(std::size_t robot, std::int64_t stampNs, const Pose2& est) {
  const auto it =
      std::find_if(history_.begin(), history_.end(), [&](const auto& h) { return h.first == stampNs; });
  if (it == history_.end() || robot >= it->second.size() || !est.isFinite()) {
    ++unmatched_;
    return;
  }
  const Pose2& t = it->second[robot];
  const double pos = std::hypot(est.x - t.x, est.y - t.y);
  const double head = std::abs(angleDiff(est.theta, t.theta));
  const double s = static_cast<double>(stampNs) * 1e-9;
  const auto b = static_cast<std::size_t>(std::max(0.0, std::floor(s / binS_)));
  if (bins_.size() <= b) {
    bins_.resize(b + 1);
  }
  if (robots_.size() <= robot) {
    robots_.resize(robot + 1);
  }
  Robot& r = robots_[robot];
  if (pos > r.posMax) {
    r.posMax = pos;
    r.posMaxT = s;
  }
  r.posLast = pos;
  r.headMax = std::max(r.headMax, head);
  r.seen = true;
  Bin& bin = bins_[b];
  bin.posSum += pos;
  bin.posMax = std::max(bin.posMax, pos);
  bin.headSum += head;
  bin.headMax = std::max(bin.headMax, head);
  ++bin.n;
  pos_.push_back(static_cast<float>(pos));
  head_.push_back(static_cast<float>(head));
  inHidden_.push_back(hiddenAt(s));
  ++samples_;
}

namespace {

nlohmann::json stats(std::vector<float> pos, std::vector<float> head) {
  auto rms = [](const std::vector<float>& v) {
    double s = 0.0;
    for (const float x : v) {
      s += static_cast<double>(x) * static_cast<double>(x);
    }
    return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
  };
  auto p95 = [](std::vector<float>& v) {
    if (v.empty()) {
      return 0.0;
    }
    const auto k = static_cast<std::size_t>(0.95 * static_cast<double>(v.size() - 1));
    std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
    return static_cast<double>(v[k]);
  };
  auto mx = [](const std::vector<float>& v) {
    return v.empty() ? 0.0 : static_cast<double>(*std::max_element(v.begin(), v.end()));
  };
  return {{"samples", pos.size()}, {"pos_rmse", rms(pos)}, {"pos_max", mx(pos)},   {"head_rmse", rms(head)},
          {"head_max", mx(head)},  {"pos_p95", p95(pos)},  {"head_p95", p95(head)}};
}

}  // namespace

nlohmann::json LocalizationErrorLog::toJson(const std::vector<std::string>& names) const {
  nlohmann::json series = nlohmann::json::array();
  for (std::size_t b = 0; b < bins_.size(); ++b) {
    const Bin& bin = bins_[b];
    if (bin.n == 0) {
      continue;
    }
    const double t = (static_cast<double>(b) + 0.5) * binS_;
    const double n = static_cast<double>(bin.n);
    series.push_back({{"t", t},
                      {"pos_mean", bin.posSum / n},
                      {"pos_max", bin.posMax},
                      {"head_mean", bin.headSum / n},
                      {"head_max", bin.headMax},
                      {"hidden", hiddenAt(t)}});
  }
  std::vector<float> hp, hh, vp, vh;
  for (std::size_t i = 0; i < pos_.size(); ++i) {
    (inHidden_[i] ? hp : vp).push_back(pos_[i]);
    (inHidden_[i] ? hh : vh).push_back(head_[i]);
  }
  nlohmann::json hidden = nlohmann::json::array();
  for (const auto& [from, to] : hidden_) {
    hidden.push_back({from, to});
  }
  nlohmann::json perRobot = nlohmann::json::array();
  for (std::size_t i = 0; i < robots_.size(); ++i) {
    const Robot& r = robots_[i];
    if (r.seen) {
      perRobot.push_back({{"robot", i < names.size() ? nlohmann::json(names[i]) : nlohmann::json(i)},
                          {"pos_max", r.posMax},
                          {"pos_max_t", r.posMaxT},
                          {"pos_last", r.posLast},
                          {"head_max", r.headMax}});
    }
  }
  return {{"bin_s", binS_},
          {"per_robot", perRobot},
          {"hidden", hidden},
          {"series", series},
          {"overall", stats(pos_, head_)},
          {"hidden_stretches", stats(hp, hh)},
          {"visible_stretches", stats(vp, vh)},
          {"unmatched", unmatched_}};
}

}  // namespace fleet::sim
