// fact-preflight: the pre-flight checklist of one drone, run by scripts/run-drone.sh before the
// planner (the app that makes the drone move) is started. Each item is one line, PASS or FAIL
// with what was seen:
//   swarm key          --key-file loads as fact-gossip loads it (32 raw bytes or 64 hex digits), is
//                      a regular file owned by this user or root that no other user may read or
//                      write (mode 600 or 400), or --insecure was chosen;
//   flight controller  fact-fc-bridge reports the FC's HEARTBEAT fresh (fact::fc_state_t
//                      connected on FACT_FC_STATE_<id>) and the FC standby or active (MAV_STATE
//                      3 or 4, not booting, calibrating, critical, emergency or terminated);
//   camera             frames arrive (fact::frame_t on FACT_FRAMES_<id>) that fact-detector takes:
//                      this drone's id, 1 … 8192 px, sizes that match, usable intrinsics, and two
//                      with valid depth (frames without are skipped); or --png-dir holds
//                      intrinsics.json and gray/depth pairs;
//   VIO                odometry arrives from fact-vio-relay (fact::odometry_t on FACT_ODOMETRY_<id>,
//                      this drone's id, every field finite, seq and utime increasing, a relay
//                      restart taken as fact::app::odometry_restarted takes it) and, with
//                      frames on LCM, on the camera's clock: its newest utime within 1 s of the
//                      newest frame's (a VIO on the boot clock matches no detection).
// Exit codes: 0 every item passes; 1 an item fails; 2 bad flags.
#include "common/cli_checks.h"
#include "common/app.h"
#include "common/convert.h"
#include "common/flags.h"
#include "fact/fc_state_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/json_io.h"
#include "fact/odometry_t.hpp"
#include "fact_gossip/wire.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdint>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>

namespace {

namespace fs = std::filesystem;
constexpr const char* kApp = "fact-preflight";

struct Options {
  fact::app::CommonFlags common;
  std::string key_file, png_dir, frames_url;
  bool insecure = false;
  double timeout = 5;  // s to wait for the LCM items
  std::string frames_channel, odometry_channel, fc_state_channel;  // "" = FACT_<NAME>_<id>
};

// One checklist item.
struct Item {
  std::string name;
  bool pass = false;
  std::string seen;  // what was seen, or why it failed
};

Item check_key(const Options& o) {
  Item it{"swarm key", false, ""};
  if (o.insecure) {
    it.pass = true;
    it.seen = "none (--insecure: gossip is not authenticated)";
    return it;
  }
  if (o.key_file.empty()) {
    it.seen = "no --key-file (and not --insecure)";
    return it;
  }
  // A regular file, checked before it is opened: a FIFO hung the check, /dev/zero grew it without
  // end (review, session 33).
  struct stat st {};
  if (stat(o.key_file.c_str(), &st) != 0 || !S_ISREG(st.st_mode)) {
    it.seen = o.key_file + " is not a regular file";
    return it;
  }
  fact::app::SwarmKey key{};
  if (const std::string e = fact::app::load_key(o.key_file, &key); !e.empty()) {
    it.seen = e;
    return it;
  }
  if (st.st_mode & 077) {  // group or other may read or write it: the swarm's secret is not
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(st.st_mode & 0777));
    it.seen = o.key_file + " is open to other users (mode " + mode + "): chmod 600 it";
    return it;
  }
  if (st.st_uid != geteuid() && st.st_uid != 0) {  // its owner may rewrite it and chmod it open
    it.seen = o.key_file + " is owned by uid " + std::to_string(st.st_uid) + ", not by this user (uid " +
              std::to_string(geteuid()) + ") or root: chown it";
    return it;
  }
  it.pass = true;
  it.seen = o.key_file + " (32-byte key)";
  return it;
}

// As fact-detector reads the directory: intrinsics.json that it accepts (read_intrinsics_file),
// and <utime>_gray.png + <utime>_depth.png pairs named as it names them (png_frame_name: files
// with other names are ignored there, so they do not count here). A bad intrinsics.json or
// non-numeric names used to pass, and a symbolic link loop threw out of the check (review,
// session 33).
Item check_png_dir(const std::string& dir) {
  Item it{"camera", false, ""};
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) {
    it.seen = "--png-dir " + dir + " is not a directory" + (ec ? " (" + ec.message() + ")" : "");
    return it;
  }
  try {
    (void)fact::read_intrinsics_file((fs::path(dir) / "intrinsics.json").string());
  } catch (const fact::FormatError& e) {
    it.seen = e.what();
    return it;
  }
  int pairs = 0;
  for (fs::directory_iterator entry(dir, ec), end; !ec && entry != end; entry.increment(ec)) {
    const std::string n = entry->path().filename().string();
    std::string stem;
    int64_t utime = 0;
    const fact::PngFrameName kind = fact::png_frame_name(n, &stem, &utime);
    if (kind == fact::PngFrameName::other) continue;
    if (kind == fact::PngFrameName::time_too_large) {  // (the detector refuses the directory)
      it.seen = (fs::path(dir) / n).string() + ": the time " + stem + " us does not fit in 64 bits";
      return it;
    }
    std::error_code depth_ec;
    if (fs::is_regular_file(fs::path(dir) / (stem + "_depth.png"), depth_ec)) ++pairs;
  }
  if (ec) {
    it.seen = "--png-dir " + dir + ": " + ec.message();
    return it;
  }
  it.pass = pairs > 0;
  it.seen = std::to_string(pairs) + " gray/depth PNG pairs (<utime>_gray.png, <utime>_depth.png) in " + dir;
  return it;
}

// Listens for the LCM items until all have passed or the timeout.
class Listener {
 public:
  Listener(const Options& o, Item* fc, Item* camera, Item* vio) : o_(o), fc_(fc), camera_(camera), vio_(vio) {}

  void on_fc(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    fact::fc_state_t m;
    if (!decoded(rb, ch, &m, fc_)) return;
    if (m.drone_id != o_.common.drone_id) {  // another bridge on this channel: a failure of its own
      foreign("fc_state", m.drone_id, ch, fc_);
      return;
    }
    if (foreign_fc_) return;
    const bool ready = m.system_status == 3 || m.system_status == 4;  // MAV_STATE_STANDBY / ACTIVE
    fc_->pass = m.connected && ready;
    const std::string state = "MAV_STATE " + std::to_string(m.system_status) + " (" + mav_state(m.system_status) + ")";
    fc_->seen = !m.connected ? (m.heartbeat_age_ms < 0 ? "fact-fc-bridge runs but has never seen a HEARTBEAT from the flight controller"
                                                        : "last HEARTBEAT " + std::to_string(m.heartbeat_age_ms) + " ms ago (stale)")
                : !ready     ? "HEARTBEAT fresh but the flight controller is not ready: " + state
                             : "HEARTBEAT " + std::to_string(m.heartbeat_age_ms) + " ms old, " + state + ", " +
                                   (m.armed ? "armed" : "disarmed") + (m.offboard ? ", OFFBOARD" : "");
  }

  // A frame is checked as fact-detector checks it (fact::app::frame_message_error): one it would reject
  // fails the item for good, naming the field and value.
  void on_frame(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    fact::frame_t m;
    if (!decoded(rb, ch, &m, camera_)) return;
    std::string counter;
    if (const std::string e = fact::app::frame_message_error(m, o_.common.drone_id, &counter); !e.empty()) {
      camera_->pass = false;  // a stream fact-detector rejects frame by frame: fails for good
      camera_->seen = "a frame fact-detector rejects on " + ch + ": " + e;
      bad_frame_ = true;
      return;
    }
    if (bad_frame_) return;
    // A frame without valid depth (a camera warming up, a hand over the lens) is skipped, as the
    // detector skips it; the item passes on 2 frames with depth.
    if (std::all_of(m.depth_mm.begin(), m.depth_mm.end(), [](int16_t d) { return d == 0; })) {
      if (!camera_->pass)
        camera_->seen = "frame seq " + std::to_string(m.seq) + " on " + ch +
                        ": depth_mm is 0 at every pixel (no valid depth: is the depth stream on?)";
      return;
    }
    ++depth_frames_;
    newest_frame_utime_ = std::max(newest_frame_utime_, m.utime);
    camera_->pass = depth_frames_ >= 2;
    camera_->seen = std::to_string(depth_frames_) + " frames " + std::to_string(m.width) + "x" + std::to_string(m.height) +
                    " with depth on " + ch;
    check_clocks();
  }

  // Odometry as fact-detector, fact-gossip and fact-planner take it: one they would refuse fails
  // the item for good, naming the field and value.
  void on_odometry(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    fact::odometry_t m;
    if (!decoded(rb, ch, &m, vio_)) return;
    if (m.drone_id != o_.common.drone_id) {
      foreign("odometry", m.drone_id, ch, vio_);
      return;
    }
    std::string e;
    const std::pair<const char*, double> fields[] = {
        {"position[0]", m.position[0]}, {"position[1]", m.position[1]}, {"position[2]", m.position[2]},
        {"velocity[0]", m.velocity[0]}, {"velocity[1]", m.velocity[1]}, {"velocity[2]", m.velocity[2]},
        {"yaw", m.yaw},                 {"roll", m.roll},               {"pitch", m.pitch}};
    for (const auto& [name, v] : fields)
      if (e.empty() && !std::isfinite(v)) e = std::string(name) + " = " + fmt(v) + " (must be finite)";
    // A stream restart (fact::app::odometry_restarted: seq back to 0 or far back) is taken as the
    // apps take it: counting starts again.
    if (e.empty() && odometry_ > 0 && fact::app::odometry_restarted(last_seq_, last_utime_, m.seq, m.utime)) odometry_ = 0;
    if (e.empty() && odometry_ > 0 && !(m.seq > last_seq_ && m.utime > last_utime_))
      e = "seq " + std::to_string(m.seq) + ", utime " + std::to_string(m.utime) + " us after seq " +
          std::to_string(last_seq_) + ", utime " + std::to_string(last_utime_) + " us: not increasing (a frozen or "
          "repeating VIO)";
    if (!e.empty() || bad_odometry_) {
      if (!e.empty()) vio_->seen = "odometry the apps refuse on " + ch + ": seq " + std::to_string(m.seq) + ": " + e;
      vio_->pass = false;
      bad_odometry_ = true;
      return;
    }
    ++odometry_;
    last_seq_ = m.seq;
    last_utime_ = m.utime;
    vio_->pass = odometry_ >= 2;
    vio_->seen = std::to_string(odometry_) + " samples on " + ch + ", position (" + fmt(m.position[0]) + ", " +
                 fmt(m.position[1]) + ", " + fmt(m.position[2]) + ") m, yaw " + fmt(m.yaw) + " rad";
    check_clocks();
  }

 private:
  static std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
  }
  static const char* mav_state(int s) {
    static const char* const names[] = {"uninit", "boot", "calibrating", "standby", "active",
                                        "critical", "emergency", "poweroff", "flight termination"};
    return s >= 0 && s <= 8 ? names[s] : "unknown";
  }
  // A message of another drone on this drone's channel: another process publishes there, which
  // fails the item (the apps would drop its messages, or take the wrong ones).
  void foreign(const char* what, int drone, const std::string& ch, Item* item) {
    item->pass = false;
    item->seen = std::string(what) + " of drone " + std::to_string(drone) + " on " + ch + " (this is drone " +
                 std::to_string(o_.common.drone_id) + "): another process publishes on this drone's channel";
    if (item == fc_) foreign_fc_ = true;
    if (item == vio_) bad_odometry_ = true;
  }
  // Frames on LCM and odometry must share a clock: the newest odometry within 1 s of the newest
  // frame (fact-gossip interpolates the odometry at each detection's time).
  void check_clocks() {
    if (!o_.png_dir.empty() || newest_frame_utime_ == INT64_MIN || odometry_ == 0 || bad_odometry_) return;
    // (in double: the int64 difference of two far-apart stamps overflowed and came out small)
    const double apart_s = (static_cast<double>(last_utime_) - static_cast<double>(newest_frame_utime_)) * 1e-6;
    if (std::abs(apart_s) <= 1.0) return;
    vio_->pass = false;
    vio_->seen = "odometry utime " + std::to_string(last_utime_) + " us is " + fmt(apart_s) + " s from the newest frame's " +
                 std::to_string(newest_frame_utime_) + " us: the VIO and the camera are on different clocks (for a "
                 "tum or udp VIO source, fact-vio-relay --restamp)";
  }
  template <class T>
  bool decoded(const lcm::ReceiveBuffer* rb, const std::string& ch, T* m, Item* item) {
    const std::string err = fact::app::decode_error(rb->data, static_cast<int>(rb->data_size), m);
    if (err.empty()) return true;
    if (!item->pass) item->seen = "undecodable message on " + ch + ": " + err;
    return false;
  }
  const Options& o_;
  Item *fc_, *camera_, *vio_;
  int depth_frames_ = 0, odometry_ = 0;
  bool bad_frame_ = false, bad_odometry_ = false, foreign_fc_ = false;
  int64_t last_seq_ = 0, last_utime_ = 0;      // the newest odometry taken
  int64_t newest_frame_utime_ = INT64_MIN;     // µs
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App cli{"fact-preflight: one drone's pre-flight checklist (swarm key, flight-controller heartbeat, camera\n"
               "frames, VIO odometry); run by scripts/run-drone.sh before the planner starts.",
               kApp};
  fact::app::add_common_flags(cli, &o.common, fact::app::DroneIdFlag::required);
  cli.add_option("--key-file", o.key_file, "Swarm key file (as fact-gossip's --key-file)")->type_name("FILE");
  cli.add_flag("--insecure", o.insecure, "No swarm key: the key item passes, saying gossip is unauthenticated");
  cli.add_option("--png-dir", o.png_dir, "Camera from PNG pairs: check the directory instead of frames on LCM")->type_name("DIR");
  cli.add_option("--frames-url", o.frames_url, "LCM URL the frames come on, if not --lcm-url")->type_name("URL");
  cli.add_option("--frames-channel", o.frames_channel, "Default FACT_FRAMES_<id>")->type_name("CHANNEL");
  cli.add_option("--odometry-channel", o.odometry_channel, "Default FACT_ODOMETRY_<id>")->type_name("CHANNEL");
  cli.add_option("--fc-state-channel", o.fc_state_channel, "Default FACT_FC_STATE_<id>")->type_name("CHANNEL");
  cli.add_option("--timeout", o.timeout, "s to wait for the flight controller, frames and odometry")->capture_default_str();
  cli.footer("--sim-clock, --clock-channel, --status-channel and --status-period are accepted, as every app takes\n"
             "them (scripts/run-drone.sh gives each app the same ones), and have no effect here: the checklist\n"
             "waits on the steady clock, compares the messages' own stamps, and is printed, not published.\n"
             "Exit codes: 0 every item passes; 1 an item fails; 2 bad flags.");
  try {
    fact::app::refuse_empty_values(cli);
    cli.parse(argc, argv);
    fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::required);
    fact::app::check_range("--timeout", o.timeout, 0.1, 3600, "s");  // (1e-300 waited for nothing)
    if (o.insecure && !o.key_file.empty()) throw fact::app::FlagError("--insecure and --key-file exclude each other");
  } catch (const CLI::ParseError& e) {
    return cli.exit(e) == 0 ? 0 : 2;
  } catch (const fact::app::FlagError& e) {
    std::cerr << kApp << ": error: " << e.what() << " (see --help)\n";
    return 2;
  }
  const int id = o.common.drone_id;
  auto def = [id](std::string* ch, const char* base) {
    if (ch->empty()) *ch = fact::app::channel(base, id);
  };
  def(&o.frames_channel, "FACT_FRAMES");
  def(&o.odometry_channel, "FACT_ODOMETRY");
  def(&o.fc_state_channel, "FACT_FC_STATE");

  Item key = check_key(o);
  Item fc{"flight controller", false, "no fact::fc_state_t on " + o.fc_state_channel + " (is fact-fc-bridge running?)"};
  Item camera{"camera", false, "no frame on " + o.frames_channel};
  Item vio{"VIO", false, "no odometry on " + o.odometry_channel + " (is fact-vio-relay running and its source live?)"};
  if (!o.png_dir.empty()) camera = check_png_dir(o.png_dir);

  lcm::LCM lcm(o.common.lcm_url);
  std::unique_ptr<lcm::LCM> frames_lcm;
  if (!o.frames_url.empty() && o.png_dir.empty()) frames_lcm = std::make_unique<lcm::LCM>(o.frames_url);
  if (!lcm.good() || (frames_lcm && !frames_lcm->good())) {
    std::cerr << kApp << ": error: cannot open LCM (--lcm-url / --frames-url)\n";
    return 1;
  }
  fact::app::install_stop_handler();
  Listener l(o, &fc, &camera, &vio);
  lcm.subscribe(o.fc_state_channel, &Listener::on_fc, &l);
  lcm.subscribe(o.odometry_channel, &Listener::on_odometry, &l);
  if (o.png_dir.empty()) (frames_lcm ? *frames_lcm : lcm).subscribe(o.frames_channel, &Listener::on_frame, &l)->setQueueCapacity(4);
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(o.timeout);
  fact::app::run_loop(lcm, 20, [&](int64_t) {
    if ((fc.pass && camera.pass && vio.pass) || std::chrono::steady_clock::now() >= end) fact::app::request_stop();
  }, {frames_lcm.get()});

  bool all = true;
  std::printf("pre-flight checklist, drone %d:\n", id);
  for (const Item* it : {&key, &fc, &camera, &vio}) {
    std::printf("  [%s] %-17s %s\n", it->pass ? "PASS" : "FAIL", it->name.c_str(), it->seen.c_str());
    all = all && it->pass;
  }
  std::printf(all ? "pre-flight: every item passes\n" : "pre-flight: FAILED, the drone must not fly\n");
  return all ? 0 : 1;
}
