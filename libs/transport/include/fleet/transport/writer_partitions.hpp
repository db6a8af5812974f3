#pragma once

// What a reader of a per-robot topic knows about the writers it is matched with: their partitions,
// looked up once per writer (Cyclone's publication handle in each sample's info) and kept. The
// lookup is made when the writer matches (a listener), before any of its samples can be taken, so a
// writer that has already left by the time its last sample is read is still known.

#include <dds/dds.h>

#include <mutex>
#include <string>
#include <unordered_map>
#include <vector>

namespace fleet::transport {

class WriterPartitions {
 public:
  WriterPartitions();
  ~WriterPartitions();
  WriterPartitions(const WriterPartitions&) = delete;
  WriterPartitions& operator=(const WriterPartitions&) = delete;

  /// The listener to create the reader with (it records each writer as it matches).
  [[nodiscard]] const dds_listener_t* listener() const { return listener_; }

  /// True when the writer of a sample (its publication handle) may speak for `robot`: it is in the
  /// partition "robot/<robot>". An empty `robot` (a sample about no robot) must come from a writer
  /// in no robot partition. False also when the writer cannot be found (never matched).
  bool speaksFor(dds_entity_t reader, dds_instance_handle_t writer, const std::string& robot);

 private:
  static void onMatched(dds_entity_t reader, dds_subscription_matched_status_t status, void* self);
  /// Looks the writer up in Cyclone and keeps its partitions; false when it is not matched.
  bool learn(dds_entity_t reader, dds_instance_handle_t writer);

  std::mutex m_;
  std::unordered_map<dds_instance_handle_t, std::vector<std::string>> partitions_;
  dds_listener_t* listener_;
};

}  // namespace fleet::transport
