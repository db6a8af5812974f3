#include "fleet/core/bounded_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace fleet {

namespace {

std::string kindOf(mode_t mode) {
  if (S_ISDIR(mode)) {
    return "a directory";
  }
  if (S_ISFIFO(mode)) {
    return "a FIFO";
  }
  if (S_ISCHR(mode)) {
    return "a character device";
  }
  if (S_ISBLK(mode)) {
    return "a block device";
  }
  if (S_ISSOCK(mode)) {
    return "a socket";
  }
  return "not a regular file";
}

// Closes the descriptor on every way out.
struct Fd {
  int fd;
  ~Fd() {
    if (fd >= 0) {
      ::close(fd);
    }
  }
};

}  // namespace

Expected<std::string> readBoundedFile(const std::string& path, std::uint64_t limit, const std::string& code) {
  // O_NONBLOCK: opening a FIFO for reading would otherwise wait for a writer, for good.
  Fd f{::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC)};
  if (f.fd < 0) {
    return unexpected(code, path + ": cannot open the file: " + std::strerror(errno));
  }
  struct stat st {};
  if (::fstat(f.fd, &st) != 0) {
    return unexpected(code, path + ": cannot stat file: " + std::strerror(errno));
  }
  if (!S_ISREG(st.st_mode)) {
    return unexpected(code, path + ": is " + kindOf(st.st_mode) + ", expected a regular file");
  }
  const auto size = static_cast<std::uint64_t>(st.st_size);
  auto tooLarge = [&](std::uint64_t n) {
    return unexpected(code, path + ": is " + std::to_string(n) + " bytes, more than the limit of " +
                                std::to_string(limit) + " bytes for this kind of file");
  };
  if (size > limit) {
    return tooLarge(size);
  }
  std::string out;
  out.resize(static_cast<std::size_t>(size));
  std::size_t got = 0;
  // Read to the end rather than to the stat size (the file may change meanwhile), never past the limit.
  while (true) {
    if (got == out.size()) {
      if (out.size() >= limit + 1) {
        return tooLarge(out.size());
      }
      out.resize(static_cast<std::size_t>(std::min<std::uint64_t>(limit + 1, out.size() + 64 * kKiB)));
    }
    const ssize_t n = ::read(f.fd, out.data() + got, out.size() - got);
    if (n < 0) {
      if (errno == EINTR) {
        continue;
      }
      return unexpected(code, path + ": read failed: " + std::strerror(errno));
    }
    if (n == 0) {
      break;
    }
    got += static_cast<std::size_t>(n);
    if (got > limit) {
      return tooLarge(got);
    }
  }
  out.resize(got);
  return out;
}

}  // namespace fleet
