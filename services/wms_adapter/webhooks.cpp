#include "webhooks.hpp"

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>

#include "fleet/core/clock.hpp"
#include "webhook_signature.hpp"
#include "webhook_url.hpp"

namespace fleet::wms {

struct Webhooks::Sub {
  WebhookStatus status;  // under m
  std::string secret;
  WebhookUrl target;
  std::mutex m;
  std::condition_variable cv;
  bool removed = false;
};

nlohmann::json webhookJson(const WebhookStatus& s, std::int64_t lastEventId) {
  return {{"id", s.id},
          {"url", s.url},
          {"state", s.state},
          {"created_ns", s.createdNs},
          {"delivered_through", s.deliveredThrough},
          {"pending", std::max<std::int64_t>(0, lastEventId - s.deliveredThrough)},
          {"deliveries", s.deliveries},
          {"failures", s.failures},
          {"last_error", s.lastError},
          {"last_attempt_ns", s.lastAttemptNs},
          {"last_success_ns", s.lastSuccessNs}};
}

namespace {

constexpr std::int64_t kLeaseNs = 5'000'000'000;  // a replica's hold on a subscription it delivers
constexpr auto kSyncEvery = std::chrono::seconds(1);

}  // namespace

Webhooks::Webhooks(WebhookSettings settings, std::shared_ptr<SqliteDb> db, EventLog& log)
    : Webhooks(std::move(settings), std::make_unique<SqliteWebhookStore>(std::move(db)), log) {}

Webhooks::Webhooks(WebhookSettings settings, std::unique_ptr<WebhookStore> store, EventLog& log)
    : s_(std::move(settings)), store_(std::move(store)), replica_(randomHex(8)), log_(log) {
  const auto stored = store_->load();
  {
    std::lock_guard lock(m_);
    for (const auto& w : stored) {
      if (auto sub = subOf(w)) {
        subs_[sub->status.id] = sub;
        start(sub);
      }
    }
  }
  if (store_->shared()) {
    syncer_ = std::thread([this] {
      std::unique_lock lock(m_);
      while (!stop_) {
        syncCv_.wait_for(lock, kSyncEvery, [&] { return stop_.load(); });
        if (stop_) {
          break;
        }
        lock.unlock();
        sync();
        lock.lock();
      }
    });
  }
}

std::shared_ptr<Webhooks::Sub> Webhooks::subOf(const StoredWebhook& w) {
  auto target = parseWebhookUrl(w.status.url, nullptr);
  if (!target) {
    return nullptr;  // stored by a build that checked it: cannot happen short of editing the store
  }
  auto sub = std::make_shared<Sub>();
  sub->status = w.status;
  sub->secret = w.secret;
  sub->target = *target;
  return sub;
}

void Webhooks::sync() {
  std::vector<StoredWebhook> stored;
  try {
    stored = store_->load();
  } catch (const std::exception&) {
    return;  // the database is away: the next round looks again
  }
  std::vector<std::shared_ptr<Sub>> gone;
  {
    std::lock_guard lock(m_);
    if (stop_) {
      return;
    }
    std::map<std::string, const StoredWebhook*> byId;
    for (const auto& w : stored) {
      byId[w.status.id] = &w;
      if (!subs_.count(w.status.id)) {
        if (auto sub = subOf(w)) {
          subs_[w.status.id] = sub;
          start(sub);
        }
      }
    }
    for (auto it = subs_.begin(); it != subs_.end();) {
      const auto found = byId.find(it->first);
      if (found == byId.end()) {
        gone.push_back(it->second);
        it = subs_.erase(it);
        continue;
      }
      // Delivered by another replica: its status as stored (GET /v1/webhooks on either).
      std::lock_guard sl(it->second->m);
      if (found->second->status.lastAttemptNs > it->second->status.lastAttemptNs) {
        it->second->status = found->second->status;
      }
      ++it;
    }
  }
  for (auto& sub : gone) {
    {
      std::lock_guard sl(sub->m);
      sub->removed = true;
    }
    sub->cv.notify_all();
  }
}

bool Webhooks::mine(Sub& sub, std::int64_t& cursor) {
  if (!store_->shared()) {
    return true;
  }
  WebhookStore::Claim claim;
  try {
    claim = store_->claim(sub.status.id, replica_, WallClock{}.nowNs(), kLeaseNs);
  } catch (const std::exception&) {
    return false;  // the database is away: nobody can take the lease from the one holding it
  }
  if (claim.granted && claim.deliveredThrough && *claim.deliveredThrough > cursor) {
    cursor = *claim.deliveredThrough;  // another replica delivered up to there
    std::lock_guard sl(sub.m);
    sub.status.deliveredThrough = cursor;
  }
  return claim.granted;
}

Webhooks::~Webhooks() {
  stop();
}

void Webhooks::stop() {
  stop_ = true;
  std::vector<std::thread> threads;
  {
    std::lock_guard lock(m_);
    syncCv_.notify_all();
    for (auto& [id, sub] : subs_) {
      std::lock_guard sl(sub->m);
      sub->cv.notify_all();
    }
    threads.swap(threads_);
  }
  log_.wakeAll();
  for (auto& t : threads) {
    t.join();
  }
  if (syncer_.joinable()) {
    syncer_.join();
  }
}

void Webhooks::start(const std::shared_ptr<Sub>& sub) {
  threads_.emplace_back([this, sub] { run(sub); });
}

std::optional<Webhooks::Created> Webhooks::create(const std::string& url, std::string secret,
                                                  std::int64_t nowNs) {
  auto target = parseWebhookUrl(url, nullptr);
  if (!target) {
    return std::nullopt;
  }
  auto sub = std::make_shared<Sub>();
  sub->target = *target;
  sub->secret = secret.empty() ? randomHex(32) : std::move(secret);
  auto& st = sub->status;
  st.id = "wh-" + randomHex(8);
  st.url = url;
  st.createdNs = nowNs;
  std::lock_guard lock(m_);
  if (stop_ || subs_.size() >= static_cast<std::size_t>(s_.maxSubscriptions)) {
    return std::nullopt;
  }
  st.deliveredThrough = log_.lastId();  // events from now on
  store_->insert({st, sub->secret});
  subs_[st.id] = sub;
  start(sub);
  return Created{st, sub->secret};
}

bool Webhooks::remove(const std::string& id) {
  std::shared_ptr<Sub> sub;
  {
    std::lock_guard lock(m_);
    const auto it = subs_.find(id);
    if (it != subs_.end()) {
      sub = it->second;
      subs_.erase(it);
    }
    // In a shared store another replica may have made it a moment ago.
    if (!store_->remove(id) && !sub) {
      return false;
    }
  }
  if (sub) {
    {
      std::lock_guard sl(sub->m);
      sub->removed = true;
    }
    sub->cv.notify_all();
  }
  return true;
}

std::vector<WebhookStatus> Webhooks::list() const {
  std::vector<WebhookStatus> out;
  std::lock_guard lock(m_);
  for (const auto& [id, sub] : subs_) {
    std::lock_guard sl(sub->m);
    out.push_back(sub->status);
  }
  std::sort(out.begin(), out.end(), [](const auto& a, const auto& b) { return a.createdNs < b.createdNs; });
  return out;
}

std::optional<WebhookStatus> Webhooks::find(const std::string& id) const {
  std::lock_guard lock(m_);
  const auto it = subs_.find(id);
  if (it == subs_.end()) {
    return std::nullopt;
  }
  std::lock_guard sl(it->second->m);
  return it->second->status;
}

void Webhooks::store(const Sub& sub) {
  store_->update(sub.status);
}

std::optional<std::string> Webhooks::deliver(Sub& sub, std::int64_t eventId, const std::string& body) {
  httplib::Client client(sub.target.origin);
  const auto timeout = std::chrono::milliseconds(s_.timeoutMs);
  client.set_connection_timeout(timeout);
  client.set_read_timeout(timeout);
  client.set_write_timeout(timeout);
  client.set_follow_location(false);
  if (sub.target.scheme == "https") {
    client.enable_server_certificate_verification(true);
    if (!s_.caFile.empty()) {
      client.set_ca_cert_path(s_.caFile);
    }
  }
  const std::int64_t now =
      std::chrono::duration_cast<std::chrono::seconds>(std::chrono::system_clock::now().time_since_epoch())
          .count();
  const httplib::Headers headers = {{"X-Fleet-Event-Id", std::to_string(eventId)},
                                    {"X-Fleet-Webhook-Id", sub.status.id},
                                    {"X-Fleet-Timestamp", std::to_string(now)},
                                    {"X-Fleet-Signature", webhookSignature(sub.secret, now, body)},
                                    {"User-Agent", "fleet-wms-adapter"}};
  const auto res = client.Post(sub.target.path, headers, body, "application/json");
  if (!res) {
    return "no answer: " + httplib::to_string(res.error());
  }
  if (res->status < 200 || res->status > 299) {
    return "answered " + std::to_string(res->status);
  }
  return std::nullopt;
}

std::vector<LoggedEvent> Webhooks::readAfter(std::int64_t cursor) {
  try {
    return log_.after(cursor, 1);
  } catch (const std::exception&) {
    // A read error of the log's file (the newest events come from memory): tried again shortly.
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    return {};
  }
}

void Webhooks::run(const std::shared_ptr<Sub>& sub) {
  std::mt19937 jitter(std::random_device{}());
  std::int64_t cursor = 0;
  {
    std::lock_guard sl(sub->m);
    cursor = sub->status.deliveredThrough;
  }
  auto over = [&] {
    std::lock_guard sl(sub->m);
    return stop_ || sub->removed;
  };
  while (!over()) {
    if (!mine(*sub, cursor)) {
      // Another replica holds it: look again when its lease could have run out.
      std::unique_lock sl(sub->m);
      sub->cv.wait_for(sl, std::chrono::seconds(1), [&] { return stop_ || sub->removed; });
      continue;
    }
    // What to send next: a gap when retention passed the cursor, else the next event.
    std::int64_t id = 0;
    nlohmann::json body;
    const std::int64_t pruned = log_.prunedThrough();
    if (cursor < pruned) {
      id = pruned;
      body = {{"type", "gap"}, {"event_id", pruned}, {"missed_after", cursor}, {"missed_through", pruned}};
    } else if (auto next = readAfter(cursor); !next.empty()) {
      id = next[0].id;
      body = loggedEventJson(next[0]);
      body["type"] = "task";
    } else {
      log_.waitAfter(cursor, std::chrono::milliseconds(500));
      continue;
    }
    const auto why = deliver(*sub, id, body.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
    std::chrono::milliseconds wait{0};
    {
      std::lock_guard sl(sub->m);
      auto& st = sub->status;
      st.lastAttemptNs = WallClock{}.nowNs();
      if (!why) {
        cursor = id;
        st.deliveredThrough = id;
        ++st.deliveries;
        st.failures = 0;
        st.state = "active";
        st.lastSuccessNs = st.lastAttemptNs;
      } else {
        ++st.failures;
        st.lastError = *why;
        if (st.failures >= s_.maxAttempts) {
          st.state = "failing";
          wait = std::chrono::milliseconds(s_.failingRetryMs);
        } else {
          const double base = std::min<double>(
              s_.backoffMaxMs, s_.backoffMs * std::pow(2.0, static_cast<double>(st.failures - 1)));
          wait = std::chrono::milliseconds(
              static_cast<std::int64_t>(base * std::uniform_real_distribution<double>(0.75, 1.0)(jitter)));
        }
      }
      if (!sub->removed) {
        try {
          store(*sub);
        } catch (const std::exception& e) {
          // The cursor stays in memory: delivery goes on, a restart sends from the stored one.
          st.lastError = std::string("cannot store the cursor: ") + e.what();
        }
      }
    }
    if (wait.count() > 0) {
      std::unique_lock sl(sub->m);
      sub->cv.wait_for(sl, wait, [&] { return stop_ || sub->removed; });
    }
  }
}

}  // namespace fleet::wms
