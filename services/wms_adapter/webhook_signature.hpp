#pragma once

// How a webhook delivery is signed (docs/operator-guide.md#webhooks): HMAC-SHA256 with the
// subscription's secret over "<timestamp>.<body>", sent as
//   X-Fleet-Timestamp: <unix seconds>
//   X-Fleet-Signature: sha256=<64 lower-case hex digits>
// A receiver recomputes it, compares in constant time and refuses a timestamp too far from its
// clock (a replay).

#include <cstdint>
#include <string>

namespace fleet::wms {

/// HMAC-SHA256 of `message` with `key`, as 64 lower-case hex digits.
std::string hmacSha256Hex(const std::string& key, const std::string& message);

/// The X-Fleet-Signature value for `body` sent at `unixSeconds`.
std::string webhookSignature(const std::string& secret, std::int64_t unixSeconds, const std::string& body);

/// `bytes` random bytes from OpenSSL's generator as hex (secrets, subscription ids).
std::string randomHex(std::size_t bytes);

}  // namespace fleet::wms
