#include "common/app.h"

#include "fact/app_status_t.hpp"
#include "fact/sim_clock_t.hpp"

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <poll.h>
#include <chrono>
#include <csignal>
#include <cstdio>
#include <ctime>
#include <iostream>
#include <utility>

namespace fact::app {

namespace {
std::atomic<bool> g_sim_clock{false};
std::atomic<int64_t> g_sim_now{0};
std::atomic<int64_t> g_ticks_undecodable{0}, g_ticks_refused{0};

// The latest simulated time a tick may carry (µs since the epoch, about the year 2128): fact-sim's
// own epoch is at most 4e15 and its duration 1e7 s. A tick beyond it, or not positive, would hold
// the clock there for good (a tick at INT64_MAX − 5 did: review, session 33).
constexpr int64_t kLatestSimTime = 5000000000000000;

void on_sim_clock(const lcm::ReceiveBuffer* rbuf, const std::string&, void*) {
  fact::sim_clock_t tick;
  if (!rbuf || !decode_error(rbuf->data, static_cast<int>(rbuf->data_size), &tick).empty()) {
    ++g_ticks_undecodable;
    return;
  }
  if (tick.utime <= 0 || tick.utime > kLatestSimTime) {
    ++g_ticks_refused;
    return;
  }
  int64_t seen = g_sim_now.load();
  while (tick.utime > seen && !g_sim_now.compare_exchange_weak(seen, tick.utime)) {
  }
}
}  // namespace

int64_t now_us() {
  if (g_sim_clock.load()) return g_sim_now.load();
  using namespace std::chrono;
  return duration_cast<microseconds>(system_clock::now().time_since_epoch()).count();
}

int64_t monotonic_us() {
  if (g_sim_clock.load()) return g_sim_now.load();
  using namespace std::chrono;
  return duration_cast<microseconds>(steady_clock::now().time_since_epoch()).count();
}

void follow_sim_clock(lcm::LCM& lcm, const std::string& channel) {
  lcm.subscribeFunction(channel, &on_sim_clock, static_cast<void*>(nullptr));
  g_sim_clock = true;
}

bool following_sim_clock() { return g_sim_clock.load(); }

SimClockTicks sim_clock_ticks_dropped() { return {g_ticks_undecodable.load(), g_ticks_refused.load()}; }

bool wait_for_sim_clock(lcm::LCM& lcm, int timeout_ms) {
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (g_sim_now.load() == 0 && !stop_requested()) {
    const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    if (lcm.handleTimeout(static_cast<int>(std::min<int64_t>(left.count(), 100))) < 0 && errno != EINTR) return false;
  }
  return g_sim_now.load() != 0;
}

std::string channel(const std::string& base, int drone_id) {
  if (drone_id < 0) return base;
  return base + "_" + std::to_string(drone_id);
}

namespace {
volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_stop_signal(int) { g_stop = 1; }
}  // namespace

void install_stop_handler() {
  struct sigaction sa {};
  sa.sa_handler = on_stop_signal;
  sigemptyset(&sa.sa_mask);
  sa.sa_flags = 0;  // no SA_RESTART: a blocking wait returns and the loop sees the flag
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
}

bool stop_requested() { return g_stop != 0; }
void request_stop() { g_stop = 1; }
void clear_stop() { g_stop = 0; }

Log::Log(std::string app, int drone_id) : app_(std::move(app)), drone_id_(drone_id) {}

void Log::event(const std::string& line) const {
  int64_t t = now_us();
  std::time_t secs = static_cast<std::time_t>(t / 1000000);
  std::tm tm{};
  gmtime_r(&secs, &tm);
  char stamp[64];
  std::snprintf(stamp, sizeof stamp, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900,
                tm.tm_mon + 1, tm.tm_mday, tm.tm_hour, tm.tm_min, tm.tm_sec,
                static_cast<int>((t % 1000000) / 1000));
  std::string out = std::string(stamp) + " " + app_ + "[" + std::to_string(drone_id_) + "] " + line + "\n";
  std::fwrite(out.data(), 1, out.size(), stderr);  // one write per line: lines of apps sharing a terminal do not interleave
  std::fflush(stderr);
}

Status::Status(lcm::LCM* lcm, std::string channel, std::string app, int drone_id)
    : lcm_(lcm), channel_(std::move(channel)), app_(std::move(app)), drone_id_(drone_id) {}

void Status::count(const std::string& name, int64_t n) {
  auto it = values_.find(name);
  if (it == values_.end()) {
    names_.push_back(name);
    values_.emplace(name, n);
  } else {
    it->second += n;
  }
}

int64_t Status::value(const std::string& name) const {
  auto it = values_.find(name);
  return it == values_.end() ? 0 : it->second;
}

std::optional<int64_t> counter_value(const fact::app_status_t& m, const std::string& name) {
  const std::size_t n = std::min({static_cast<std::size_t>(std::max(m.num_counters, 0)), m.counter_names.size(),
                                  m.counter_values.size()});
  for (std::size_t i = 0; i < n; ++i)
    if (m.counter_names[i] == name) return m.counter_values[i];
  return std::nullopt;
}

void Status::set_state(const std::string& s) { state_ = s; }
void Status::note(const std::string& message) { message_ = message; }
void Status::set_period_us(int64_t period_us) { period_us_ = period_us > 0 ? period_us : 1; }

bool odometry_restarted(int64_t last_seq, int64_t last_utime, int64_t seq, int64_t utime) {
  constexpr int64_t kReorderSamples = 64, kReorderUs = 1000000;
  if (seq >= last_seq) return false;
  return seq == 0 || last_seq - seq > kReorderSamples || utime < last_utime - kReorderUs;
}

void log_counted(const Log& log, const std::string& counter, int64_t n, const std::string& line) {
  if (n <= 10 || n % 100 == 0) log.event(line + " (" + counter + " = " + std::to_string(n) + ")");
}

void count_and_log(Status& status, const Log& log, const std::string& counter, const std::string& line) {
  status.count(counter);
  log_counted(log, counter, status.value(counter), line);
}

void Status::tick(int64_t now) {
  // (now before the last publication: the wall clock was set back; publishing again re-bases the
  // period instead of going quiet until the clock catches up)
  if (!ever_published_ || now - last_publish_ >= period_us_ || now < last_publish_) publish(now);
}

void Status::publish(int64_t now) {
  last_publish_ = now;
  ever_published_ = true;
  if (lcm_ == nullptr) return;
  fact::app_status_t m;
  m.utime = now;
  m.drone_id = drone_id_;
  m.app = app_;
  m.state = state_;
  m.num_counters = static_cast<int32_t>(names_.size());
  for (const auto& name : names_) {
    m.counter_names.push_back(name);
    m.counter_values.push_back(values_.at(name));
  }
  m.message = message_;
  if (lcm_->publish(channel_, &m) == 0) ++published_;
}

namespace detail {
namespace {

// A read-only cursor over an LCM encoding (big-endian), for the count checks below.
class Wire {
 public:
  Wire(const void* data, int size) : p_(static_cast<const uint8_t*>(data)), size_(size) {}
  bool skip(int64_t bytes) {
    if (bytes < 0 || bytes > size_ - pos_) return false;
    pos_ += static_cast<int>(bytes);
    return true;
  }
  bool i32(int32_t* v) {
    if (size_ - pos_ < 4) return false;
    uint32_t u = 0;
    for (int i = 0; i < 4; ++i) u = (u << 8) | p_[pos_ + i];
    pos_ += 4;
    *v = static_cast<int32_t>(u);
    return true;
  }
  // An array count whose elements each take at least min_bytes: 0 ≤ count and the rest holds them.
  bool count(int32_t* n, int64_t min_bytes) {
    return i32(n) && *n >= 0 && static_cast<int64_t>(*n) * min_bytes <= size_ - pos_;
  }
  bool string() {  // int32 length including the terminating NUL, then the bytes
    int32_t n = 0;
    return i32(&n) && n >= 1 && skip(n);
  }

 private:
  const uint8_t* p_;
  int size_;
  int pos_ = 0;
};

// round_packet_t without its fingerprint (as nested in swarm_rounds_t): utime, drone_id, round,
// position[3], yaw, count, observations (each 7 doubles).
constexpr int64_t kObservationBytes = 7 * 8;
constexpr int64_t kRoundPacketMinBytes = 8 + 4 + 4 + 24 + 8 + 4;
bool round_packet_body(Wire& w) {
  int32_t n = 0;
  return w.skip(8 + 4 + 4 + 24 + 8) && w.count(&n, kObservationBytes) && w.skip(n * kObservationBytes);
}

}  // namespace

bool counts_fit(const fact::app_status_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;  // each counter: a string (≥ 5 bytes) and an int64
  return w.skip(8 + 8 + 4) && w.string() && w.string() && w.count(&n, 5 + 8);
}
bool counts_fit(const fact::detections_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;  // detection_t: track_id, vector[3], box[4] (float), confidence (float), range
  return w.skip(8 + 8 + 4 + 8) && w.count(&n, 4 + 24 + 16 + 4 + 8);
}
bool counts_fit(const fact::frame_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t gray = 0, depth = 0;
  return w.skip(8 + 8 + 4 + 8 + 4 + 4 + 4 * 8) && w.count(&gray, 1) && w.skip(gray) && w.count(&depth, 2);
}
bool counts_fit(const fact::gossip_packet_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;
  return w.skip(8 + 8 + 4 + 8 + 1) && w.count(&n, 1);
}
bool counts_fit(const fact::gossip_request_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;
  return w.skip(8 + 8 + 4 + 4) && w.count(&n, 4);
}
bool counts_fit(const fact::gossip_summary_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;  // origins, rounds_held (int32) and digests (int64)
  return w.skip(8 + 8 + 4) && w.count(&n, 4 + 4 + 8);
}
bool counts_fit(const fact::round_packet_t*, const void* data, int size) {
  Wire w(data, size);
  return w.skip(8) && round_packet_body(w);
}
bool counts_fit(const fact::swarm_result_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;  // drone_pose_t: id, yaw, position[3], resolved (1 byte)
  return w.skip(8 + 8 + 4) && w.string() && w.string() && w.string() && w.skip(4 + 4) &&
         w.count(&n, 4 + 8 + 24 + 1);
}
bool counts_fit(const fact::swarm_rounds_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t drones = 0, packets = 0;
  if (!(w.skip(8 + 8 + 4 + 4) && w.count(&drones, 4) && w.skip(drones * int64_t{4}) &&
        w.count(&packets, kRoundPacketMinBytes)))
    return false;
  for (int32_t i = 0; i < packets; ++i)
    if (!round_packet_body(w)) return false;
  return true;
}
bool counts_fit(const fact::truth_t*, const void* data, int size) {
  Wire w(data, size);
  int32_t n = 0;  // per drone: id, frame_yaw, frame_origin[3], position[3], yaw
  return w.skip(8 + 8) && w.count(&n, 4 + 8 + 24 + 24 + 8);
}

}  // namespace detail

namespace {

// The LCM instances a loop serves, checked usable; empty (after logging) when one is not.
std::vector<lcm::LCM*> loop_instances(lcm::LCM& lcm, const std::vector<lcm::LCM*>& more) {
  std::vector<lcm::LCM*> all{&lcm};
  for (lcm::LCM* m : more)
    if (m) all.push_back(m);
  for (lcm::LCM* m : all)
    if (!m->good()) {
      std::cerr << "LCM is not usable (bad --lcm-url, or no network for udpm)\n";
      return {};
    }
  return all;
}

// Waits up to wait_us for any instance's socket, then handles one message on each readable one.
// 0 when fine (message or timeout), 1 when polling or LCM failed (logged), 2 when stopped.
int wait_and_handle(const std::vector<lcm::LCM*>& all, int64_t wait_us) {
  const int r = handle_any(all, wait_us);
  if (r == -1) {
    std::cerr << "poll on the LCM sockets failed\n";
    return 1;
  }
  if (r == -2) {
    if (stop_requested()) return 2;
    std::cerr << "LCM handle failed\n";
    return 1;
  }
  return 0;
}

}  // namespace

int handle_any(const std::vector<lcm::LCM*>& lcms, int64_t wait_us) {
  std::vector<pollfd> fds;
  for (lcm::LCM* m : lcms) fds.push_back(pollfd{m->getFileno(), POLLIN, 0});
  const timespec ts{static_cast<time_t>(wait_us / 1000000), static_cast<long>((wait_us % 1000000) * 1000)};
  const int r = ppoll(fds.data(), fds.size(), &ts, nullptr);
  if (r < 0) return errno == EINTR ? 0 : -1;
  int handled = 0;
  for (size_t i = 0; r > 0 && i < fds.size(); ++i) {
    if (!(fds[i].revents & POLLIN)) continue;
    if (lcms[i]->handle() < 0) return -2;
    ++handled;
  }
  return handled;
}

int run_loop(lcm::LCM& lcm, int period_ms, std::function<void(int64_t now)> every,
             const std::vector<lcm::LCM*>& more) {
  const std::vector<lcm::LCM*> all = loop_instances(lcm, more);
  if (all.empty()) return 1;
  const int64_t period_us = std::max(1, period_ms) * int64_t{1000};
  while (!stop_requested()) {
    const int r = wait_and_handle(all, period_us);
    if (r == 1) return 1;
    if (r == 2) break;
    if (every) every(now_us());
  }
  return 0;
}

int run_deadline_loop(lcm::LCM& lcm, int64_t max_wait_us, std::function<int64_t(int64_t now)> every,
                      const std::vector<lcm::LCM*>& more, int64_t (*clock)()) {
  const std::vector<lcm::LCM*> all = loop_instances(lcm, more);
  if (all.empty()) return 1;
  int64_t deadline = every(clock());
  while (!stop_requested()) {
    int64_t wait = std::clamp<int64_t>(deadline - clock(), 0, max_wait_us);
    const int r = wait_and_handle(all, wait);
    if (r == 1) return 1;
    if (r == 2) break;
    deadline = every(clock());
  }
  return 0;
}

bool lcm_opened(const lcm::LCM& lcm, const std::string& url, const Log& log) {
  if (lcm.good()) return true;
  log.event("error: cannot open LCM" + (url.empty() ? std::string() : " at " + url));
  return false;
}

}  // namespace fact::app
