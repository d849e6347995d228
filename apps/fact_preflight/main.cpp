// fact-preflight: the pre-flight checklist of one drone, run by scripts/run-drone.sh before the
// planner (the app that makes the drone move) is started. Each item is one line, PASS or FAIL
// with what was seen:
//   swarm key          --key-file loads as fact-gossip loads it (32 raw bytes or 64 hex digits)
//                      and is not readable by other users (or --insecure was chosen);
//   flight controller  fact-fc-bridge reports the FC's HEARTBEAT fresh (fact::fc_state_t
//                      connected on FACT_FC_STATE_<id>);
//   camera             frames arrive (fact::frame_t on FACT_FRAMES_<id>, this drone's id, sane
//                      sizes), or --png-dir holds intrinsics.json and gray/depth pairs;
//   VIO                odometry arrives from fact-vio-relay (fact::odometry_t on FACT_ODOMETRY_<id>,
//                      finite).
// Exit codes: 0 every item passes; 1 an item fails; 2 bad flags.
#include "common/app.h"
#include "common/flags.h"
#include "fact/fc_state_t.hpp"
#include "fact/frame_t.hpp"
#include "fact/odometry_t.hpp"
#include "fact_gossip/wire.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <sys/stat.h>

#include <chrono>
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
  fact::app::SwarmKey key{};
  if (const std::string e = fact::app::load_key(o.key_file, &key); !e.empty()) {
    it.seen = e;
    return it;
  }
  struct stat st {};
  if (stat(o.key_file.c_str(), &st) == 0 && (st.st_mode & S_IROTH)) {
    char mode[8];
    std::snprintf(mode, sizeof mode, "%03o", static_cast<unsigned>(st.st_mode & 0777));
    it.seen = o.key_file + " is readable by every user (mode " + mode + "): chmod 600 it";
    return it;
  }
  it.pass = true;
  it.seen = o.key_file + " (32-byte key)";
  return it;
}

Item check_png_dir(const std::string& dir) {
  Item it{"camera", false, ""};
  if (!fs::is_directory(dir)) {
    it.seen = "--png-dir " + dir + " is not a directory";
    return it;
  }
  if (!fs::exists(fs::path(dir) / "intrinsics.json")) {
    it.seen = dir + "/intrinsics.json is missing";
    return it;
  }
  int pairs = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    const std::string n = e.path().filename().string();
    const auto at = n.rfind("_gray.png");
    if (at != std::string::npos && at + 9 == n.size() && fs::exists(fs::path(dir) / (n.substr(0, at) + "_depth.png"))) ++pairs;
  }
  it.pass = pairs > 0;
  it.seen = std::to_string(pairs) + " gray/depth PNG pairs in " + dir;
  return it;
}

// Listens for the LCM items until all have passed or the timeout.
class Listener {
 public:
  Listener(const Options& o, Item* fc, Item* camera, Item* vio) : o_(o), fc_(fc), camera_(camera), vio_(vio) {}

  void on_fc(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    fact::fc_state_t m;
    if (!decoded(rb, ch, &m, fc_)) return;
    if (m.drone_id != o_.common.drone_id) {
      fc_->seen = "fc_state for drone " + std::to_string(m.drone_id) + " on " + ch;
      return;
    }
    fc_->pass = m.connected;
    fc_->seen = m.connected ? "HEARTBEAT " + std::to_string(m.heartbeat_age_ms) + " ms old, " + (m.armed ? "armed" : "disarmed") +
                                  (m.offboard ? ", OFFBOARD" : "")
                            : (m.heartbeat_age_ms < 0 ? "fact-fc-bridge runs but has never seen a HEARTBEAT from the flight controller"
                                                      : "last HEARTBEAT " + std::to_string(m.heartbeat_age_ms) + " ms ago (stale)");
  }

  void on_frame(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    fact::frame_t m;
    if (!decoded(rb, ch, &m, camera_)) return;
    ++frames_;
    if (m.drone_id != o_.common.drone_id || m.width <= 0 || m.height <= 0 || m.gray_size != m.width * m.height ||
        m.depth_size != m.width * m.height || !(m.fx > 0)) {
      camera_->pass = false;
      camera_->seen = "a bad frame on " + ch + ": drone_id " + std::to_string(m.drone_id) + ", " + std::to_string(m.width) + "x" +
                      std::to_string(m.height) + ", gray_size " + std::to_string(m.gray_size) + ", depth_size " +
                      std::to_string(m.depth_size);
      bad_frame_ = true;
      return;
    }
    if (bad_frame_) return;
    camera_->pass = frames_ >= 2;
    camera_->seen = std::to_string(frames_) + " frames " + std::to_string(m.width) + "x" + std::to_string(m.height) + " on " + ch;
  }

  void on_odometry(const lcm::ReceiveBuffer* rb, const std::string& ch) {
    fact::odometry_t m;
    if (!decoded(rb, ch, &m, vio_)) return;
    const bool finite = std::isfinite(m.position[0]) && std::isfinite(m.position[1]) && std::isfinite(m.position[2]) &&
                        std::isfinite(m.yaw);
    ++odometry_;
    vio_->pass = finite && odometry_ >= 2;
    vio_->seen = finite ? std::to_string(odometry_) + " samples on " + ch + ", position (" + fmt(m.position[0]) + ", " +
                              fmt(m.position[1]) + ", " + fmt(m.position[2]) + ") m, yaw " + fmt(m.yaw) + " rad"
                        : "non-finite odometry on " + ch;
  }

 private:
  static std::string fmt(double v) {
    char b[32];
    std::snprintf(b, sizeof b, "%.2f", v);
    return b;
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
  int frames_ = 0, odometry_ = 0;
  bool bad_frame_ = false;
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
  cli.footer("Exit codes: 0 every item passes; 1 an item fails; 2 bad flags.");
  try {
    cli.parse(argc, argv);
    fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::required);
    if (!(std::isfinite(o.timeout) && o.timeout > 0)) throw fact::app::FlagError("--timeout: expected a number > 0, got " + std::to_string(o.timeout));
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
