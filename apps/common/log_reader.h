// Reading a recorded LCM log (an lcm-logger file) event by event with the checked decode, shared
// by the tools that judge or compare recorded runs (fact-run-report, fact-log-compare).
#pragma once

#include <lcm/lcm-cpp.hpp>

#include <functional>
#include <iostream>
#include <map>
#include <string>

#include "common/app.h"

namespace fact::app {

// Calls on_event for every event of the log at `path`, in log order. Returns "" when the log was
// read, else why it cannot be used: it cannot be opened, or it holds no events (empty, or not an
// LCM log at all).
std::string for_each_log_event(const std::string& path, const std::function<void(const lcm::LogEvent&)>& on_event);

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
