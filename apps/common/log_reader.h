// Reading a recorded LCM log (an lcm-logger file) event by event with the checked decode, shared
// by the tools that judge or compare recorded runs (fact-run-report, fact-log-compare).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <cstdio>
#include <functional>
#include <iostream>
#include <map>
#include <string>

#include "common/app.h"

namespace fact::app {

// An LCM log (lcm-logger's format: per event the sync word 0xEDA1DA01, eventnum, timestamp,
// channel length, data length, all big-endian, then channel and data) read event by event with
// every length checked before anything is allocated. LCM's own reader crashed on a data length
// of 2^31 − 1 and took a damaged event for the end of the log, losing the rest silently.
class LogReader {
 public:
  // "" or why the file cannot be read.
  std::string open(const std::string& path);
  // The next event into *event (its channel and data stay valid until the next call): true, or
  // false at the end. At the end, error() says what stopped it: "" for a clean end; a torn last
  // event (the file ends inside it: a recorder killed mid-write) sets torn() and a note, which
  // callers print as a warning; any other damage (a wrong sync word, a channel length outside
  // 1 … 999, a data length beyond the file) is an error naming the event and its byte offset.
  bool next(lcm::LogEvent* event);
  const std::string& error() const { return error_; }
  bool torn() const { return torn_; }
  const std::string& note() const { return note_; }
  int64_t events() const { return events_; }

 private:
  std::string path_;
  std::FILE* file_ = nullptr;
  int64_t size_ = 0, offset_ = 0, events_ = 0;
  std::string channel_, data_, error_, note_;
  bool torn_ = false;

 public:
  LogReader() = default;
  LogReader(const LogReader&) = delete;
  LogReader& operator=(const LogReader&) = delete;
  ~LogReader();
};

// Calls on_event for every event of the log at `path`, in log order (`app` names the caller in
// warnings). Returns "" when the log was
// read, else why it cannot be used: it cannot be opened, it is damaged (LogReader), or it holds
// no events (empty, or not an LCM log at all). A torn last event is reported on stderr as a
// warning by `app` and the events before it are used.
std::string for_each_log_event(const std::string& path, const std::string& app,
                               const std::function<void(const lcm::LogEvent&)>& on_event);

// Decodes log events with decode_error's checks. An event that does not decode is counted per
// channel and reported on stderr (the first 3 per channel, naming the event number, the channel
// and the reason); nothing is thrown and the reading goes on.
class LogDecoder {
 public:
  explicit LogDecoder(std::string app) : app_(std::move(app)) {}

  template <class T>
  bool decode(const lcm::LogEvent& e, T* msg) {
    const std::string err = decode_error(e.data, e.datalen, msg);
    if (err.empty()) return true;
    if (undecodable_[e.channel]++ < 3)
      std::cerr << app_ << ": undecodable message on " << e.channel << " (event " << e.eventnum << "): " << err << "\n";
    return false;
  }
  // Counts a message that decoded but is unusable (e.g. a NaN field) under `what`; the first one
  // is reported with `why`.
  void reject(const std::string& what, const std::string& why) {
    if (undecodable_[what]++ == 0) std::cerr << app_ << ": " << why << "\n";
  }
  const std::map<std::string, int>& undecodable() const { return undecodable_; }

 private:
  std::string app_;
  std::map<std::string, int> undecodable_;  // channel (or what was rejected) → count
};

}  // namespace fact::app
