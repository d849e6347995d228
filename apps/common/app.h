// The shell every LCM app shares: time, channel names, logging, stop signals, the status
// heartbeat with its counters, a decode that never throws, and the handleTimeout loop.
// Apps are thin: lib/ does the work, these helpers do the plumbing the same way everywhere.
#pragma once

#include "fact/app_status_t.hpp"
#include "fact/detections_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/gossip_packet_t.hpp"
#include "fact/gossip_request_t.hpp"
#include "fact/gossip_summary_t.hpp"
#include "fact/round_packet_t.hpp"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact/truth_t.hpp"

#include <lcm/lcm-cpp.hpp>

#include <cstdint>
#include <exception>
#include <functional>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace fact::app {

// The time every app reads, in microseconds (the LCM utime convention): the wall clock since the
// Unix epoch, or, after follow_sim_clock(), the simulator's clock.
int64_t now_us();

// A clock for timeouts and schedules, µs: the simulation clock after follow_sim_clock(), else the
// steady clock (from an arbitrary start), which a wall-clock step (NTP or GPS time set on the
// drone) does not move. Message and log stamps keep now_us() (a step back of 1 h froze
// fact-fc-bridge's stream rules on the wall clock: review, session 30).
int64_t monotonic_us();

// Switches now_us() to the simulation clock: fact::sim_clock_t ticks on `channel` (from fact-sim).
// now_us() then returns the newest simulated time received (it never goes back; 0 before the
// first tick). Undecodable ticks, and ticks at a time not in (0, 5e15] µs (a clock held there for
// good), are counted and ignored. Call once, before the app's loop.
void follow_sim_clock(lcm::LCM& lcm, const std::string& channel);
bool following_sim_clock();
struct SimClockTicks {
  int64_t undecodable = 0, refused = 0;
};
SimClockTicks sim_clock_ticks_dropped();  // since the start
// Handles LCM messages until the first simulation tick arrives: true, or false after timeout_ms
// (or a stop request) without one.
bool wait_for_sim_clock(lcm::LCM& lcm, int timeout_ms);

// Per-drone channel name: channel("FACT_ODOMETRY", 3) == "FACT_ODOMETRY_3".
// A negative drone id means "not per drone" and returns base unchanged.
std::string channel(const std::string& base, int drone_id);

// SIGINT / SIGTERM set a flag instead of killing the process, so the app leaves its loop cleanly.
void install_stop_handler();
bool stop_requested();
void request_stop();  // the same flag, set from code (a fatal condition, tests)
void clear_stop();    // lowers the flag again (tests running several loops in one process)

// One line per meaningful event on stderr: "2024-05-01T12:00:00.123Z fact-gossip[3] <line>".
class Log {
 public:
  Log(std::string app, int drone_id);
  void event(const std::string& line) const;
  const std::string& app() const { return app_; }
  int drone_id() const { return drone_id_; }

 private:
  std::string app_;
  int drone_id_;
};

// True when lcm opened; else logs "error: cannot open LCM at <url>" (url "" = LCM's default) and
// returns false.
bool lcm_opened(const lcm::LCM& lcm, const std::string& url, const Log& log);

// Heartbeat and counters of one app: fact::app_status_t on `channel` (FACT_STATUS by default),
// about once per period. Counters appear in the order they were first counted.
class Status {
 public:
  // lcm may be null (nothing is published; the counters still count).
  Status(lcm::LCM* lcm, std::string channel, std::string app, int drone_id);

  void count(const std::string& name, int64_t n = 1);
  int64_t value(const std::string& name) const;  // 0 for a counter never counted
  void set_state(const std::string& s);          // e.g. "running", "waiting for peers"
  void note(const std::string& message);         // the last notable event
  void set_period_us(int64_t period_us);         // default 1 000 000 µs
  int64_t period_us() const { return period_us_; }

  void tick(int64_t now);     // publishes when ≥ period since the last publish (or never published)
  void publish(int64_t now);  // publishes now
  int64_t published() const { return published_; }  // messages published so far

 private:
  lcm::LCM* lcm_;
  std::string channel_, app_;
  int drone_id_;
  std::string state_ = "starting", message_;
  std::vector<std::string> names_;
  std::map<std::string, int64_t> values_;
  int64_t period_us_ = 1000000;
  int64_t last_publish_ = 0;
  bool ever_published_ = false;
  int64_t published_ = 0;
};

// The value of counter `name` in a received heartbeat (the reading side of Status, for tools and
// tests that check an app's counters); nullopt when the message has no such counter.
std::optional<int64_t> counter_value(const fact::app_status_t& m, const std::string& name);

namespace detail {
// lcm-gen's decoders resize every variable-length array to the count read from the wire before
// checking that the bytes hold it, so a crafted message with the right fingerprint and a count of
// 2^31 − 1 would allocate gigabytes. These walk the wire format first and say whether every count
// fits in the bytes that remain (each element needs at least its minimum encoded size). Types with
// no variable-length arrays need no check (the template). Keep in step with lcmtypes/*.lcm: the
// round-trip tests of every type (test/test_lcm_messages.cpp) fail if a walker goes stale.
template <class T>
bool counts_fit(const T*, const void*, int) { return true; }
bool counts_fit(const fact::app_status_t*, const void* data, int size);
bool counts_fit(const fact::detections_t*, const void* data, int size);
bool counts_fit(const fact::frame_t*, const void* data, int size);
bool counts_fit(const fact::gossip_packet_t*, const void* data, int size);
bool counts_fit(const fact::gossip_request_t*, const void* data, int size);
bool counts_fit(const fact::gossip_summary_t*, const void* data, int size);
bool counts_fit(const fact::round_packet_t*, const void* data, int size);
bool counts_fit(const fact::swarm_result_t*, const void* data, int size);
bool counts_fit(const fact::swarm_rounds_t*, const void* data, int size);
bool counts_fit(const fact::truth_t*, const void* data, int size);
}  // namespace detail

// Why a buffer does not decode as T ("" when it does): too short, a foreign fingerprint,
// a count that the bytes cannot hold, truncated, trailing bytes, or the decoder throwing (a
// negative count or string length). Never throws. On failure *msg is left in an unspecified state.
template <class T>
std::string decode_error(const void* data, int size, T* msg) {
  if (data == nullptr || size < 8) return "too short (" + std::to_string(size) + " bytes)";
  try {
    uint64_t hash = 0;  // big-endian fingerprint, as lcm-gen writes it
    for (int i = 0; i < 8; ++i) hash = (hash << 8) | static_cast<const uint8_t*>(data)[i];
    if (hash != static_cast<uint64_t>(T::getHash()))
      return "foreign fingerprint, not a " + std::string(T::getTypeName()) + " (" + std::to_string(size) + " bytes)";
    if (!detail::counts_fit(msg, data, size))
      return "an array count larger than the " + std::to_string(size) + " bytes can hold";
    int n = msg->decode(data, 0, size);
    if (n < 0) return "truncated or malformed (" + std::to_string(size) + " bytes)";
    if (n != size)
      return std::to_string(size - n) + " trailing bytes after a " + std::to_string(n) + "-byte message";
    return "";
  } catch (const std::exception& e) {
    return std::string("decoder failed: ") + e.what() + " (" + std::to_string(size) + " bytes)";
  } catch (...) {
    return "decoder failed (" + std::to_string(size) + " bytes)";
  }
}

// Whether an odometry sample (seq, utime µs) after the newest one taken (last_seq, last_utime)
// starts a new stream: fact-vio-relay restarted (seq 0 again after a VIO clock reset, or the relay
// itself restarted). A seq going back counts when it is 0, goes back more than UDP reordering can
// (64 samples), or comes with a time more than 1 s earlier; one reordered datagram (a seq and a
// time just below the newest) is not a restart, and the caller refuses it as out of order.
bool odometry_restarted(int64_t last_seq, int64_t last_utime, int64_t seq, int64_t utime);

// Logs "<line> (<counter> = <n>)" for the n-th event of a counter kept elsewhere: the first 10,
// then every 100th, so that a flood of bad input cannot flood the log.
void log_counted(const Log& log, const std::string& counter, int64_t n, const std::string& line);
// Counts one event on `counter` in the status and logs it as log_counted does.
void count_and_log(Status& status, const Log& log, const std::string& counter, const std::string& line);

// Decodes a received message; on failure (truncated, foreign fingerprint, garbage counts) counts
// "undecodable" on status (when given), logs the channel, the byte count and the reason, and
// returns false. Never throws. To keep a flood of garbage from flooding the log, with a status
// only the first 10 failures and then every 100th are logged (each line gives the total so far).
template <class T>
bool decode(const lcm::ReceiveBuffer* rbuf, const std::string& channel, T* msg, Status* status,
            const Log& log) {
  std::string err = rbuf ? decode_error(rbuf->data, static_cast<int>(rbuf->data_size), msg)
                         : std::string("no buffer");
  if (err.empty()) return true;
  int64_t total = 1;
  if (status) {
    status->count("undecodable");
    total = status->value("undecodable");
  }
  if (total <= 10 || total % 100 == 0)
    log.event("undecodable message on " + channel + " (" + std::to_string(rbuf ? rbuf->data_size : 0) +
              " bytes, expected " + T::getTypeName() + "): " + err + "; " + std::to_string(total) +
              " undecodable so far");
  return false;
}

// handleTimeout over several LCM instances (e.g. a drone's own bus and the swarm's): waits up to
// wait_us for a message on any of them, then handles one on each that has one. Returns how many
// were handled (> 0); 0 when the wait ran out or a signal interrupted it; -1 when poll failed
// (errno says why); -2 when an instance's handle() failed.
int handle_any(const std::vector<lcm::LCM*>& lcms, int64_t wait_us);

// Loops until stop_requested(): waits up to period_ms for a message on lcm or on any of `more`
// (other LCM instances, e.g. a separate frames URL), handles what arrived, then calls
// every(now_us()). Returns 0, or 1 (after logging to stderr) if LCM fails.
int run_loop(lcm::LCM& lcm, int period_ms, std::function<void(int64_t now)> every,
             const std::vector<lcm::LCM*>& more = {});

// Like run_loop, for apps with a schedule (e.g. a setpoint stream): every(now) returns the time
// (µs, the now_us() clock) of its next deadline, and the loop waits on the LCM socket until that
// deadline (at most max_wait_us) with microsecond resolution, handling messages as they come, so
// a deadline is met as closely as the scheduler allows rather than on a polling grid. Under the
// simulation clock the wait needs no cap: simulated time moves only when a tick arrives on a
// polled socket, and that ends the wait. `more` as in run_loop. `clock` is the time every() gets
// and its deadlines are on: now_us, or monotonic_us for a schedule that a wall-clock step must not
// stall or cut short (fact-planner).
int run_deadline_loop(lcm::LCM& lcm, int64_t max_wait_us, std::function<int64_t(int64_t now)> every,
                      const std::vector<lcm::LCM*>& more = {},
                      int64_t (*clock)() = &now_us);

}  // namespace fact::app
