#pragma once

// The service manager's notification protocol (sd_notify(3)), spoken directly: one datagram to the
// Unix socket named by $NOTIFY_SOCKET (a leading '@' is the abstract namespace). Under a systemd
// unit with Type=notify a service says READY=1 once it serves, WATCHDOG=1 while its loop turns
// (when WatchdogSec= is set) and STOPPING=1 when it leaves. Without $NOTIFY_SOCKET (run by hand, in
// a container, in the tests) every call does nothing. No libsystemd: the protocol is a stable,
// documented interface, and a build without the library cannot leave a Type=notify unit waiting.

#include <chrono>
#include <optional>
#include <string>
#include <string_view>

namespace fleet::service {

/// Sends `state` ("READY=1", "WATCHDOG=1", "STOPPING=1", "STATUS=...", newline-separated) to
/// $NOTIFY_SOCKET. Returns "" when sent or when there is no socket to send to, else the error.
std::string notifyServiceManager(std::string_view state);

/// The watchdog period asked of this process ($WATCHDOG_USEC, when $WATCHDOG_PID is unset or this
/// process), or nothing when there is no watchdog. A bad value counts as none.
[[nodiscard]] std::optional<std::chrono::microseconds> watchdogPeriod();

}  // namespace fleet::service
