#include "common/log_reader.h"

namespace fact::app {

std::string for_each_log_event(const std::string& path, const std::function<void(const lcm::LogEvent&)>& on_event) {
  lcm::LogFile log(path, "r");
  if (!log.good()) return "cannot read the LCM log " + path;
  int64_t events = 0;
  for (const lcm::LogEvent* e = log.readNextEvent(); e; e = log.readNextEvent()) {
    ++events;
    on_event(*e);
  }
  if (events == 0) return "the LCM log " + path + " holds no events (empty or not an LCM log)";
  return "";
}

}  // namespace fact::app
