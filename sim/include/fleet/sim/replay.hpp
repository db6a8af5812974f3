#pragma once

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "fleet/core/expected.hpp"
#include "fleet/messages/messages.hpp"
#include "fleet/sim/world.hpp"

namespace fleet::sim {

/// First replay line: scenario name, map (rows as strings, top first), stations, robot ids and radii.
nlohmann::json replayHeader(const World& w);
/// One line per step: robots [x, y, theta, v, battery, charging, mode, task], humans [x, y, vx, vy],
/// contacts [a, b, depth] by id. Numbers rounded to mm / mrad so the file stays small and stable.
nlohmann::json replayStep(const World& w);
/// The traffic manager's roadmap as a replay step carries it (key "roadmap"): epoch, revision,
/// nodes flat [x0, y0, x1, y1, ...] to the centimetre, kinds per node (0 lane, 1 station, 2
/// approach, 3 queue, 4 parking, 5 charger), closed node ids, lanes [a, b, ...] (each pair of
/// nodes joined by an open edge once) and closed edges [from, to, ...].
nlohmann::json replayRoadmap(const msg::Roadmap& m);
/// A robot's release as a replay step carries it (under "releases", by robot id): {"b": base node
/// ids, "h": horizon node ids, "g": ends at its goal}.
nlohmann::json replayRelease(const msg::TrafficRelease& r);
/// End-of-run figures: metrics, counters, per-robot distance / idle time / bumps / battery.
nlohmann::json summary(const World& w);

/// Writes one JSON object per line into a gzip file (zlib; the gzip header carries no timestamp, so
/// equal content gives equal bytes).
class ReplayWriter {
 public:
  static Expected<ReplayWriter> open(const std::string& path);
  ReplayWriter(ReplayWriter&& o) noexcept;
  ReplayWriter& operator=(ReplayWriter&&) = delete;
  ReplayWriter(const ReplayWriter&) = delete;
  ~ReplayWriter();
  Expected<void> write(const nlohmann::json& line);
  Expected<void> close();

 private:
  explicit ReplayWriter(void* f) : f_(f) {}
  void* f_;
};

/// Reads every line of a (gzip or plain) replay.
Expected<std::vector<std::string>> readReplayLines(const std::string& path);

/// The self-contained HTML viewer with the replay lines embedded.
std::string viewerHtml(const std::vector<std::string>& replayLines);

}  // namespace fleet::sim
