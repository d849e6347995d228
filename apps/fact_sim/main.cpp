// fact-sim: the simulated swarm. One process plays N drones in a room with obstacles
// (lib/sim: world, dynamics + simulated flight controller, VIO drift, CPU renderer) and publishes,
// on a simulation clock:
//   FACT_FRAMES_<id>     fact::frame_t      gray + depth (mm) of each drone's camera, --camera-rate
//   FACT_VIO_RAW_<id>    fact::odometry_t   raw VIO in f_i with IMU roll/pitch, --odometry-rate
//   FACT_TRUTH           fact::truth_t      ground truth (evaluation only), --truth-rate
//   FACT_SIM_CLOCK       fact::sim_clock_t  simulation time, every physics batch (10 ms)
//   FACT_STATUS          fact::app_status_t heartbeat and counters
// and follows fact::setpoint_t on FACT_SETPOINT_<id> (or a --script). Every message carries the
// simulation time in utime; it starts at --epoch-utime, so runs are reproducible.
// With --mavlink-port BASE each drone instead has a simulated PX4 (sim_fc.h) on UDP
// --mavlink-bind:(BASE + drone id), driven by fact-fc-bridge over MAVLink v2; LCM setpoints are
// then not read. --frames-url and --drone-url give each drone its own LCM for its frames and for
// its VIO, clock, setpoints and (--lockstep) detections, as on a real drone, whose apps share
// nothing with the others' but the gossip.
//
// Exit codes: 0 at --duration or on SIGINT/SIGTERM; 1 LCM or socket failure; 2 bad flags or world file.
#include "common/cli_checks.h"
#include "common/app.h"
#include "fact/frame_t.hpp"
#include "fact/odometry_t.hpp"
#include "fact/setpoint_t.hpp"
#include "fact/sim_clock_t.hpp"
#include "fact/sim_dynamics.h"
#include "fact/sim_render.h"
#include "fact/truth_t.hpp"
#include "fact/world_io.h"
#include "sim_fc.h"

#include <CLI/CLI.hpp>
#include <arpa/inet.h>
#include <lcm/lcm-cpp.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <map>
#include <memory>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string>
#include <thread>
#include <vector>

namespace {

constexpr const char* kApp = "fact-sim";
constexpr int64_t kPhysicsStepUs = 2000;   // physics step (µs of sim time)
constexpr int64_t kBatchUs = 10000;        // clock tick, message handling and pacing every 10 ms
constexpr double kProgressEveryS = 5.0;    // progress log period (sim s)

struct Options {
  std::string world_file;           // "" = the built-in default world
  int drones = 0;                   // 0 = the world's count
  uint64_t seed = 1;
  double rate = 1.0;                // real-time factor; 0 = as fast as possible
  double duration = 0;              // sim s; 0 = forever
  double camera_rate = 15;          // Hz
  double odometry_rate = 100;       // Hz
  double truth_rate = 10;           // Hz
  std::string resolution = "424x240";
  std::string script = "none";
  double spin_rate = 0.8;           // rad/s
  int64_t epoch_utime = 1700000000000000;
  std::string lcm_url;
  std::string frames_channel = "FACT_FRAMES";
  std::string vio_channel = "FACT_VIO_RAW";
  std::string setpoint_channel = "FACT_SETPOINT";
  std::string truth_channel = "FACT_TRUTH";
  std::string clock_channel = "FACT_SIM_CLOCK";
  std::string status_channel = "FACT_STATUS";
  bool no_depth_noise = false;
  int mavlink_port = 0;             // 0 = off; else drone id k's FC is on UDP mavlink_bind:(mavlink_port + k)
  std::string mavlink_bind = "127.0.0.1";
  bool fc_auto_arm = false;
  std::string frames_url;           // "" = frames on lcm_url; else a URL template, "{id}" = the drone id
  std::string drone_url;            // "" = each drone's VIO, clock, setpoints, detections on lcm_url; else a template
  bool lockstep = false;            // wait for every detector's answer to a frame before the next frame
  double lockstep_timeout = 2.0;    // s of wall time a frame waits for a detector before going on without it
  std::string detections_channel = "FACT_DETECTIONS";
  bool print_ids = false;           // print the drones' ids (world + --drones) and exit
  int render_threads = 2;           // threads rendering the drones' cameras
};

struct FlagError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

void add_flags(CLI::App& app, Options& o) {
  app.add_option("--world", o.world_file, "fact-world-v1 JSON world file (default: the built-in default world)")
      ->type_name("FILE");
  app.add_option("--drones", o.drones, "Number of drones (overrides the world's count; 1-64)")->type_name("N")
      ->check(fact::app::decimal_integer());
  app.add_option("--seed", o.seed, "Seed of every random choice (starts, heights, drift, noise)")
      ->check(fact::app::uint64_text())  // (CLI11 would wrap -1 to 2^64 - 1 and read 010 as octal)
      ->capture_default_str();
  app.add_option("--rate", o.rate, "Real-time factor (1 = real time, 0 = as fast as possible)")->capture_default_str();
  app.add_option("--duration", o.duration, "Simulated seconds to run (0 = until SIGINT/SIGTERM)")
      ->type_name("S")->capture_default_str();
  app.add_option("--camera-rate", o.camera_rate, "Frames per second per drone (Hz)")->capture_default_str();
  app.add_option("--odometry-rate", o.odometry_rate, "VIO odometry rate per drone (Hz)")->capture_default_str();
  app.add_option("--truth-rate", o.truth_rate, "Ground-truth rate (Hz)")->capture_default_str();
  app.add_option("--resolution", o.resolution, "Camera resolution: 424x240 or 640x480")->capture_default_str();
  app.add_option("--script", o.script, "Scripted motion: none, hover or spin")->capture_default_str();
  app.add_option("--spin-rate", o.spin_rate, "Yaw rate of --script spin (rad/s, at most 1.5)")->capture_default_str();
  app.add_option("--epoch-utime", o.epoch_utime, "Simulation time at start (us)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--lcm-url", o.lcm_url, "LCM URL (default: LCM's default)")->type_name("URL");
  app.add_option("--frames-channel", o.frames_channel, "Frame channel base (+ _<id>)")->capture_default_str();
  app.add_option("--vio-channel", o.vio_channel, "Raw VIO odometry channel base (+ _<id>)")->capture_default_str();
  app.add_option("--setpoint-channel", o.setpoint_channel, "Setpoint channel base (+ _<id>)")->capture_default_str();
  app.add_option("--truth-channel", o.truth_channel, "Ground-truth channel")->capture_default_str();
  app.add_option("--clock-channel", o.clock_channel, "Simulation clock channel")->capture_default_str();
  app.add_option("--status-channel", o.status_channel, "Status heartbeat channel")->capture_default_str();
  app.add_flag("--no-depth-noise", o.no_depth_noise, "Publish noise-free (quantised) depth");
  app.add_option("--mavlink-port", o.mavlink_port,
                 "Simulated PX4 per drone over MAVLink v2 on UDP <mavlink-bind>:(BASE + drone id); 0 = off "
                 "(setpoints on LCM)")
      ->type_name("BASE")->capture_default_str()->check(fact::app::decimal_integer());
  app.add_option("--mavlink-bind", o.mavlink_bind, "IPv4 address the simulated flight controllers bind")
      ->type_name("ADDR")->capture_default_str();
  app.add_flag("--fc-auto-arm", o.fc_auto_arm, "Start the simulated flight controllers armed in OFFBOARD mode");
  app.add_option("--frames-url", o.frames_url,
                 "LCM URL template for each drone's frames, \"{id}\" replaced by the drone id and \"{B+id}\" by "
                 "B + id (e.g. udpm://239.255.77.{id}:{7700+id}?ttl=1): a camera group and port per drone that "
                 "only its detector and planner join. Default: frames go on --lcm-url")
      ->type_name("URL");
  app.add_option("--drone-url", o.drone_url,
                 "LCM URL template for each drone's own bus (as --frames-url: \"{id}\", \"{B+id}\"), e.g. "
                 "udpm://239.255.78.{id}:{7800+id}?ttl=1: its raw VIO and the clock go there, and its setpoints and "
                 "(--lockstep) detections are read there, so its apps need not share a bus with the other drones'. "
                 "Truth and status stay on --lcm-url, which also gets the clock. Default: everything on --lcm-url")
      ->type_name("URL");
  app.add_flag("--lockstep", o.lockstep,
               "Before each frame, wait until every drone's detector has answered the previous one "
               "(fact::detections_t with that frame's utime on <detections-channel>_<id>), so a fast run "
               "never outruns the detectors");
  app.add_option("--lockstep-timeout", o.lockstep_timeout,
                 "s of wall time a frame waits for a detector; after that the drone is not waited for "
                 "until its detector catches up")
      ->capture_default_str();
  app.add_option("--render-threads", o.render_threads, "Threads rendering the cameras (1-64; frames do not depend on it)")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_flag("--print-ids", o.print_ids, "Print the drones' ids (from the world and --drones), space separated, and exit");
  app.add_option("--detections-channel", o.detections_channel, "Detections channel base (+ _<id>), for --lockstep")
      ->capture_default_str();
  app.footer(
      "Without --world the built-in default world is used (room 10x10x4 m, a box, a cylinder and a\n"
      "polytope, drones at random starts). Drones hold their start pose until their first setpoint\n"
      "(fact::setpoint_t in f_i on <setpoint-channel>_<id>) or a --script: hover takes off to a seeded\n"
      "height in the world's drones.height range; spin then yaws at --spin-rate. NaN setpoints and\n"
      "setpoints for another drone are counted, logged and ignored.\n"
      "--mavlink-port: each drone gets a simulated PX4 (sysid 1, compid 1) on UDP ADDR:(BASE + id) that\n"
      "answers the first peer that writes to it (fact-fc-bridge --udp L:ADDR:BASE+id). It takes\n"
      "SET_POSITION_TARGET_LOCAL_NED (LOCAL_NED), arm / DO_SET_MODE commands and ODOMETRY, sends\n"
      "HEARTBEAT (1 Hz), LOCAL_POSITION_NED and ATTITUDE (30 Hz) in the NED of f_i; setpoints drive the\n"
      "drone only when armed in OFFBOARD; > 0.5 s without one there: hold position (failsafe).\n"
      "Exit codes: 0 at --duration or SIGINT/SIGTERM; 1 LCM or socket failure; 2 bad flags or world file.");
}

// v in [least, most], or 0 where zero_ok (0 = off / unlimited), naming the flag and the value.
void check_rate(const char* flag, double v, bool zero_ok, double least, double most) {
  if ((v >= least && v <= most) || (zero_ok && v == 0)) return;  // (false for NaN)
  std::ostringstream s;
  s << flag << ": expected " << (zero_ok ? "0 or " : "") << "a number in [" << least << ", " << most << "], got " << v;
  throw FlagError(s.str());
}

fact::CameraIntrinsics parse_resolution(const std::string& r) {
  if (r == "424x240") return fact::d430_424x240();
  if (r == "640x480") return fact::d430_640x480();
  throw FlagError("--resolution: expected 424x240 or 640x480, got \"" + r + "\"");
}

void check(const Options& o) {
  // Outputs go out at most once per 10 ms batch: a stream above 100 Hz was cut to 100 Hz, and
  // 1e11 Hz spun in its scheduling loop deaf to SIGTERM. Durations and the epoch stay far from
  // int64 µs overflow (1e7 s is 116 days).
  // The lower bounds keep every sample time and pacing target (1e6/rate µs steps, t/rate) far
  // inside int64: a stream at 1e-14 Hz put its second sample past 2^63 µs and its scheduling
  // loop never ended (review, session 33).
  const double per_batch = 1e6 / static_cast<double>(kBatchUs);
  check_rate("--rate", o.rate, true, 1e-3, 1e4);
  check_rate("--duration", o.duration, true, 1e-3, 1e7);
  check_rate("--camera-rate", o.camera_rate, false, 1e-3, per_batch);
  check_rate("--odometry-rate", o.odometry_rate, false, 1e-3, per_batch);
  check_rate("--truth-rate", o.truth_rate, false, 1e-3, per_batch);
  check_rate("--spin-rate", o.spin_rate, false, 1e-3, 1.5);
  check_rate("--lockstep-timeout", o.lockstep_timeout, false, 1e-3, 3600);
  if (o.epoch_utime < 0 || o.epoch_utime > 4000000000000000)
    throw FlagError("--epoch-utime: expected 0 … 4e15 us (before 2096), got " + std::to_string(o.epoch_utime));
  if (o.render_threads < 1 || o.render_threads > 64)
    throw FlagError("--render-threads: expected 1-64, got " + std::to_string(o.render_threads));
  if (o.drones < 0 || o.drones > 64) throw FlagError("--drones: expected 1 ... 64, got " + std::to_string(o.drones));
  fact::sim::Script s;
  if (!fact::sim::parse_script(o.script, &s)) throw FlagError("--script: expected none, hover or spin, got \"" + o.script + "\"");
  parse_resolution(o.resolution);
  if (o.mavlink_port < 0 || o.mavlink_port > 65535)
    throw FlagError("--mavlink-port: expected 0 (off) or a port 1..65535, got " + std::to_string(o.mavlink_port));
  if (o.mavlink_port > 0) {
    in_addr a{};
    if (::inet_pton(AF_INET, o.mavlink_bind.c_str(), &a) != 1)
      throw FlagError("--mavlink-bind: expected an IPv4 address, got \"" + o.mavlink_bind + "\"");
    if (s != fact::sim::Script::none)
      throw FlagError("--script " + o.script + " and --mavlink-port exclude each other (the flight controllers take setpoints over MAVLink)");
  } else if (o.fc_auto_arm) {
    throw FlagError("--fc-auto-arm needs --mavlink-port");
  }
  // (an empty channel flag is refused while parsing: refuse_empty_values)
}

// The world with its starts placed; throws fact::FormatError (bad file) or FlagError.
fact::sim::World load_world(const Options& o) {
  using fact::sim::World;
  World w = o.world_file.empty() ? fact::sim::default_world(o.drones > 0 ? o.drones : 4, o.seed)
                                 : fact::read_world_file(o.world_file);
  fact::sim::DroneConfig& c = w.drone_config;
  if (o.drones > 0 && o.drones != c.count) {
    if (!c.random_start) {
      if (o.drones > static_cast<int>(w.starts.size()))
        throw FlagError("--drones: " + std::to_string(o.drones) + " but the world file lists only " +
                        std::to_string(w.starts.size()) + " starts");
      w.starts.resize(static_cast<size_t>(o.drones));
      if (!c.ids.empty()) c.ids.resize(static_cast<size_t>(o.drones));
    } else if (static_cast<int>(c.ids.size()) > o.drones) {
      c.ids.resize(static_cast<size_t>(o.drones));
    } else if (!c.ids.empty()) {  // (they were dropped for 0 … N−1, so FACT_*_<id> channels went unused)
      throw FlagError("--drones: " + std::to_string(o.drones) + " but the world file lists only " +
                      std::to_string(c.ids.size()) + " ids");
    }
    c.count = o.drones;
  }
  if (c.random_start) {
    std::string err = fact::sim::place_random_starts(&w, c.seed_given ? c.seed : o.seed);
    if (!err.empty()) throw FlagError("drone placement: " + err);
  }
  std::string err = fact::sim::starts_error(w);
  if (!err.empty()) throw FlagError("drone starts: " + err);
  if (o.mavlink_port > 0)
    for (const auto& s : w.starts)
      if (s.id < 0 || o.mavlink_port + s.id > 65535)
        throw FlagError("--mavlink-port " + std::to_string(o.mavlink_port) + ": drone " + std::to_string(s.id) +
                        " would need UDP port " + std::to_string(o.mavlink_port + s.id) + " (> 65535)");
  return w;
}

// One mt19937_64 per purpose, all derived from --seed.
std::mt19937_64 make_rng(uint64_t seed, uint64_t purpose) {
  std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), static_cast<uint32_t>(purpose)};
  return std::mt19937_64(seq);
}

std::string fmt(const char* f, double a, double b = 0, double c = 0, double d = 0) {
  char buf[256];
  std::snprintf(buf, sizeof buf, f, a, b, c, d);
  return buf;
}

// A drone as the app runs it: its simulated state, script and message counters.
struct Drone {
  fact::sim::SimDrone sim;
  fact::sim::ScriptState script;
  bool external = false;        // a setpoint arrived on LCM: the script no longer drives it
  bool takeoff_logged = false;
  int64_t frame_seq = 0, odom_seq = 0;
  std::unique_ptr<fact::sim_fc::SimFc> fc;      // with --mavlink-port: its simulated PX4
  std::unique_ptr<fact::sim_fc::FcPort> fc_port;
  lcm::LCM* frames_lcm = nullptr;   // where its frames go (--frames-url), else the main LCM
  lcm::LCM* bus = nullptr;          // its own bus (--drone-url): VIO and clock out, setpoints and detections in
  std::unique_ptr<fact::sim::Renderer> renderer;  // its camera, with its own noise stream
  fact::sim::RenderedFrame frame;   // its newest rendered frame
  int64_t answered_utime = -1;      // --lockstep: newest frame utime its detector answered
  bool waited_out = false;          // --lockstep: timed out; not waited for until it catches up
};

class Simulator {
 public:
  Simulator(const Options& o, fact::sim::World world, lcm::LCM* lcm, fact::app::Status* status,
            const fact::app::Log* log)
      : o_(o), world_(std::move(world)), lcm_(lcm), status_(status), log_(log),
        intrinsics_(parse_resolution(o.resolution)),
        drift_rng_(make_rng(o.seed, 1)) {
    fact::sim::parse_script(o.script, &script_);
    std::mt19937_64 height_rng = make_rng(o.seed, 3);
    const auto& c = world_.drone_config;
    std::uniform_real_distribution<double> height(c.height_min, c.height_max);
    std::mt19937_64 noise_seeds = make_rng(o.seed, 2);  // one depth-noise stream per drone's camera
    for (const auto& s : world_.starts) {
      Drone d;
      d.sim = fact::sim::make_drone(s);
      d.renderer = std::make_unique<fact::sim::Renderer>(world_, intrinsics_, fact::CameraExtrinsics(),
                                                         render_options(o), noise_seeds());
      d.script.height = height(height_rng);
      if (script_ != fact::sim::Script::none) {
        d.sim.landed = false;
        d.sim.have_setpoint = true;
      }
      drones_.push_back(std::move(d));
    }
  }

  // With --mavlink-port: a simulated flight controller per drone on UDP bind:(BASE + id).
  // Throws fact::sim_fc::SocketError when a socket cannot be bound.
  void open_flight_controllers() {
    fact::sim_fc::FcOptions fo;
    fo.auto_arm = o_.fc_auto_arm;
    for (const char* c : {"fc_setpoints", "fc_rejected_nan", "fc_rejected_frame", "fc_rejected_type_mask",
                          "fc_rejected_range", "fc_not_for_us", "fc_commands", "fc_command_denied", "fc_odometry",
                          "fc_peer_heartbeats", "fc_failsafe", "fc_heartbeats_sent", "fc_telemetry_sent",
                          "fc_mavlink_bad_crc", "fc_mavlink_bad_length", "fc_mavlink_unknown_id",
                          "fc_mavlink_signed_frame", "fc_mavlink_unknown_flags", "fc_mavlink_truncated", "fc_foreign_peer", "fc_send_failed"})
      status_->count(c, 0);
    std::string ports;
    for (Drone& d : drones_) {
      d.fc = std::make_unique<fact::sim_fc::SimFc>(d.sim.id, fo, status_, log_);
      d.fc_port = std::make_unique<fact::sim_fc::FcPort>(o_.mavlink_bind, o_.mavlink_port + d.sim.id);
      ports += " " + std::to_string(d.sim.id) + "@" + d.fc_port->describe();
    }
    log_->event("simulated flight controllers (MAVLink v2, sysid 1 compid 1, " +
                std::string(o_.fc_auto_arm ? "armed in OFFBOARD" : "disarmed in POSCTL") + " at start):" + ports);
  }

  // Opens each drone's frames LCM (--frames-url, "{id}" replaced by its id; drones sharing a URL
  // share an instance). "" when fine, else the URL that failed.
  std::string open_frame_urls() {
    for (Drone& d : drones_) {
      d.frames_lcm = lcm_;
      if (o_.frames_url.empty()) continue;
      const std::string url = frames_url_for(o_.frames_url, d.sim.id);
      auto& slot = frame_lcms_[url];
      if (!slot) slot = std::make_unique<lcm::LCM>(url);
      if (!slot->good()) return url;
      d.frames_lcm = slot.get();
    }
    return "";
  }

  // Opens each drone's own bus (--drone-url, as open_frame_urls); without it every drone's bus
  // is the main LCM. Call before subscribe() and subscribe_detections(). "" when fine, else the
  // URL that failed.
  std::string open_drone_urls() {
    buses_ = {lcm_};
    for (Drone& d : drones_) {
      d.bus = lcm_;
      if (o_.drone_url.empty()) continue;
      const std::string url = frames_url_for(o_.drone_url, d.sim.id);
      if (url == o_.lcm_url) continue;  // the main LCM itself
      auto& slot = bus_lcms_[url];
      if (!slot) {
        slot = std::make_unique<lcm::LCM>(url);
        if (!slot->good()) return url;
        buses_.push_back(slot.get());
      }
      d.bus = slot.get();
    }
    return "";
  }

  // handleTimeout over the main LCM and every drone bus (fact::app::handle_any): > 0 when
  // something was handled, 0 on timeout, < 0 when polling or LCM failed.
  int handle_timeout(int timeout_ms) { return fact::app::handle_any(buses_, int64_t{timeout_ms} * 1000); }

  // The template with "{id}" replaced by the id and "{B+id}" (B an integer) by B + id, so each drone
  // can have its own group and port: Linux hands a udpm socket bound to a port the datagrams of
  // every group joined on that port in its network namespace, so a group alone does not separate
  // drones that share a namespace.
  static std::string frames_url_for(std::string url, int id) {
    for (size_t at = url.find('{'); at != std::string::npos; at = url.find('{', at)) {
      const size_t end = url.find('}', at);
      if (end == std::string::npos) break;
      const std::string key = url.substr(at + 1, end - at - 1);
      std::string value;
      if (key == "id") {
        value = std::to_string(id);
      } else if (key.size() > 3 && key.size() <= 9 && key.compare(key.size() - 3, 3, "+id") == 0 &&
                 key.find_first_not_of("0123456789") == key.size() - 3) {  // B of at most 6 digits
        value = std::to_string(std::stol(key.substr(0, key.size() - 3)) + id);
      } else {
        ++at;
        continue;
      }
      url.replace(at, end - at + 1, value);
      at += value.size();
    }
    return url;
  }

  // --lockstep: every drone's detections tell which frame its detector has answered.
  void subscribe_detections() {
    for (size_t i = 0; i < drones_.size(); ++i) {
      const std::string ch = fact::app::channel(o_.detections_channel, drones_[i].sim.id);
      drones_[i].bus->subscribe(ch, &Simulator::on_detections_raw, this)->setQueueCapacity(100);
      detections_index_.push_back(ch);
    }
  }

  void on_detections_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    fact::detections_t m;
    if (!fact::app::decode(rbuf, channel, &m, status_, *log_)) return;
    auto it = std::find(detections_index_.begin(), detections_index_.end(), channel);
    if (it == detections_index_.end()) return;
    Drone& d = drones_[static_cast<size_t>(it - detections_index_.begin())];
    d.answered_utime = std::max(d.answered_utime, m.utime);
  }

  static fact::sim::RenderOptions render_options(const Options& o) {
    fact::sim::RenderOptions r;
    r.depth_noise = !o.no_depth_noise;
    return r;
  }

  // Subscribes to every drone's setpoint channel.
  void subscribe() {
    for (size_t i = 0; i < drones_.size(); ++i) {
      const std::string ch = fact::app::channel(o_.setpoint_channel, drones_[i].sim.id);
      drones_[i].bus->subscribe(ch, &Simulator::on_setpoint_raw, this)->setQueueCapacity(1000);
      channel_index_.push_back(ch);
    }
  }

  void on_setpoint_raw(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    fact::setpoint_t m;
    if (!fact::app::decode(rbuf, channel, &m, status_, *log_)) return;
    auto it = std::find(channel_index_.begin(), channel_index_.end(), channel);
    if (it == channel_index_.end()) return;
    Drone& d = drones_[static_cast<size_t>(it - channel_index_.begin())];
    if (m.drone_id != d.sim.id) {
      reject("wrong_drone_id", "setpoint on " + channel + " for drone_id " + std::to_string(m.drone_id) +
                                   " (expected " + std::to_string(d.sim.id) + "), ignored");
      return;
    }
    fact::sim::Setpoint sp;
    sp.position = Eigen::Vector3d(m.position[0], m.position[1], m.position[2]);
    sp.velocity = Eigen::Vector3d(m.velocity[0], m.velocity[1], m.velocity[2]);
    sp.acceleration = Eigen::Vector3d(m.acceleration[0], m.acceleration[1], m.acceleration[2]);
    sp.yaw = m.yaw;
    sp.yaw_rate = m.yaw_rate;
    const std::string err = fact::sim::setpoint_error(sp);
    if (!err.empty()) {
      reject("rejected_nan", "setpoint on " + channel + ": " + err + ", ignored");
      return;
    }
    if (const std::string range = fact::sim::setpoint_range_error(sp); !range.empty()) {
      reject("rejected_range", "setpoint on " + channel + ": " + range + ", ignored");
      return;
    }
    status_->count("setpoints");
    if (!d.external) log_->event("first setpoint for drone " + std::to_string(d.sim.id) + " on " + channel);
    d.external = true;
    d.sim.setpoint = sp;
    d.sim.have_setpoint = true;
    d.sim.landed = false;
  }

  // Runs until --duration or a stop request. Returns the exit code.
  int run() {
    auto wall0 = std::chrono::steady_clock::now();
    int64_t t = 0;  // sim time since the epoch (µs)
    const int64_t end = o_.duration > 0 ? static_cast<int64_t>(std::llround(o_.duration * 1e6)) : -1;
    int64_t n_cam = 0, n_odom = 0, n_truth = 0;
    double next_progress = kProgressEveryS;
    status_->set_state("running");
    if (!publish_outputs(t, &n_cam, &n_odom, &n_truth)) return 1;
    while (!fact::app::stop_requested() && (end < 0 || t < end)) {
      if (!service_flight_controllers(t)) return 1;
      for (int64_t s = 0; s < kBatchUs; s += kPhysicsStepUs) {
        step(t);
        t += kPhysicsStepUs;
      }
      if (!publish_outputs(t, &n_cam, &n_odom, &n_truth)) return 1;
      send_telemetry(t);
      if (t * 1e-6 >= next_progress) {
        progress(t);
        next_progress += kProgressEveryS;
      }
      if (!handle_messages(&wall0, t)) return 1;
    }
    progress(t);
    status_->set_state("stopped");
    status_->publish(o_.epoch_utime + t);
    log_->event(fact::app::stop_requested() ? "stopped by signal" : "duration reached, exiting");
    return 0;
  }

 private:
  void reject(const std::string& counter, const std::string& line) {
    fact::app::count_and_log(*status_, *log_, counter, line);
  }

  // Reads every pending MAVLink datagram of every flight controller (non-blocking), at sim time t.
  // False when a socket failed.
  bool service_flight_controllers(int64_t t) {
    for (Drone& d : drones_) {
      if (!d.fc_port) continue;
      std::string error;
      const bool ok = d.fc_port->drain(
          [&](const uint8_t* data, std::size_t n) { d.fc->on_bytes(data, n, d.sim, t); }, status_, *log_, d.sim.id, &error);
      if (!ok) {
        log_->event("error: " + error);
        return false;
      }
    }
    return true;
  }

  // The flight controllers' HEARTBEAT / LOCAL_POSITION_NED / ATTITUDE due at sim time t, to
  // their peers (nothing before a peer has written).
  void send_telemetry(int64_t t) {
    for (Drone& d : drones_) {
      if (!d.fc_port || !d.fc_port->has_peer()) continue;
      d.fc->telemetry(d.sim, t, [&](const std::vector<uint8_t>& b) { d.fc_port->send(b, status_, *log_); });
    }
  }

  void step(int64_t t) {
    const double ts = t * 1e-6;
    for (Drone& d : drones_) {
      if (d.fc) d.fc->control(&d.sim, t);
      if (!d.external && script_ != fact::sim::Script::none) {
        d.sim.setpoint = fact::sim::script_setpoint(script_, &d.script, fact::sim::vio_sample(d.sim), ts, o_.spin_rate);
        if (d.script.airborne && !d.takeoff_logged) {
          d.takeoff_logged = true;
          log_->event("drone " + std::to_string(d.sim.id) + fmt(" takeoff done at %.2f m after %.2f s", d.script.height, ts));
        }
      }
      fact::sim::step_drone(&d.sim, world_, gains_, limits_, kPhysicsStepUs * 1e-6, &drift_rng_);
    }
  }

  // Publishes whatever is due at sim time t: clock always, odometry, frames, truth, status.
  // False if LCM failed (while waiting for the detectors).
  bool publish_outputs(int64_t t, int64_t* n_cam, int64_t* n_odom, int64_t* n_truth) {
    const int64_t utime = o_.epoch_utime + t;
    fact::sim_clock_t clock;
    clock.utime = utime;
    clock.rate = o_.rate;
    for (lcm::LCM* b : buses_) b->publish(o_.clock_channel, &clock);
    if (due(t, o_.odometry_rate, n_odom)) publish_odometry(utime);
    if (due(t, o_.camera_rate, n_cam) && !publish_frames(utime)) return false;
    if (due(t, o_.truth_rate, n_truth)) publish_truth(utime);
    status_->tick(utime);
    return true;
  }

  // Whether the k-th sample of a `rate` Hz stream (at round(k·1e6/rate) µs) is due at t. A sample
  // time beyond int64 µs is never due (check() keeps rates far from that).
  static bool due(int64_t t, double rate, int64_t* k) {
    const auto at = [&] { return static_cast<double>(*k) * 1e6 / rate; };
    if (!(at() < 9e18) || t < std::llround(at())) return false;
    while (at() < 9e18 && std::llround(at()) <= t) ++*k;
    return true;
  }

  std::vector<fact::sim::DronePose> poses() const {
    std::vector<fact::sim::DronePose> out;
    for (const Drone& d : drones_) {
      fact::sim::DronePose p;
      p.position = d.sim.p;
      p.yaw = d.sim.yaw;
      p.pitch = d.sim.pitch;
      p.roll = d.sim.roll;
      out.push_back(p);
    }
    return out;
  }

  void publish_odometry(int64_t utime) {
    for (Drone& d : drones_) {
      const fact::sim::VioSample v = fact::sim::vio_sample(d.sim);
      fact::odometry_t m;
      m.utime = utime;
      m.drone_id = d.sim.id;
      m.seq = d.odom_seq++;
      for (int k = 0; k < 3; ++k) {
        m.position[k] = v.position[k];
        m.velocity[k] = v.velocity[k];
      }
      m.yaw = v.yaw;
      m.roll = v.roll;
      m.pitch = v.pitch;
      d.bus->publish(fact::app::channel(o_.vio_channel, d.sim.id), &m);
      status_->count("odometry");
    }
  }

  // --lockstep: handles messages until every drone's detector has answered the frame of
  // `frame_utime` (or --lockstep-timeout passes: those drones are then skipped until they catch up).
  // False if LCM failed.
  bool wait_for_detectors(int64_t frame_utime) {
    auto pending = [&](const Drone& d) { return !d.waited_out && d.answered_utime < frame_utime; };
    const auto limit = std::chrono::steady_clock::now() + std::chrono::duration<double>(o_.lockstep_timeout);
    for (Drone& d : drones_)
      if (d.waited_out && d.answered_utime >= frame_utime) {
        d.waited_out = false;
        log_->event("lockstep: drone " + std::to_string(d.sim.id) + "'s detector caught up; waiting for it again");
      }
    while (std::any_of(drones_.begin(), drones_.end(), pending) && !fact::app::stop_requested()) {
      if (std::chrono::steady_clock::now() >= limit) {
        for (Drone& d : drones_)
          if (pending(d)) {
            d.waited_out = true;
            reject("lockstep_timeouts", "lockstep: drone " + std::to_string(d.sim.id) + "'s detector has not answered the frame at " +
                                            std::to_string(frame_utime) + " us within " + fmt("%g s", o_.lockstep_timeout) +
                                            "; going on without waiting for it");
          }
        break;
      }
      if (handle_timeout(10) < 0 && !fact::app::stop_requested()) {
        log_->event("error: LCM failed while waiting for the detectors");
        return false;
      }
    }
    return true;
  }

  bool publish_frames(int64_t utime) {
    if (o_.lockstep && last_frame_utime_ >= 0 && !wait_for_detectors(last_frame_utime_)) return false;
    last_frame_utime_ = utime;
    render_all();
    const fact::CameraIntrinsics& k = intrinsics_;
    for (size_t i = 0; i < drones_.size(); ++i) {
      const fact::sim::RenderedFrame& frame_ = drones_[i].frame;
      fact::frame_t m;
      m.utime = utime;
      m.drone_id = drones_[i].sim.id;
      m.seq = drones_[i].frame_seq++;
      m.width = k.width;
      m.height = k.height;
      m.fx = k.fx;
      m.fy = k.fy;
      m.cx = k.cx;
      m.cy = k.cy;
      m.gray_size = static_cast<int32_t>(frame_.gray.size());
      m.gray.assign(frame_.gray.begin(), frame_.gray.end());
      m.depth_size = static_cast<int32_t>(frame_.depth_mm.size());
      m.depth_mm.resize(frame_.depth_mm.size());
      for (size_t j = 0; j < frame_.depth_mm.size(); ++j)
        m.depth_mm[j] = static_cast<int16_t>(std::min<uint16_t>(frame_.depth_mm[j], 32767));
      drones_[i].frames_lcm->publish(fact::app::channel(o_.frames_channel, m.drone_id), &m);
      status_->count("frames");
    }
    return true;
  }

  // Renders every drone's camera at the current poses, split over --render-threads threads (drone
  // i on thread i mod T; each drone has its own renderer and noise stream, so the frames do not
  // depend on T).
  void render_all() {
    const std::vector<fact::sim::DronePose> p = poses();
    const size_t n = drones_.size();
    const size_t threads = std::min<size_t>(static_cast<size_t>(o_.render_threads), n);
    auto work = [&](size_t first) {
      for (size_t i = first; i < n; i += threads) drones_[i].renderer->render(p, static_cast<int>(i), &drones_[i].frame);
    };
    const auto t0 = std::chrono::steady_clock::now();
    std::vector<std::thread> pool;
    for (size_t t = 1; t < threads; ++t) pool.emplace_back(work, t);
    work(0);
    for (std::thread& t : pool) t.join();
    render_s_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    renders_ += static_cast<int64_t>(n);
  }

  void publish_truth(int64_t utime) {
    fact::truth_t m;
    m.utime = utime;
    m.num_drones = static_cast<int32_t>(drones_.size());
    for (const Drone& d : drones_) {
      m.drone_ids.push_back(d.sim.id);
      m.frame_yaw.push_back(d.sim.frame_yaw);
      m.frame_origin.push_back({d.sim.origin.x(), d.sim.origin.y(), d.sim.origin.z()});
      m.position.push_back({d.sim.p.x(), d.sim.p.y(), d.sim.p.z()});
      m.yaw.push_back(d.sim.yaw);
    }
    lcm_->publish(o_.truth_channel, &m);
    status_->count("truth");
  }

  void progress(int64_t t) {
    const double ms = renders_ > 0 ? 1e3 * render_s_ / static_cast<double>(renders_) : 0.0;
    log_->event(fmt("sim t = %.1f s: ", t * 1e-6) + std::to_string(status_->value("frames")) + " frames (" +
                fmt("%.2f ms/render", ms) + "), " + std::to_string(status_->value("odometry")) + " odometry, " +
                std::to_string(status_->value("setpoints")) + " setpoints" +
                (o_.mavlink_port > 0 ? ", " + std::to_string(status_->value("fc_setpoints")) + " MAVLink setpoints" : ""));
  }

  // Handles pending LCM messages; with --rate > 0 also waits until the wall clock catches up
  // with sim time t. --rate is a cap: a sim that fell behind (slow rendering, --lockstep waits)
  // moves wall0 on instead of bursting to catch up. False if LCM failed.
  bool handle_messages(std::chrono::steady_clock::time_point* wall0, int64_t t) {
    if (o_.rate > 0) {
      const auto target = *wall0 + std::chrono::microseconds(static_cast<int64_t>(t / o_.rate));
      const auto behind = std::chrono::steady_clock::now() - target;
      if (behind > std::chrono::milliseconds(50)) *wall0 += behind;
    }
    for (;;) {
      int wait_ms = 0;
      if (o_.rate > 0) {
        const auto target = *wall0 + std::chrono::microseconds(static_cast<int64_t>(t / o_.rate));
        const auto left = std::chrono::duration_cast<std::chrono::microseconds>(target - std::chrono::steady_clock::now());
        wait_ms = static_cast<int>(std::max<int64_t>(0, (left.count() + 999) / 1000));
      }
      const int r = handle_timeout(wait_ms);
      if (r < 0 && fact::app::stop_requested()) return true;  // SIGINT / SIGTERM interrupted the wait
      if (r < 0) {
        log_->event("error: LCM failed while handling messages");
        return false;
      }
      if (fact::app::stop_requested()) return true;
      if (r == 0 && wait_ms == 0) return true;  // nothing pending and no time left to wait
      if (r == 0) continue;                     // timed out: re-check the remaining wait
    }
  }

  const Options& o_;
  fact::sim::World world_;
  lcm::LCM* lcm_;
  fact::app::Status* status_;
  const fact::app::Log* log_;
  fact::CameraIntrinsics intrinsics_;
  std::mt19937_64 drift_rng_;
  fact::sim::Script script_ = fact::sim::Script::none;
  fact::sim::ControllerGains gains_;
  fact::sim::DynamicsLimits limits_;
  std::vector<Drone> drones_;
  std::vector<std::string> channel_index_;
  std::vector<std::string> detections_index_;
  std::map<std::string, std::unique_ptr<lcm::LCM>> frame_lcms_;  // --frames-url instances by URL
  std::map<std::string, std::unique_ptr<lcm::LCM>> bus_lcms_;    // --drone-url instances by URL
  std::vector<lcm::LCM*> buses_;  // the main LCM, then each distinct drone bus (what is handled)
  int64_t last_frame_utime_ = -1;
  double render_s_ = 0;
  int64_t renders_ = 0;
};

std::string world_summary(const fact::sim::World& w, const Options& o) {
  std::string s = "world " + (o.world_file.empty() ? std::string("(built-in default)") : o.world_file) +
                  fmt(": room %.1f x %.1f x %.1f m, ", w.room_size.x(), w.room_size.y(), w.room_size.z()) +
                  std::to_string(w.obstacles.size()) + " obstacles, " + std::to_string(w.starts.size()) + " drones:";
  for (const auto& d : w.starts)
    s += " " + std::to_string(d.id) + fmt("@(%.2f, %.2f, %.2f) yaw %.2f", d.position.x(), d.position.y(), d.position.z(), d.yaw);
  return s;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App cli{"fact-sim: simulated drones in a room — rendered gray + depth frames, raw VIO, ground truth"};
  Options o;
  add_flags(cli, o);
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  fact::app::Log log(kApp, -1);
  fact::sim::World world;
  try {
    check(o);
    world = load_world(o);
  } catch (const FlagError& e) {
    log.event(std::string("error: ") + e.what());
    return 2;
  } catch (const fact::FormatError& e) {
    log.event(std::string("error: bad world file: ") + e.what());
    return 2;
  }
  if (o.print_ids) {
    for (size_t i = 0; i < world.starts.size(); ++i) std::cout << (i ? " " : "") << world.starts[i].id;
    std::cout << "\n";
    return 0;
  }
  fact::app::install_stop_handler();
  lcm::LCM lcm(o.lcm_url);
  if (!fact::app::lcm_opened(lcm, o.lcm_url, log)) return 1;
  fact::app::Status status(&lcm, o.status_channel, kApp, -1);
  log.event("start: seed " + std::to_string(o.seed) + fmt(", rate %g, duration %g s, camera %g Hz", o.rate, o.duration, o.camera_rate) +
            ", " + o.resolution + ", script " + o.script + ", epoch " + std::to_string(o.epoch_utime) + " us");
  log.event(world_summary(world, o));
  Simulator sim(o, world, &lcm, &status, &log);
  if (const std::string bad = sim.open_drone_urls(); !bad.empty()) {
    log.event("error: cannot open LCM for a drone's bus at " + bad + " (--drone-url " + o.drone_url + ")");
    return 1;
  }
  if (o.mavlink_port > 0) {
    try {
      sim.open_flight_controllers();
    } catch (const fact::sim_fc::SocketError& e) {
      log.event(std::string("error: ") + e.what());
      return 1;
    }
  } else {
    sim.subscribe();
  }
  if (const std::string bad = sim.open_frame_urls(); !bad.empty()) {
    log.event("error: cannot open LCM for frames at " + bad + " (--frames-url " + o.frames_url + ")");
    return 1;
  }
  if (o.lockstep) {
    sim.subscribe_detections();
    log.event("lockstep: each frame waits up to " + fmt("%g s", o.lockstep_timeout) + " for every drone's " +
              o.detections_channel + "_<id> answer to the previous frame");
  }
  return sim.run();
}
