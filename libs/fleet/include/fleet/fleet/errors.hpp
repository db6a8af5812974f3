#pragma once

namespace fleet::errc {

/// `Error::code` values returned by the fleet library, so services can map them to HTTP statuses
/// (invalid → 400, not_found → 404, conflict → 409, storage → 503).
inline constexpr const char* kInvalid = "invalid";
inline constexpr const char* kUnknownStation = "unknown_station";
inline constexpr const char* kNotFound = "not_found";
inline constexpr const char* kConflict = "conflict";
inline constexpr const char* kIllegalTransition = "illegal_transition";
inline constexpr const char* kStorage = "storage";
inline constexpr const char* kWrongRobot = "wrong_robot";
/// A write refused because the writer's lease epoch is no longer the current one (another fleet
/// manager took over): nothing was stored.
inline constexpr const char* kFenced = "fenced";
/// The database's schema is newer than this binary's: refused, nothing changed.
inline constexpr const char* kSchemaNewer = "schema_newer";
/// A fault of the service itself, not of the request (an order that cannot be built).
inline constexpr const char* kInternal = "internal";

}  // namespace fleet::errc
