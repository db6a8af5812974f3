#pragma once

// Where webhook subscriptions (webhooks.hpp) are kept: with the event log, in the adapter's SQLite
// file, or in the PostgreSQL database adapter replicas share. In a shared store every replica sees
// every subscription, and each subscription is delivered by one replica at a time: the one holding
// its lease (renewed with every attempt, taken over when it runs out), so a replica that dies
// hands its deliveries to another within the lease, at the cursor it had stored.

#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <vector>

#include "fleet/fleet/pg_connection.hpp"
#include "sqlite_db.hpp"

namespace fleet::wms {

/// A subscription as GET /v1/webhooks shows it (the secret only on creation).
struct WebhookStatus {
  std::string id;
  std::string url;
  std::string state = "active";  // "active" or "failing"
  std::int64_t createdNs = 0;
  std::int64_t deliveredThrough = 0;  // the newest event id the receiver acknowledged
  std::int64_t deliveries = 0;        // acknowledged deliveries
  std::int64_t failures = 0;          // failed attempts in a row
  std::string lastError;
  std::int64_t lastAttemptNs = 0;
  std::int64_t lastSuccessNs = 0;
};

struct StoredWebhook {
  WebhookStatus status;
  std::string secret;
};

class WebhookStore {
 public:
  virtual ~WebhookStore() = default;
  /// Every subscription, oldest first. Throws std::runtime_error on a read error.
  virtual std::vector<StoredWebhook> load() = 0;
  virtual void insert(const StoredWebhook& w) = 0;
  /// False when there is no such subscription.
  virtual bool remove(const std::string& id) = 0;
  /// Writes the status (cursor, counts, state, last error and times). Throws on a write error.
  virtual void update(const WebhookStatus& s) = 0;
  /// Whether `replica` may deliver subscription `id` now: it holds the lease, or takes it because
  /// it ran out, until `nowNs + leaseNs`. With the cursor as stored (the previous holder's). A
  /// store of one adapter always grants it and has no cursor to give.
  struct Claim {
    bool granted = true;
    std::optional<std::int64_t> deliveredThrough;
  };
  virtual Claim claim(const std::string& id, const std::string& replica, std::int64_t nowNs,
                      std::int64_t leaseNs) {
    (void)id, (void)replica, (void)nowNs, (void)leaseNs;
    return {};
  }
  /// Whether other adapters share the subscriptions.
  [[nodiscard]] virtual bool shared() const { return false; }
};

class SqliteWebhookStore : public WebhookStore {
 public:
  explicit SqliteWebhookStore(std::shared_ptr<SqliteDb> db);
  std::vector<StoredWebhook> load() override;
  void insert(const StoredWebhook& w) override;
  bool remove(const std::string& id) override;
  void update(const WebhookStatus& s) override;

 private:
  std::shared_ptr<SqliteDb> db_;
};

class PostgresWebhookStore : public WebhookStore {
 public:
  /// Connects and creates the table when missing; throws std::runtime_error naming the URL.
  explicit PostgresWebhookStore(const std::string& url);
  std::vector<StoredWebhook> load() override;
  void insert(const StoredWebhook& w) override;
  bool remove(const std::string& id) override;
  void update(const WebhookStatus& s) override;
  Claim claim(const std::string& id, const std::string& replica, std::int64_t nowNs,
              std::int64_t leaseNs) override;
  [[nodiscard]] bool shared() const override { return true; }

 private:
  std::string url_;
  std::mutex m_;
  pg::Connection conn_;
};

}  // namespace fleet::wms
