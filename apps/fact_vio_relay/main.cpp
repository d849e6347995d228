// fact-vio-relay: one drone's VIO odometry from one source in, one normalised fact::odometry_t
// stream out on FACT_ODOMETRY_<id>, through fact::OdometryFilter (lib/odometry_filter).
//
// Sources:
//   lcm  fact::odometry_t as the simulator publishes it (raw) on FACT_VIO_RAW_<id>; its velocity is
//        kept, a message with another drone_id is counted (wrong_drone_id) and dropped.
//   tum  a TUM trajectory file ("t tx ty tz qx qy qz qw" per line), replayed at real time × --rate
//        (0 = as fast as possible); the app exits 0 at the end of the file.
//   udp  one pose line per UDP datagram, in the same format, on --bind:--port.
// Pose lines: t in seconds, position in metres in f_i, the body's attitude as a Hamilton unit
// quaternion, world-from-body, FLU; yaw/pitch/roll are its Z-Y-X Euler angles (yaw = heading of the
// body x axis); velocity is the backward difference of consecutive published positions.
//
// Every sample is checked (non-finite fields, time not strictly increasing, position or yaw jumps
// faster than --max-speed / --max-yaw-rate, unusable quaternions, malformed lines); a rejected one
// is counted (status counters rejected_<reason>) and logged, at most one line per reason per second.
//
// Exit codes: 0 end of the TUM file, or stopped by SIGINT/SIGTERM; 1 LCM, the socket or the file
// failed while running; 2 bad flags or an unreadable --file.
#include "common/app.h"
#include "common/flags.h"
#include "fact/odometry_filter.h"
#include "fact/odometry_t.hpp"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <chrono>
#include <thread>
#include <vector>

namespace {

constexpr const char* kApp = "fact-vio-relay";
constexpr int kInputQueue = 1000;  // lcm source: messages LCM may hold for the input subscription

// Every parameter of the app, with its unit.
struct Options {
  fact::app::CommonFlags common;        // --drone-id (default 0), --lcm-url, status, --sim-clock
  std::string source = "lcm";           // lcm | tum | udp
  std::string input_channel;            // lcm source; empty = FACT_VIO_RAW_<id>
  std::string output_channel;           // empty = FACT_ODOMETRY_<id>
  std::string file;                     // tum source: the trajectory file
  double rate = 1.0;                    // tum source: replay speed, × real time; 0 = as fast as possible
  int port = 0;                         // udp source: port to listen on (1 … 65535)
  std::string bind = "127.0.0.1";       // udp source: IPv4 address to listen on
  bool restamp = false;                 // tum/udp: shift sample times so the first is "now" (µs)
  fact::OdometryFilterOptions filter;   // max_speed (m/s), max_yaw_rate (rad/s)
};

using fact::app::check_positive;
using fact::app::FlagError;

void add_flags(CLI::App& app, Options& o) {
  o.common.drone_id = 0;
  fact::app::add_common_flags(app, &o.common, fact::app::DroneIdFlag::optional);
  app.add_option("--source", o.source, "Where odometry comes from: lcm, tum or udp")
      ->type_name("SOURCE")
      ->capture_default_str();
  app.add_option("--input-channel", o.input_channel, "lcm source: raw odometry channel (default FACT_VIO_RAW_<id>)")
      ->type_name("CHANNEL");
  app.add_option("--output-channel", o.output_channel, "Output channel (default FACT_ODOMETRY_<id>)")
      ->type_name("CHANNEL");
  app.add_option("--file", o.file, "tum source: the TUM trajectory file to replay")->type_name("FILE");
  app.add_option("--rate", o.rate, "tum source: replay speed, x real time (0 = as fast as possible)")
      ->type_name("X")
      ->capture_default_str();
  app.add_option("--port", o.port, "udp source: UDP port to listen on (1-65535)")->type_name("PORT")
      ->check(fact::app::decimal_integer());
  app.add_option("--bind", o.bind, "udp source: IPv4 address to listen on")->type_name("ADDR")->capture_default_str();
  app.add_flag("--restamp", o.restamp, "tum (at --rate 1) / udp sources: shift sample times so the first is the wall clock");
  app.add_option("--max-speed", o.filter.max_speed, "Reject a position change faster than this (m/s, > 0)")
      ->type_name("M/S")
      ->capture_default_str();
  app.add_option("--max-yaw-rate", o.filter.max_yaw_rate, "Reject a yaw change faster than this (rad/s, > 0)")
      ->type_name("RAD/S")
      ->capture_default_str();
  app.footer(
      "Publishes fact::odometry_t (position m, velocity m/s, unwrapped yaw, roll, pitch rad, in the\n"
      "drone's odometry frame f_i: gravity-aligned FLU) with seq +1 per published sample.\n"
      "Pose lines (tum file lines, one per udp datagram; '#' comments and blank lines skipped):\n"
      "  t tx ty tz qx qy qz qw\n"
      "t in seconds, position in metres, the body's attitude as a Hamilton unit quaternion,\n"
      "world-from-body, body axes FLU; yaw = heading of the body x axis (Z-Y-X Euler angles).\n"
      "Velocity: the source's (lcm), else the difference of consecutive published positions.\n"
      "--restamp adds one offset to every time (the first sample's arrival minus its own time), taken\n"
      "again when a sample's restamped time is more than 10 s (the filter's gap limit) from its\n"
      "arrival, or its own time goes back more than 1 s: the VIO clock jumped (counted:\n"
      "restamp_rebased).\n"
      "Rejected, counted and logged (at most one line per reason per second): NaN/inf fields\n"
      "(rejected_nan), time not strictly increasing (rejected_out_of_order), position or yaw jumps\n"
      "faster than --max-speed/--max-yaw-rate or more than 10 s after the last published sample\n"
      "(rejected_jump), positions beyond 10 km, velocities beyond twice --max-speed, pitch outside\n"
      "[-pi/2, pi/2] or roll outside [-pi, pi] (rejected_range), unusable quaternions\n"
      "(rejected_attitude), malformed lines (rejected_malformed), times beyond int64 us\n"
      "(rejected_time); lcm: undecodable messages, another drone's (wrong_drone_id). When 20\n"
      "samples in a row are out of order or jumps but each follows the one before within the\n"
      "limits (a VIO whose clock or frame was reset), the 20th restarts the stream (seq 0,\n"
      "counted as restarts); a replay re-bases its pace after a gap over 10 s.\n"
      "Counters go out on the status channel as fact::app_status_t.\n"
      "--rate 0 publishes as fast as LCM goes: a subscriber keeps every sample only with a queue\n"
      "capacity above LCM's default of 30 messages per subscription.\n"
      "Exit codes: 0 end of the tum file, or SIGINT/SIGTERM; 1 LCM, socket or file failure;\n"
      "2 bad flags or unreadable --file.");
}

void only_for(const CLI::App& app, const char* flag, const std::string& source, const Options& o) {
  if (app.count(flag) > 0 && o.source != source)
    throw FlagError(std::string(flag) + " is only for --source " + source + " (the source is " + o.source + ")");
}

void check(const CLI::App& app, Options& o) {
  fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::optional);
  if (o.source != "lcm" && o.source != "tum" && o.source != "udp")
    throw FlagError("--source: expected lcm, tum or udp, got \"" + o.source + "\"");
  only_for(app, "--input-channel", "lcm", o);
  only_for(app, "--file", "tum", o);
  only_for(app, "--rate", "tum", o);
  only_for(app, "--port", "udp", o);
  only_for(app, "--bind", "udp", o);
  if (o.restamp && o.source == "lcm") throw FlagError("--restamp is only for --source tum or udp");
  if (o.input_channel.empty()) o.input_channel = fact::app::channel("FACT_VIO_RAW", o.common.drone_id);
  if (o.output_channel.empty()) o.output_channel = fact::app::channel("FACT_ODOMETRY", o.common.drone_id);
  if (o.source == "lcm" && o.input_channel == o.output_channel)
    throw FlagError("--input-channel and --output-channel are both " + o.output_channel + " (the relay would feed itself)");
  if (o.output_channel == o.common.status_channel)
    throw FlagError("--output-channel and --status-channel are both " + o.output_channel);
  if (o.source == "lcm" && o.input_channel == o.common.status_channel)
    throw FlagError("--input-channel and --status-channel are both " + o.input_channel +
                    " (the relay would read its own heartbeats)");
  check_positive("--max-speed", o.filter.max_speed);
  check_positive("--max-yaw-rate", o.filter.max_yaw_rate);
  if (o.source == "tum") {
    if (o.file.empty()) throw FlagError("--source tum needs --file FILE");
    // (a rate of 1e-12 stretched every gap beyond the longest wait and silently replayed as fast
    // as possible; restamped times keep the file's intervals, so only real time keeps them on the
    // wall clock that the detector's stamps follow: review, session 30)
    std::ostringstream rate;
    rate << o.rate;
    if (!(std::isfinite(o.rate) && (o.rate == 0 || (o.rate >= 0.01 && o.rate <= 1000))))
      throw FlagError("--rate: expected 0 (as fast as possible) or a number in [0.01, 1000], got " + rate.str());
    if (o.restamp && o.rate != 1)
      throw FlagError("--restamp with --source tum needs --rate 1 (real time): at --rate " + rate.str() +
                      " the restamped times would drift from the wall clock");
  }
  if (o.source == "udp") {
    if (o.port < 1 || o.port > 65535) throw FlagError("--source udp needs --port in 1-65535, got " + std::to_string(o.port));
    in_addr a{};
    if (inet_pton(AF_INET, o.bind.c_str(), &a) != 1)
      throw FlagError("--bind: expected an IPv4 address such as 127.0.0.1, got \"" + o.bind + "\"");
  }
}

// The relay: source samples → filter → fact::odometry_t, with counters and rate-limited logging.
class Relay {
 public:
  Relay(lcm::LCM& lcm, const Options& options)
      : lcm_(lcm),
        options_(options),
        log_(kApp, options.common.drone_id),
        status_(&lcm, options.common.status_channel, kApp, options.common.drone_id),
        filter_(options.filter) {
    status_.set_period_us(static_cast<int64_t>(std::llround(options.common.status_period * 1e6)));
    // Every counter from the start, so that a reader sees zeros rather than missing names.
    status_.count("published", 0);
    for (fact::Rejection r : {fact::Rejection::non_finite, fact::Rejection::out_of_order, fact::Rejection::jump,
                              fact::Rejection::bad_attitude, fact::Rejection::malformed, fact::Rejection::bad_time,
                              fact::Rejection::out_of_range})
      status_.count(fact::counter_name(r), 0);
    if (options.source == "lcm") {
      status_.count("undecodable", 0);
      status_.count("wrong_drone_id", 0);
    }
    status_.count("publish_failed", 0);
    status_.count("restarts", 0);
  }

  const fact::app::Log& log() const { return log_; }
  int lcm_fileno() { return lcm_.getFileno(); }

  // Handles the LCM messages that arrive within `ms` (the simulation clock's ticks with --sim-clock:
  // the tum and udp sources read no other LCM input, and without this the clock stood still;
  // review, session 33). Waits `ms` when LCM cannot be polled.
  void handle_lcm(int ms) {
    const auto end = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    for (int left = ms;; left = static_cast<int>(std::chrono::ceil<std::chrono::milliseconds>(
                               end - std::chrono::steady_clock::now()).count())) {
      const int r = lcm_.handleTimeout(std::max(0, left));
      if (r < 0) std::this_thread::sleep_until(end);
      if (r <= 0 || left <= 0) return;
    }
  }

  fact::app::Status& status() { return status_; }

  // lcm source.
  void on_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    fact::odometry_t m;
    const int64_t now = fact::app::now_us();
    const std::string error = fact::app::decode_error(rbuf->data, static_cast<int>(rbuf->data_size), &m);
    if (!error.empty()) {  // as fact::app::decode, but the log line rate-limited like every rejection
      status_.count("undecodable");
      limited("undecodable", now,
              "undecodable message on " + channel + " (" + std::to_string(rbuf->data_size) + " bytes, expected " +
                  fact::odometry_t::getTypeName() + "): " + error);
      return;
    }
    if (m.drone_id != options_.common.drone_id) {
      status_.count("wrong_drone_id");
      limited("wrong_drone_id", now, "dropped a message on " + channel + " from drone " + std::to_string(m.drone_id));
      return;
    }
    fact::OdometryInput in;
    in.utime = static_cast<double>(m.utime);
    in.position = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
    in.yaw = m.yaw;
    in.roll = m.roll;
    in.pitch = m.pitch;
    in.has_velocity = true;
    in.velocity = Eigen::Vector3d(m.velocity[0], m.velocity[1], m.velocity[2]);
    handle(filter_.push(in), now, "message seq " + std::to_string(m.seq));
  }

  // tum and udp sources: one pose line; `where` names it in log lines ("line 12", "datagram …").
  void on_line(const std::string& text, const std::string& where) {
    const int64_t now = fact::app::now_us();
    fact::PoseLine line;
    std::string error;
    switch (fact::parse_pose_line(text, &line, &error)) {
      case fact::PoseLineKind::empty: return;
      case fact::PoseLineKind::malformed: malformed(where, error); return;
      case fact::PoseLineKind::sample: break;
    }
    if (options_.restamp && std::isfinite(line.time) && std::abs(line.time) < 9e12) {
      // The offset puts the first sample's time at its arrival (whole µs: intervals kept exactly).
      // Restamped times then follow the wall clock; one off it by more than the filter's max_gap
      // (which would refuse it as a jump) means the VIO's own clock jumped (a reset): the offset is
      // taken again at this sample, so the stream goes on in wall-clock time instead of restarting
      // 20 samples later on the stale offset, far from the camera's frame times. (A smaller
      // threshold would re-base on a relay that stalls and then catches up.)
      // Also when the VIO's own time goes back by more than a reordered datagram can (1 s): a reset
      // smaller than max_gap would otherwise restart the stream on the old offset, seconds behind.
      // (A relay that stalls and catches up sees its lines' times keep increasing.)
      const int64_t line_us = std::llround(line.time * 1e6);
      const double offset = static_cast<double>(now - line_us);
      const bool went_back = has_offset_ && line_us < last_line_us_ - 1000000;
      if (!has_offset_ || line_us > last_line_us_ || went_back) last_line_us_ = line_us;
      if (!has_offset_) {
        offset_us_ = offset;
        has_offset_ = true;
      } else if (went_back || std::abs(offset - offset_us_) > options_.filter.max_gap * 1e6) {
        status_.count("restamp_rebased");
        log_.event(where + ": the VIO clock jumped by " + std::to_string((offset_us_ - offset) * 1e-6) +
                   " s against the wall clock: --restamp offset taken again at this sample");
        offset_us_ = offset;
      }
    }
    handle(filter_.push(line, offset_us_), now, where);
  }

  // Input that is not a pose line (a malformed line, an oversized datagram).
  void malformed(const std::string& where, const std::string& detail) {
    const std::string name = fact::counter_name(fact::Rejection::malformed);
    status_.count(name);
    limited(name, fact::app::now_us(), where + ": " + name + ": " + detail);
  }

  void every(int64_t now) { status_.tick(now); }

  void final_status(const std::string& state) {
    status_.set_state(state);
    status_.publish(fact::app::now_us());
  }

  std::string summary() const {
    std::ostringstream s;
    s << "published " << status_.value("published");
    for (const char* name : {"rejected_nan", "rejected_out_of_order", "rejected_jump", "rejected_attitude",
                             "rejected_malformed", "rejected_time", "rejected_range", "undecodable", "wrong_drone_id",
                             "restarts", "publish_failed"})
      if (status_.value(name) > 0) s << ", " << name << " " << status_.value(name);
    return s.str();
  }

 private:
  void handle(const fact::FilterResult& r, int64_t now, const std::string& where) {
    if (r.empty) return;
    if (!r.accepted()) {
      const std::string name = fact::counter_name(r.rejection);
      status_.count(name);
      limited(name, now, where + ": " + name + ": " + r.detail);
      return;
    }
    fact::odometry_t m;
    m.utime = r.output.utime;
    m.drone_id = options_.common.drone_id;
    m.seq = r.output.seq;
    for (int k = 0; k < 3; ++k) {
      m.position[k] = r.output.position[k];
      m.velocity[k] = r.output.velocity[k];
    }
    m.yaw = r.output.yaw;
    m.roll = r.output.roll;
    m.pitch = r.output.pitch;
    if (lcm_.publish(options_.output_channel, &m) != 0) {
      status_.count("publish_failed");
      limited("publish_failed", now, "publish on " + options_.output_channel + " failed");
      return;
    }
    status_.count("published");
    if (r.restarted) {
      status_.count("restarts");
      log_.event(where + ": " + r.detail + "; publishing from utime " + std::to_string(m.utime) + " us with seq 0");
    }
    if (r.output.seq == 0) {
      std::ostringstream s;
      s << "first sample published on " << options_.output_channel << ": utime " << m.utime << " us, position ("
        << m.position[0] << ", " << m.position[1] << ", " << m.position[2] << ") m, yaw " << m.yaw << " rad";
      log_.event(s.str());
      status_.set_state("relaying");
    }
  }

  // A log line for `key` at most once per second; the status message keeps the last one.
  void limited(const std::string& key, int64_t now, const std::string& line) {
    status_.note(line);
    int64_t held = 0;
    if (!limiter_.allow(key, now, &held)) return;
    log_.event(held > 0 ? line + " (" + std::to_string(held) + " more " + key + " since the last such line)" : line);
  }

  lcm::LCM& lcm_;
  const Options& options_;
  fact::app::Log log_;
  fact::app::Status status_;
  fact::OdometryFilter filter_;
  fact::LogLimiter limiter_{1000000};
  bool has_offset_ = false;  // --restamp: offset found (at the first sample with a usable time)
  int64_t last_line_us_ = 0; // --restamp: the newest line time seen (µs, the VIO's own clock)
  double offset_us_ = 0;     // µs added to every sample's time (0 without --restamp)
};

// Sleeps until `target` (steady clock, immune to wall-clock steps) or a stop, keeping the heartbeat
// going and the simulation clock's ticks handled (--sim-clock).
void wait_until(std::chrono::steady_clock::time_point target, Relay& relay) {
  while (!fact::app::stop_requested()) {
    const auto left = target - std::chrono::steady_clock::now();
    if (left <= std::chrono::steady_clock::duration::zero()) return;
    relay.every(fact::app::now_us());
    const auto ms = std::chrono::ceil<std::chrono::milliseconds>(left).count();
    relay.handle_lcm(static_cast<int>(std::min<int64_t>(ms, 100)));
  }
}

// 1 (after saying why) when a publish failed during the run, else `code`: the help promises exit 1
// when LCM fails while running (a relay that lost 19 of 30 samples exited 0; review, session 33).
int exit_code(Relay& relay, int code) {
  const int64_t failed = relay.status().value("publish_failed");
  if (failed == 0) return code;
  relay.log().event("error: " + std::to_string(failed) + " publish(es) failed");
  return 1;
}

int run_tum(std::ifstream& file, const Options& o, Relay& relay) {
  relay.status().set_state("replaying " + o.file);
  relay.status().publish(fact::app::now_us());
  auto base_clock = std::chrono::steady_clock::now();  // when the line at base_time is due
  bool has_first = false;
  double base_time = 0;      // s, the file time the schedule counts from
  double previous_time = 0;  // s, the previous sample line's time
  std::string text;
  int64_t line_no = 0;
  while (!fact::app::stop_requested() && std::getline(file, text)) {
    ++line_no;
    if (o.rate > 0) {
      fact::PoseLine line;
      std::string error;
      if (fact::parse_pose_line(text, &line, &error) == fact::PoseLineKind::sample && std::isfinite(line.time)) {
        if (!has_first) {
          has_first = true;
          base_time = previous_time = line.time;
        }
        // Time going back, or a gap beyond the filter's max_gap (a far-future typo, a pause, a
        // restarted clock), re-bases the schedule at this line instead of being waited for, and the
        // replay goes on paced from there (review, session 30: a typo had put the relay to sleep for
        // decades, and a first fix left every line after a real pause unpaced).
        const double gap = line.time - previous_time;
        if (gap < 0 || gap > o.filter.max_gap) {
          base_time = line.time;
          base_clock = std::chrono::steady_clock::now();
        }
        previous_time = line.time;
        wait_until(base_clock + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                    std::chrono::duration<double>((line.time - base_time) / o.rate)),
                   relay);
        if (fact::app::stop_requested()) break;
      }
    }
    relay.handle_lcm(0);  // (the clock's ticks when the replay is not paced)
    relay.on_line(text, o.file + " line " + std::to_string(line_no));
    relay.every(fact::app::now_us());
  }
  if (file.bad()) {
    relay.log().event("error: reading " + o.file + " failed after line " + std::to_string(line_no));
    relay.final_status("read failed");
    return 1;
  }
  const bool stopped = fact::app::stop_requested();
  relay.log().event(std::string(stopped ? "stopped" : "end of file") + " after " + std::to_string(line_no) +
                    " lines: " + relay.summary());
  relay.final_status(stopped ? "stopped" : "finished");
  return 0;
}

int run_udp(int sock, const Options& o, Relay& relay) {
  relay.status().set_state("listening on udp " + o.bind + ":" + std::to_string(o.port));
  relay.status().publish(fact::app::now_us());
  std::vector<char> buffer(65536);
  int64_t datagrams = 0;
  bool logged_sender = false;
  while (!fact::app::stop_requested()) {
    // The socket and LCM (the simulation clock's ticks with --sim-clock).
    pollfd p[2] = {{sock, POLLIN, 0}, {relay.lcm_fileno(), POLLIN, 0}};
    const int ready = poll(p, p[1].fd >= 0 ? 2 : 1, 100);
    if (ready < 0) {
      if (errno == EINTR) continue;
      relay.log().event(std::string("error: poll on the udp socket failed: ") + std::strerror(errno));
      relay.final_status("socket failed");
      return 1;
    }
    if (p[1].fd >= 0 && (p[1].revents & POLLIN)) relay.handle_lcm(0);
    if (p[0].revents & POLLIN) {
      sockaddr_in from{};
      socklen_t from_len = sizeof from;
      const ssize_t n = recvfrom(sock, buffer.data(), buffer.size(), MSG_TRUNC, reinterpret_cast<sockaddr*>(&from), &from_len);
      if (n < 0) {
        if (errno == EINTR || errno == EAGAIN) continue;
        relay.log().event(std::string("error: recvfrom failed: ") + std::strerror(errno));
        relay.final_status("socket failed");
        return 1;
      }
      ++datagrams;
      char addr[INET_ADDRSTRLEN] = "?";
      inet_ntop(AF_INET, &from.sin_addr, addr, sizeof addr);
      const std::string sender = std::string(addr) + ":" + std::to_string(ntohs(from.sin_port));
      if (!logged_sender) {
        relay.log().event("first datagram from " + sender);
        logged_sender = true;
      }
      const std::string where = "datagram " + std::to_string(datagrams) + " from " + sender;
      if (static_cast<size_t>(n) > buffer.size())  // truncated: never a pose line
        relay.malformed(where, "datagram of " + std::to_string(n) + " bytes is too long for a pose line");
      else
        relay.on_line(std::string(buffer.data(), static_cast<size_t>(n)), where);
    }
    relay.every(fact::app::now_us());
  }
  relay.log().event("stopped after " + std::to_string(datagrams) + " datagrams: " + relay.summary());
  relay.final_status("stopped");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  CLI::App app{"Relays one drone's VIO odometry from the simulator (LCM), a TUM trajectory file or a UDP\n"
               "line stream as one normalised fact::odometry_t stream on FACT_ODOMETRY_<id> (LCM).",
               kApp};
  add_flags(app, options);
  app.get_formatter()->column_width(34);
  if (const int code = fact::app::parse_flags(app, argc, argv, kApp, [&] { check(app, options); }); code >= 0) return code;

  const fact::app::Log log(kApp, options.common.drone_id);
  // The source first: a file that cannot be read is bad input (2), before any LCM traffic.
  std::ifstream file;
  if (options.source == "tum") {
    std::error_code ec;
    if (std::filesystem::is_directory(options.file, ec)) {
      std::cerr << kApp << ": error: --file " << options.file << ": is a directory\n";
      return 2;
    }
    file.open(options.file);
    if (!file) {
      std::cerr << kApp << ": error: --file " << options.file << ": cannot open: " << std::strerror(errno) << "\n";
      return 2;
    }
  }
  int sock = -1;
  if (options.source == "udp") {
    sock = socket(AF_INET, SOCK_DGRAM | SOCK_CLOEXEC, 0);
    sockaddr_in addr{};
    addr.sin_family = AF_INET;
    addr.sin_port = htons(static_cast<uint16_t>(options.port));
    inet_pton(AF_INET, options.bind.c_str(), &addr.sin_addr);
    if (sock < 0 || bind(sock, reinterpret_cast<sockaddr*>(&addr), sizeof addr) != 0) {
      log.event("error: cannot listen on udp " + options.bind + ":" + std::to_string(options.port) + ": " +
                std::strerror(errno));
      if (sock >= 0) close(sock);
      return 1;
    }
  }

  lcm::LCM lcm(options.common.lcm_url);
  if (!fact::app::lcm_opened(lcm, options.common.lcm_url, log)) {
    if (sock >= 0) close(sock);
    return 1;
  }
  fact::app::install_stop_handler();
  if (!fact::app::start_clock(lcm, options.common, log)) {
    if (sock >= 0) close(sock);
    return 1;
  }
  Relay relay(lcm, options);
  std::ostringstream start;
  start << "source " << options.source;
  if (options.source == "lcm") start << " " << options.input_channel;
  if (options.source == "tum") start << " " << options.file << " at rate " << options.rate;
  if (options.source == "udp") start << " " << options.bind << ":" << options.port;
  start << ", publishing on " << options.output_channel << " (max speed " << options.filter.max_speed
        << " m/s, max yaw rate " << options.filter.max_yaw_rate << " rad/s" << (options.restamp ? ", restamped" : "")
        << ")";
  log.event(start.str());

  int code = 0;
  if (options.source == "lcm") {
    // Room for bursts: LCM drops (silently, uncounted) what exceeds a subscription's queue.
    lcm.subscribe(options.input_channel, &Relay::on_raw, &relay)->setQueueCapacity(kInputQueue);
    relay.status().set_state("listening on " + options.input_channel);
    relay.status().publish(fact::app::now_us());
    code = fact::app::run_loop(lcm, 100, [&](int64_t now) { relay.every(now); });
    log.event(std::string(code == 0 ? "stopped: " : "stopped (LCM failed): ") + relay.summary());
    relay.final_status(code == 0 ? "stopped" : "LCM failed");
  } else if (options.source == "tum") {
    code = run_tum(file, options, relay);
  } else {
    code = run_udp(sock, options, relay);
    close(sock);
  }
  return exit_code(relay, code);
}
