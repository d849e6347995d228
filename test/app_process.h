// A program that a test runs as a child process: started with posix_spawn, stdin from /dev/null,
// stdout and stderr into files, waited for with deadlines scaled by FACT_TEST_TIME_SCALE
// (test_time.h), and stopped (SIGTERM, then SIGKILL) when the test is done with it. The app
// tests (fact-sim, the simulated flight controller, fact-planner, fact-solver, fact-fc-bridge,
// fact-vio-relay) each start their app through it.
#pragma once

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <stdlib.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <system_error>
#include <thread>
#include <utility>
#include <vector>

#include "test_time.h"

extern char** environ;

namespace fact::test {

// The whole file as text ("" when it cannot be read).
inline std::string read_text(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// A new empty file <tmp>/<prefix>-XXXXXX (mkstemp: no two tests or processes share one), removed
// when this is destroyed. A class that runs an AppProcess with its output in such a file derives
// from TempFile first, so that the file exists before the process starts and outlives it.
class TempFile {
 public:
  explicit TempFile(const std::string& prefix) {
    std::string pattern = (std::filesystem::temp_directory_path() / (prefix + "-XXXXXX")).string();
    const int fd = mkstemp(pattern.data());
    if (fd >= 0) close(fd);
    path_ = pattern;
  }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  ~TempFile() {
    std::error_code ec;
    std::filesystem::remove(path_, ec);
  }
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_;
};

// {program, args...}: the words an AppProcess runs.
inline std::vector<std::string> command_line(const std::string& program, const std::vector<std::string>& args) {
  std::vector<std::string> words = {program};
  words.insert(words.end(), args.begin(), args.end());
  return words;
}

class AppProcess {
 public:
  using Clock = std::chrono::steady_clock;

  // Runs words[0] with words as its argv. stdout goes to `out` and stderr to `err` (created or
  // truncated); the same path for both collects them in one file in the order written, and
  // "/dev/null" discards.
  AppProcess(std::vector<std::string> words, const std::filesystem::path& out, const std::filesystem::path& err)
      : out_(out), err_(err) {
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
    posix_spawn_file_actions_addopen(&actions, 1, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    if (err == out)
      posix_spawn_file_actions_adddup2(&actions, 1, 2);
    else
      posix_spawn_file_actions_addopen(&actions, 2, err.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);
    if (words.empty() || posix_spawn(&pid_, words[0].c_str(), &actions, nullptr, argv.data(), environ) != 0) pid_ = -1;
    posix_spawn_file_actions_destroy(&actions);
  }
  AppProcess(const AppProcess&) = delete;
  AppProcess& operator=(const AppProcess&) = delete;
  // Still running: SIGTERM, and SIGKILL after 3 s (scaled).
  ~AppProcess() {
    if (!running()) return;
    kill(pid_, SIGTERM);
    if (wait_for(std::chrono::seconds(3)) == kStillRunning) {
      kill(pid_, SIGKILL);
      waitpid(pid_, nullptr, 0);
    }
  }

  bool started() const { return pid_ > 0; }
  // Still running? Reaps it, and keeps its exit code, once it has exited.
  bool running() {
    if (pid_ <= 0 || done_) return false;
    int status = 0;
    if (waitpid(pid_, &status, WNOHANG) == 0) return true;
    done_ = true;
    code_ = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
    return false;
  }
  // Waits up to limit × FACT_TEST_TIME_SCALE: the exit code, 128 + the signal that ended it, or
  // kStillRunning (−1) when it has not exited by then (or never started).
  static constexpr int kStillRunning = -1;
  int wait_for(Clock::duration limit) {
    const auto end = Clock::now() + fact::test::scaled(limit);
    while (running()) {
      if (Clock::now() >= end) return kStillRunning;
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return done_ ? code_ : kStillRunning;
  }
  // wait_for with the limit in seconds.
  int wait_s(double seconds) {
    return wait_for(std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds)));
  }
  // Sends `signal` (if still running), then wait_for(limit).
  int stop(int signal = SIGTERM, Clock::duration limit = std::chrono::seconds(5)) {
    if (running()) kill(pid_, signal);
    return wait_for(limit);
  }
  std::string out() const { return read_text(out_); }
  std::string err() const { return read_text(err_); }

 private:
  std::filesystem::path out_, err_;
  pid_t pid_ = -1;
  bool done_ = false;
  int code_ = kStillRunning;
};

}  // namespace fact::test
