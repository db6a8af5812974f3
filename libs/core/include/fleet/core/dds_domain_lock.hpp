#pragma once

// A DDS domain id no other fleet on this machine uses: two fleets on one domain take each other's
// orders (robots are keyed by id, and every fleet has an r1). Load-test runs and tests hold a lock
// file per domain (/tmp/fleet-test-dds-domain-N.lock) for their lifetime; the first of `count`
// domains from `first`, starting at `first + start % count`, whose lock this process can take is
// returned and held until the process ends (its file descriptor stays open). When every one is
// held, the starting one (shared, as it would be without the locks).

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <string>

namespace fleet {

inline int lockFreeDdsDomain(int first, int count, int start) {
  start = ((start % count) + count) % count;
  for (int k = 0; k < count; ++k) {
    const int d = first + (start + k) % count;
    const std::string path = "/tmp/fleet-test-dds-domain-" + std::to_string(d) + ".lock";
    const int fd = open(path.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0666);
    if (fd >= 0 && flock(fd, LOCK_EX | LOCK_NB) == 0) {
      return d;  // fd stays open: the lock lives as long as the process
    }
    if (fd >= 0) {
      close(fd);
    }
  }
  return first + start;
}

}  // namespace fleet
