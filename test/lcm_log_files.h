// LCM log files in tests of the log tools (fact-log-merge, fact-log-compare): events written with
// lcm::LogFile and read back; the tests' temporary directories come from temp_dir.h.
#pragma once

#include <gtest/gtest.h>
#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include "temp_dir.h"

namespace fact::test {

// One event of a log: receive time (µs), channel and the message's bytes.
struct LoggedEvent {
  int64_t timestamp;
  std::string channel;
  std::string data;
};

// Writes events, in order, as an lcm-logger file at path.
inline void write_log(const std::filesystem::path& path, const std::vector<LoggedEvent>& events) {
  lcm::LogFile log(path.string(), "w");
  ASSERT_TRUE(log.good()) << path;
  for (const LoggedEvent& e : events) {
    lcm::LogEvent le;
    le.eventnum = 0;
    le.timestamp = e.timestamp;
    le.channel = e.channel;
    le.datalen = static_cast<int32_t>(e.data.size());
    le.data = const_cast<char*>(e.data.data());
    ASSERT_EQ(log.writeEvent(&le), 0);
  }
}

// Every event of the log at path (none when it cannot be read).
inline std::vector<LoggedEvent> read_log(const std::filesystem::path& path) {
  std::vector<LoggedEvent> out;
  lcm::LogFile log(path.string(), "r");
  if (!log.good()) return out;
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent())
    out.push_back({e->timestamp, e->channel, std::string(static_cast<const char*>(e->data), e->datalen)});
  return out;
}

}  // namespace fact::test
