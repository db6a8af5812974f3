#pragma once

// Runs a shell command in a test and keeps its exit code and its output (stdout and stderr).

#include <sys/wait.h>

#include <array>
#include <cstdio>
#include <string>

namespace fleet::test {

struct Outcome {
  int code = -1;  ///< exit code, -1 when it did not exit normally
  std::string output;
};

inline Outcome runCommand(const std::string& cmd) {
  Outcome r;
  FILE* p = popen((cmd + " 2>&1").c_str(), "r");
  std::array<char, 512> buf{};
  while (p != nullptr && fgets(buf.data(), buf.size(), p) != nullptr) {
    r.output += buf.data();
  }
  const int status = p != nullptr ? pclose(p) : -1;
  r.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

}  // namespace fleet::test
