#pragma once

// Webhook subscriptions and their delivery (docs/operator-guide.md#webhooks). Each subscription
// is a URL, a secret and a cursor into the event log (event_log.hpp): the log is the durable
// outbox, the cursor (stored with the subscription after every delivered event) says how far the
// receiver has acknowledged, so an adapter restart resumes where it stood and loses nothing; an
// event the receiver took whose cursor was not stored yet is sent again (at least once: receivers
// de-duplicate by X-Fleet-Event-Id).
//
// Every subscription has a thread of its own, so a slow or dead receiver holds up no other. A
// failed attempt (no connection, no answer within timeout_ms, a status other than 2xx) is retried
// after a back-off doubling from backoff_ms to backoff_max_ms with jitter; after max_attempts
// failures in a row the subscription is marked `failing` (GET /v1/webhooks shows it with the last
// error) and is tried once every failing_retry_ms, becoming `active` again with its first success.
// A cursor the log's retention has passed gets a `gap` delivery naming the ids missed.
//
// The subscriptions live in a WebhookStore (webhook_store.hpp): the adapter's SQLite file, or the
// PostgreSQL database replicas share; there each replica sees every subscription (it looks again
// every second) and delivers those whose lease it holds.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "event_log.hpp"
#include "sqlite_db.hpp"
#include "webhook_store.hpp"

namespace fleet::wms {

struct WebhookSettings {
  std::vector<std::string> allow;  // URL prefixes a subscription may deliver to (webhook_url.hpp)
  int maxSubscriptions = 32;
  int timeoutMs = 5000;  // connect and answer, per attempt
  int maxAttempts = 8;   // failures in a row before `failing`
  int backoffMs = 500;   // the first retry's delay; doubles
  int backoffMaxMs = 60'000;
  int failingRetryMs = 300'000;  // how often a failing subscription is tried
  std::string caFile;            // CA certificates for https receivers (empty: the system's)
};

class Webhooks {
 public:
  /// Loads the stored subscriptions and starts their delivery. Throws std::runtime_error when the
  /// database cannot be read.
  Webhooks(WebhookSettings settings, std::shared_ptr<SqliteDb> db, EventLog& log);
  /// On any store; a shared one is looked at every second for subscriptions made or removed
  /// through other replicas.
  Webhooks(WebhookSettings settings, std::unique_ptr<WebhookStore> store, EventLog& log);
  ~Webhooks();
  Webhooks(const Webhooks&) = delete;
  Webhooks& operator=(const Webhooks&) = delete;

  struct Created {
    WebhookStatus status;
    std::string secret;
  };
  /// A new subscription delivering events logged from now on. `secret` empty: one is made. The
  /// caller has checked the URL (refuseWebhookUrl) and the secret; nothing when the limit of
  /// subscriptions is reached.
  std::optional<Created> create(const std::string& url, std::string secret, std::int64_t nowNs);
  /// False when there is no such subscription.
  bool remove(const std::string& id);
  [[nodiscard]] std::vector<WebhookStatus> list() const;
  [[nodiscard]] std::optional<WebhookStatus> find(const std::string& id) const;
  [[nodiscard]] const WebhookSettings& settings() const { return s_; }
  /// Stops every delivery (each within timeout_ms); also done by the destructor.
  void stop();

 private:
  struct Sub;
  void run(const std::shared_ptr<Sub>& sub);
  /// One POST of `body` for event `eventId`; nothing on a 2xx, else why it failed.
  std::optional<std::string> deliver(Sub& sub, std::int64_t eventId, const std::string& body);
  void store(const Sub& sub);  // writes the status (cursor, counts, state); throws on a disk error
  /// A shared store: whether this replica delivers `sub` now; takes a newer stored cursor.
  bool mine(Sub& sub, std::int64_t& cursor);
  void sync();  // a shared store: start what other replicas made, stop what they removed
  std::shared_ptr<Sub> subOf(const StoredWebhook& w);
  std::vector<LoggedEvent> readAfter(std::int64_t cursor);  // the next event; none on a read error
  void start(const std::shared_ptr<Sub>& sub);

  WebhookSettings s_;
  std::unique_ptr<WebhookStore> store_;
  std::string replica_;  // this adapter, as a lease holder
  EventLog& log_;
  mutable std::mutex m_;
  std::map<std::string, std::shared_ptr<Sub>> subs_;
  std::vector<std::thread> threads_;  // joined by stop()
  std::atomic<bool> stop_{false};
  std::thread syncer_;  // a shared store
  std::condition_variable syncCv_;
};

/// A subscription's JSON (without its secret).
nlohmann::json webhookJson(const WebhookStatus& s, std::int64_t lastEventId);

}  // namespace fleet::wms
