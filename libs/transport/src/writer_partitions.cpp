#include "fleet/transport/writer_partitions.hpp"

#include <algorithm>

#include "fleet/transport/robot_partition.hpp"

namespace fleet::transport {

WriterPartitions::WriterPartitions() : listener_(dds_create_listener(this)) {
  dds_lset_subscription_matched(listener_, &WriterPartitions::onMatched);
}

WriterPartitions::~WriterPartitions() {
  dds_delete_listener(listener_);
}

void WriterPartitions::onMatched(dds_entity_t reader, dds_subscription_matched_status_t status, void* self) {
  if (status.current_count_change > 0) {
    static_cast<WriterPartitions*>(self)->learn(reader, status.last_publication_handle);
  }
}

bool WriterPartitions::learn(dds_entity_t reader, dds_instance_handle_t writer) {
  dds_builtintopic_endpoint_t* ep = dds_get_matched_publication_data(reader, writer);
  if (ep == nullptr) {
    return false;
  }
  std::vector<std::string> names;
  uint32_t n = 0;
  char** ps = nullptr;
  if (ep->qos != nullptr && dds_qget_partition(ep->qos, &n, &ps)) {
    for (uint32_t i = 0; i < n; ++i) {
      names.emplace_back(ps[i]);
      dds_free(ps[i]);
    }
    dds_free(ps);
  }
  dds_builtintopic_free_endpoint(ep);
  std::lock_guard lock(m_);
  partitions_[writer] = std::move(names);
  return true;
}

bool WriterPartitions::speaksFor(dds_entity_t reader, dds_instance_handle_t writer,
                                 const std::string& robot) {
  for (int attempt = 0; attempt < 2; ++attempt) {
    {
      std::lock_guard lock(m_);
      if (const auto it = partitions_.find(writer); it != partitions_.end()) {
        const auto& ps = it->second;
        if (robot.empty()) {
          return std::none_of(ps.begin(), ps.end(),
                              [](const std::string& p) { return p.starts_with(kRobotPartitionPrefix); });
        }
        const std::string mine = robotPartition(robot);
        return std::find(ps.begin(), ps.end(), mine) != ps.end();
      }
    }
    // The listener has not run yet for this writer (it runs on Cyclone's thread): ask now.
    if (!learn(reader, writer)) {
      return false;
    }
  }
  return false;
}

}  // namespace fleet::transport
