#include "fleet/service/process_metrics.hpp"

#include <dirent.h>
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>
#include <sstream>

#include "fleet/metrics/exposition.hpp"

namespace fleet::service {
namespace {

std::optional<std::string> readAll(const char* path) {
  std::ifstream in(path);
  if (!in) {
    return std::nullopt;
  }
  std::ostringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

/// The boot time (seconds since the epoch): the "btime" line of /proc/stat.
std::optional<double> bootTime() {
  std::ifstream in("/proc/stat");
  std::string line;
  while (std::getline(in, line)) {
    double v = 0;
    if (line.starts_with("btime ") && std::istringstream(line.substr(6)) >> v) {
      return v;
    }
  }
  return std::nullopt;
}

std::optional<double> countOpenFds() {
  DIR* d = ::opendir("/proc/self/fd");
  if (d == nullptr) {
    return std::nullopt;
  }
  double n = 0;
  while (const dirent* e = ::readdir(d)) {
    if (e->d_name[0] != '.') {
      ++n;
    }
  }
  ::closedir(d);
  return n - 1;  // the directory stream's own descriptor
}

}  // namespace

std::optional<ProcessStats> readProcessStats() {
  const auto stat = readAll("/proc/self/stat");
  const auto boot = bootTime();
  if (!stat || !boot) {
    return std::nullopt;
  }
  // The command name (field 2) is in parentheses and may hold spaces or ')': fields 3 onwards
  // follow the last ')'.
  const auto close = stat->rfind(')');
  if (close == std::string::npos) {
    return std::nullopt;
  }
  std::istringstream fields(stat->substr(close + 1));
  std::string skip;
  double utime = 0, stime = 0, start = 0, vsize = 0, rssPages = 0;
  // Fields 3..13, then utime (14) and stime (15), 16..21, starttime (22), vsize (23), rss (24).
  for (int f = 3; f <= 13; ++f) {
    fields >> skip;
  }
  fields >> utime >> stime;
  for (int f = 16; f <= 21; ++f) {
    fields >> skip;
  }
  fields >> start >> vsize >> rssPages;
  if (!fields) {
    return std::nullopt;
  }
  const double ticks = static_cast<double>(::sysconf(_SC_CLK_TCK));
  const double page = static_cast<double>(::sysconf(_SC_PAGESIZE));
  ProcessStats s;
  s.cpuSeconds = (utime + stime) / ticks;
  s.residentBytes = rssPages * page;
  s.virtualBytes = vsize;
  s.startTimeSeconds = *boot + start / ticks;
  s.openFds = countOpenFds().value_or(0.0);
  rlimit lim{};
  if (::getrlimit(RLIMIT_NOFILE, &lim) == 0) {
    s.maxFds = static_cast<double>(lim.rlim_cur);
  }
  return s;
}

std::string processMetricsText(const ProcessStats& s) {
  std::string out;
  auto family = [&out](const char* name, const char* type, const char* help, double v) {
    out += std::string("# HELP ") + name + " " + help + "\n# TYPE " + name + " " + type + "\n" + name + " " +
           metrics::formatValue(v) + "\n";
  };
  family("process_cpu_seconds_total", "counter", "Total user and system CPU time spent in seconds.",
         s.cpuSeconds);
  family("process_max_fds", "gauge", "Maximum number of open file descriptors.", s.maxFds);
  family("process_open_fds", "gauge", "Number of open file descriptors.", s.openFds);
  family("process_resident_memory_bytes", "gauge", "Resident memory size in bytes.", s.residentBytes);
  family("process_start_time_seconds", "gauge", "Start time of the process since unix epoch in seconds.",
         s.startTimeSeconds);
  family("process_virtual_memory_bytes", "gauge", "Virtual memory size in bytes.", s.virtualBytes);
  return out;
}

std::string processMetricsText() {
  const auto s = readProcessStats();
  return s ? processMetricsText(*s) : std::string();
}

}  // namespace fleet::service
