#include "task_feeder.hpp"

#include <httplib.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>
#include <thread>

namespace fleet::ctl {

using nlohmann::json;

TaskFeeder::TaskFeeder(Source source, Say say)
    : src_(std::move(source)), say_(std::move(say)), rng_(src_.seed) {}

void TaskFeeder::due(double simS) {
  std::lock_guard<std::mutex> lock(mu_);
  if (src_.fromList) {
    // Tasks at or after the end never: whether the clock is seen there before the simulator stops
    // is a race.
    while (listNext_ < src_.list.size() && src_.list[listNext_].atS <= simS &&
           src_.list[listNext_].atS < src_.endS) {
      pending_.push_back(toTaskRequest(src_.list[listNext_]));
      ++listNext_;
      ++generated_;
    }
    return;
  }
  const int dueCount = static_cast<int>(std::floor(simS * src_.ratePerMin / 60.0)) + 1;
  while (generated_ < dueCount && (src_.maxTasks <= 0 || generated_ < src_.maxTasks)) {
    ++generated_;
    char id[32];
    std::snprintf(id, sizeof id, "lt-%05d", generated_);
    std::uniform_int_distribution<std::size_t> p(0, src_.pickups.size() - 1);
    std::uniform_int_distribution<std::size_t> d(0, src_.dropoffs.size() - 1);
    pending_.push_back({{"id", id},
                        {"kind", "transport"},
                        {"pickup", src_.pickups[p(rng_)]},
                        {"dropoff", src_.dropoffs[d(rng_)]},
                        {"load_duration_ns", 2000000000LL},
                        {"unload_duration_ns", 2000000000LL}});
  }
}

void TaskFeeder::submit(httplib::Client& http) {
  std::vector<json> toPost;
  {
    std::lock_guard<std::mutex> lock(mu_);
    toPost.swap(pending_);
  }
  std::vector<json> keep;
  for (std::size_t i = 0; i < toPost.size(); i += 100) {
    json batch = json::array();
    for (std::size_t k = i; k < std::min(toPost.size(), i + 100); ++k) {
      batch.push_back(toPost[k]);
    }
    auto r = http.Post("/v1/tasks", batch.dump(), "application/json");
    if (!r) {
      ++postErrors_;
      for (auto& t : batch) {
        keep.push_back(t);
      }
      continue;
    }
    auto body = json::parse(r->body, nullptr, false);
    json results = json::array();
    if (body.is_object() && body.contains("results")) {
      results = body["results"];
    } else if (body.is_object() && body.contains("id")) {
      results.push_back(body);
    }
    std::set<std::string> answered;
    for (const auto& item : results) {
      const std::string id = item.value("id", "");
      const int st = item.value("status", 0);
      answered.insert(id);
      if (st == 200 || st == 201) {
        std::lock_guard<std::mutex> lock(mu_);
        ledger_.acknowledged(id);
      } else if (st >= 400 && st < 500 && st != 429) {
        ++refused_;
        say_("task " + id + " refused: " + item.dump());
      } else {
        for (auto& t : batch) {
          if (t["id"] == id) {
            keep.push_back(t);
          }
        }
      }
    }
    for (auto& t : batch) {
      if (!answered.count(t["id"].get<std::string>())) {
        keep.push_back(t);
      }
    }
  }
  std::lock_guard<std::mutex> lock(mu_);
  pending_.insert(pending_.begin(), keep.begin(), keep.end());
}

void TaskFeeder::run(httplib::Client& http, const std::atomic<bool>& stop) {
  while (!stop) {
    submit(http);
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
  }
}

int TaskFeeder::generated() const {
  std::lock_guard<std::mutex> lock(mu_);
  return generated_;
}

std::size_t TaskFeeder::pending() const {
  std::lock_guard<std::mutex> lock(mu_);
  return pending_.size();
}

std::size_t TaskFeeder::acknowledged() const {
  std::lock_guard<std::mutex> lock(mu_);
  return ledger_.count();
}

Accounting TaskFeeder::reconcile(const std::vector<TaskRow>& tasks,
                                 const std::vector<TransitionRow>& transitions) const {
  std::lock_guard<std::mutex> lock(mu_);
  return ledger_.reconcile(tasks, transitions);
}

}  // namespace fleet::ctl
