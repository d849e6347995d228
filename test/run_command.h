// Running a command line in a test: its exit code and everything it wrote (stdout and stderr).
#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace fact::test {

struct Ran {
  int code;         // exit code, or -1 when the command did not exit normally
  std::string out;  // stdout and stderr, interleaved
};

// Runs `command` through the shell with stderr joined to stdout.
inline Ran run_command(const std::string& command) {
  const std::string cmd = command + " 2>&1";
  FILE* p = popen(cmd.c_str(), "r");
  if (p == nullptr) return {-1, "popen failed: " + command};
  std::string out;
  char buf[4096];
  for (size_t n; (n = fread(buf, 1, sizeof buf, p)) > 0;) out.append(buf, n);
  const int st = pclose(p);
  return {WIFEXITED(st) ? WEXITSTATUS(st) : -1, out};
}

}  // namespace fact::test
