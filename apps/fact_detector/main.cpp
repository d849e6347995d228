// fact-detector: gray + depth frames in (fact::frame_t on FACT_FRAMES_<id>, or a directory of PNG
// pairs), tracked detections out (fact::detections_t on FACT_DETECTIONS_<id>), one message per
// processed frame (also when empty), holding the confirmed tracks matched in that frame.
//
// Per frame: checks (sizes, intrinsics, depth) → backend (depth segmentation, or YOLO through
// OpenCV dnn) → tracker (ByteTrack style, own rotation compensated by H = K·R·K⁻¹ from the
// odometry attitude at the frame time) → per confirmed track: range (mean of the smallest X % of
// the box's depths + target radius) and the vector in the gravity-aligned body frame.
// The work is lib/'s (fact/detector.h, fact/tracker.h, fact/yolo.h); this file is plumbing.
//
// Exit codes: 0 end of --png-dir, or SIGINT/SIGTERM; 1 LCM failed; 2 bad flags, an unreadable
// --png-dir, or a --model that does not load.
#include "common/app.h"
#include "common/convert.h"
#include "common/flags.h"
#include "fact/detector.h"
#include "fact/json_io.h"
#include "fact/odometry_filter.h"
#include "fact/odometry_t.hpp"
#include "fact/tracker.h"
#include "fact/yolo.h"

#include <CLI/CLI.hpp>
#include <lcm/lcm-cpp.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include <algorithm>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <sstream>
#include <string>
#include <system_error>
#include <utility>
#include <vector>

namespace {

namespace fs = std::filesystem;
constexpr const char* kApp = "fact-detector";

struct Options {
  fact::app::CommonFlags common;
  std::string frames_channel;     // "" = FACT_FRAMES_<id>
  std::string frames_url;         // "" = frames come on --lcm-url
  std::string odometry_channel;   // "" = FACT_ODOMETRY_<id>
  std::string output_channel;     // "" = FACT_DETECTIONS_<id>
  std::string png_dir;            // read frames from here instead of LCM
  std::string backend = "depth";  // depth | yolo
  std::string model;              // yolo: the ONNX file
  int yolo_size = 640;            // yolo: model input side (px)
  double odometry_wait_ms = 50;   // how long a frame waits for odometry newer than it (ms, wall clock)
  std::vector<double> camera_offset = {0.10, 0.0, 0.0};  // optical centre in the body frame (m)
  double camera_pitch = 0.0;      // rad, camera tilted down by this about the body y axis
  fact::RangeOptions range;
  fact::SegmentationOptions segmentation;
  fact::TrackerOptions tracker;
};

void add_flags(CLI::App& app, Options& o) {
  fact::app::add_common_flags(app, &o.common, fact::app::DroneIdFlag::optional);
  app.add_option("--frames-channel", o.frames_channel, "Input frames (default FACT_FRAMES_<id>)")->type_name("CHANNEL");
  app.add_option("--frames-url", o.frames_url,
                 "LCM URL the frames come on, if not --lcm-url (e.g. a per-drone camera group with a large "
                 "recv_buf_size, so the other apps never receive frames)")
      ->type_name("URL");
  app.add_option("--odometry-channel", o.odometry_channel, "Odometry for the attitude (default FACT_ODOMETRY_<id>)")
      ->type_name("CHANNEL");
  app.add_option("--output-channel", o.output_channel, "Detections out (default FACT_DETECTIONS_<id>)")
      ->type_name("CHANNEL");
  app.add_option("--png-dir", o.png_dir,
                 "Read <utime>_gray.png + <utime>_depth.png pairs, intrinsics.json and optional odometry.tum "
                 "from this directory instead of LCM; exit 0 at the end")
      ->type_name("DIR");
  app.add_option("--backend", o.backend, "Detector backend: depth (segmentation) or yolo (ONNX model)")
      ->type_name("NAME")
      ->capture_default_str();
  app.add_option("--model", o.model, "yolo: ONNX YOLOv8 model file")->type_name("FILE");
  app.add_option("--yolo-size", o.yolo_size, "yolo: the model's square input size (px)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.add_option("--odometry-wait-ms", o.odometry_wait_ms,
                 "How long a frame waits for odometry newer than it before it is processed with the newest (ms)")
      ->capture_default_str();
  app.add_option("--smallest-percent", o.range.smallest_percent,
                 "Range: mean of the smallest X % of the valid depths in the box (0 < X <= 100)")
      ->capture_default_str();
  app.add_option("--target-radius", o.range.target_radius,
                 "Range: added to the near-surface distance to reach the target's centre (m)")
      ->capture_default_str();
  app.add_option("--camera-offset", o.camera_offset, "Camera optical centre in the body frame x,y,z (m, FLU)")
      ->delimiter(',')
      ->expected(3)
      ->type_name("X,Y,Z");
  app.add_option("--camera-pitch", o.camera_pitch, "Camera tilted down by this angle about the body y axis (rad)")
      ->capture_default_str();
  app.add_option("--min-depth", o.segmentation.min_depth, "Segmentation: ignore nearer depths (m)")
      ->capture_default_str();
  app.add_option("--max-depth", o.segmentation.max_depth, "Segmentation: no blob farther than this (m)")
      ->capture_default_str();
  app.add_option("--min-size", o.segmentation.min_size, "Segmentation: a drone blob's larger side at least (m)")
      ->capture_default_str();
  app.add_option("--max-size", o.segmentation.max_size, "Segmentation: a drone blob's sides at most (m)")
      ->capture_default_str();
  app.add_option("--background-gap", o.segmentation.background_gap,
                 "Segmentation: a drone is nearer than its surroundings by at least this (m)")
      ->capture_default_str();
  app.add_option("--confirm-hits", o.tracker.confirm_hits, "Tracker: matched frames to confirm a track")
      ->capture_default_str()->check(fact::app::decimal_integer());
  app.add_option("--max-lost", o.tracker.max_lost, "Tracker: frames a lost track is kept")->capture_default_str()
      ->check(fact::app::decimal_integer());
  app.footer(
      "Publishes fact::detections_t per processed frame: the confirmed tracks matched in it, each with\n"
      "track_id, box (u, v, w, h px; edges enclose the pixels), confidence, range (m, centre to centre)\n"
      "and vector (m, observer centre -> target centre, gravity-aligned body frame: x heading, z up).\n"
      "Attitude (roll, pitch for the vector; yaw, pitch, roll for the rotation compensation) comes from\n"
      "odometry interpolated at the frame time; a frame waits up to --odometry-wait-ms for odometry\n"
      "newer than it, then uses the newest (counted: stale_odometry; none at all: no_odometry, level).\n"
      "--png-dir DIR: DIR/intrinsics.json {\"width\",\"height\",\"fx\",\"fy\",\"cx\",\"cy\"}, pairs\n"
      "<utime>_gray.png (8-bit) + <utime>_depth.png (16-bit mm, 0 = invalid), optional DIR/odometry.tum\n"
      "(t tx ty tz qx qy qz qw, t in s, Hamilton world-from-body quaternion).\n"
      "Rejected, counted and logged, the app keeps running: wrong sizes (bad_frame), bad intrinsics\n"
      "(bad_intrinsics), all-invalid depth (no_depth), depth and gray of different sizes (size_mismatch),\n"
      "another drone's frame (wrong_drone_id), undecodable messages (undecodable), non-finite attitude\n"
      "(bad_odometry), odometry not later than the newest sample or more than 10 s after it\n"
      "(odometry_out_of_order; 20 such in a consistent run, or a seq going back, restart the attitude\n"
      "buffer: odometry_restarts).\n"
      "Exit codes: 0 end of --png-dir or SIGINT/SIGTERM; 1 LCM failure; 2 bad flags, unreadable --png-dir,\n"
      "or a --model that fails to load.");
}

void check(Options& o) {
  fact::app::check_common_flags(o.common, fact::app::DroneIdFlag::optional);
  const int id = o.common.drone_id;
  if (o.frames_channel.empty()) o.frames_channel = fact::app::channel("FACT_FRAMES", id);
  if (o.odometry_channel.empty()) o.odometry_channel = fact::app::channel("FACT_ODOMETRY", id);
  if (o.output_channel.empty()) o.output_channel = fact::app::channel("FACT_DETECTIONS", id);
  if (o.backend != "depth" && o.backend != "yolo")
    throw fact::app::FlagError("--backend: expected depth or yolo, got \"" + o.backend + "\"");
  if (o.backend == "yolo" && o.model.empty()) throw fact::app::FlagError("--backend yolo needs --model FILE");
  if (o.backend != "yolo" && !o.model.empty()) throw fact::app::FlagError("--model is only for --backend yolo");
  if (!(o.range.smallest_percent > 0 && o.range.smallest_percent <= 100))
    throw fact::app::FlagError("--smallest-percent: expected a number in (0, 100], got " +
                               std::to_string(o.range.smallest_percent));
  if (!std::isfinite(o.range.target_radius) || o.range.target_radius < 0)
    throw fact::app::FlagError("--target-radius: expected a finite number >= 0, got " +
                               std::to_string(o.range.target_radius));
  for (double c : o.camera_offset)
    if (!std::isfinite(c)) throw fact::app::FlagError("--camera-offset: expected finite numbers");
  if (!std::isfinite(o.camera_pitch)) throw fact::app::FlagError("--camera-pitch: expected a finite number");
  if (!(o.odometry_wait_ms >= 0 && o.odometry_wait_ms < 1e6))
    throw fact::app::FlagError("--odometry-wait-ms: expected a number in [0, 1e6), got " +
                               std::to_string(o.odometry_wait_ms));
  fact::app::check_positive("--min-depth", o.segmentation.min_depth);
  fact::app::check_positive("--max-depth", o.segmentation.max_depth);
  fact::app::check_positive("--min-size", o.segmentation.min_size);
  fact::app::check_positive("--max-size", o.segmentation.max_size);
  // Each alone is fine; together they must leave something to find (9 … 8 m found nothing, silently).
  if (!(o.segmentation.min_depth < o.segmentation.max_depth))
    throw fact::app::FlagError("--min-depth " + std::to_string(o.segmentation.min_depth) + " must be below --max-depth " +
                               std::to_string(o.segmentation.max_depth));
  if (!(o.segmentation.min_size <= o.segmentation.max_size))
    throw fact::app::FlagError("--min-size " + std::to_string(o.segmentation.min_size) +
                               " must be at most --max-size " + std::to_string(o.segmentation.max_size));
  if (!(o.segmentation.background_gap >= 0))
    throw fact::app::FlagError("--background-gap: expected a number >= 0, got " +
                               std::to_string(o.segmentation.background_gap));
  if (o.tracker.confirm_hits < 1) throw fact::app::FlagError("--confirm-hits: expected >= 1");
  if (o.tracker.max_lost < 0) throw fact::app::FlagError("--max-lost: expected >= 0");
}

fact::CameraExtrinsics extrinsics_of(const Options& o) {
  fact::CameraExtrinsics e;  // default: looking ahead; pitched down by camera_pitch about body y
  e.R_body_cam = Eigen::AngleAxisd(o.camera_pitch, Eigen::Vector3d::UnitY()).toRotationMatrix() * e.R_body_cam;
  e.t_body_cam = Eigen::Vector3d(o.camera_offset[0], o.camera_offset[1], o.camera_offset[2]);
  return e;
}

// Attitude samples by time; linear interpolation (yaw is unwrapped upstream).
struct Attitude {
  int64_t utime = 0;
  double yaw = 0, pitch = 0, roll = 0;
};
class AttitudeBuffer {
 public:
  static constexpr int64_t kMaxGapUs = 10000000;  // a sample more than 10 s after the newest is refused
  static constexpr std::size_t kRestartRun = 20;  // refused samples in a consistent run that restart it
  static constexpr std::size_t kCapacity = 2000;

  enum class Push { accepted, restarted, not_later, too_far_ahead };

  // A sample with its odometry seq. A seq going back to 0, by more than reordering can, or with a
  // time over 1 s earlier (fact::app::odometry_restarted) is the relay's restart (its clock was
  // reset): the buffer starts again. A sample not later than the newest, or more than kMaxGapUs after it,
  // is refused; kRestartRun refused samples in a row, each later than the one before and within
  // kMaxGapUs of it, are a new clock too and start the buffer again (one glitched sample far
  // ahead used to freeze the attitude for good, and a VIO clock reset lost every later sample).
  Push push(const Attitude& a, int64_t seq) {
    const bool restarted = have_seq_ && !samples_.empty() &&
                           fact::app::odometry_restarted(last_seq_, samples_.back().utime, seq, a.utime);
    if (!have_seq_ || seq > last_seq_ || restarted) last_seq_ = seq;  // (not lowered by a reordered one)
    have_seq_ = true;
    if (restarted) return restart({a});
    if (samples_.empty() || later_within_gap(samples_.back().utime, a.utime)) {
      run_.clear();
      append(a);
      return Push::accepted;
    }
    const bool consistent = !run_.empty() && later_within_gap(run_.back().utime, a.utime);
    if (!consistent) run_.clear();
    run_.push_back(a);
    if (run_.size() >= kRestartRun) return restart(std::deque<Attitude>(run_.begin(), run_.end()));
    return a.utime <= samples_.back().utime ? Push::not_later : Push::too_far_ahead;
  }
  // A recorded file's sample (--png-dir's odometry.tum): taken when later than the newest, whatever
  // the gap (a pause in the recording is not a new clock).
  bool push_recorded(const Attitude& a) {
    if (!samples_.empty() && a.utime <= samples_.back().utime) return false;
    append(a);
    return true;
  }
  bool empty() const { return samples_.empty(); }
  int64_t newest() const { return samples_.empty() ? INT64_MIN : samples_.back().utime; }
  // Interpolated at t, clamped to the oldest / newest sample.
  Attitude at(int64_t t) const {
    if (t <= samples_.front().utime) return samples_.front();
    if (t >= samples_.back().utime) return samples_.back();
    auto it = std::lower_bound(samples_.begin(), samples_.end(), t,
                               [](const Attitude& a, int64_t x) { return a.utime < x; });
    const Attitude& b = *it;
    const Attitude& a = *(it - 1);
    const double s = double(t - a.utime) / double(b.utime - a.utime);
    return Attitude{t, a.yaw + s * (b.yaw - a.yaw), a.pitch + s * (b.pitch - a.pitch), a.roll + s * (b.roll - a.roll)};
  }

 private:
  // t later than t0 by at most kMaxGapUs (the difference taken unsigned: no overflow for any times).
  static bool later_within_gap(int64_t t0, int64_t t) {
    return t > t0 && static_cast<uint64_t>(t) - static_cast<uint64_t>(t0) <= static_cast<uint64_t>(kMaxGapUs);
  }
  void append(const Attitude& a) {
    samples_.push_back(a);
    while (samples_.size() > kCapacity) samples_.pop_front();
  }
  Push restart(std::deque<Attitude> samples) {
    samples_ = std::move(samples);
    run_.clear();
    return Push::restarted;
  }

  std::deque<Attitude> samples_;
  std::deque<Attitude> run_;  // refused samples since the last accepted one, while consistent
  bool have_seq_ = false;
  int64_t last_seq_ = 0;
};

// Backend + tracker + range: a frame with its attitude → detections_t.
class Pipeline {
 public:
  Pipeline(const Options& o, std::unique_ptr<fact::YoloDetector> yolo)
      : o_(o), extrinsics_(extrinsics_of(o)), tracker_(o.tracker), yolo_(std::move(yolo)) {}

  // "" and *out filled, or what went wrong with the backend.
  std::string process(const fact::FrameView& frame, int64_t seq, const std::optional<Attitude>& att,
                      fact::detections_t* out) {
    std::vector<fact::BoxDetection> boxes;
    if (yolo_) {
      std::string error;
      boxes = yolo_->detect(frame, &error);
      if (!error.empty()) return "yolo: " + error;
    } else {
      try {  // OpenCV asserts by throwing: a frame it cannot handle is that frame's failure, not the app's
        boxes = fact::detect_depth(frame, o_.segmentation);
      } catch (const cv::Exception& e) {
        return std::string("depth segmentation: ") + e.what();
      }
    }
    Eigen::Matrix3d H = Eigen::Matrix3d::Identity();  // previous frame's pixels → this frame's
    if (att && previous_) {
      const Eigen::Matrix3d R = fact::camera_rotation(previous_->yaw, previous_->pitch, previous_->roll, att->yaw,
                                                      att->pitch, att->roll, extrinsics_);
      H = fact::rotation_homography(frame.intrinsics, R);
    }
    previous_ = att;
    tracker_.update(boxes, H);
    out->utime = frame.utime;
    out->drone_id = o_.common.drone_id;
    out->frame_seq = seq;
    out->detections.clear();
    const double roll = att ? att->roll : 0.0, pitch = att ? att->pitch : 0.0;
    for (const fact::Track* t : tracker_.confirmed_matched()) {
      const fact::TargetVector v = fact::target_vector(frame, t->box, extrinsics_, roll, pitch, o_.range);
      if (!v.valid) continue;
      fact::detection_t d;
      d.track_id = t->id;
      for (int i = 0; i < 3; ++i) d.vector[i] = v.vector_g[i];
      d.box[0] = t->box.u;
      d.box[1] = t->box.v;
      d.box[2] = t->box.w;
      d.box[3] = t->box.h;
      d.confidence = t->box.score;
      d.range = v.range;
      out->detections.push_back(d);
    }
    out->count = static_cast<int32_t>(out->detections.size());
    return "";
  }

 private:
  const Options& o_;
  fact::CameraExtrinsics extrinsics_;
  fact::Tracker tracker_;
  std::unique_ptr<fact::YoloDetector> yolo_;
  std::optional<Attitude> previous_;
};

class App {
 public:
  App(lcm::LCM* lcm, const Options& o, std::unique_ptr<fact::YoloDetector> yolo)
      : lcm_(lcm), o_(o), log_(kApp, o.common.drone_id), status_(lcm, o.common.status_channel, kApp, o.common.drone_id),
        pipeline_(o, std::move(yolo)) {
    status_.set_period_us(static_cast<int64_t>(std::llround(o.common.status_period * 1e6)));
    for (const char* c : {"frames", "published", "detections", "bad_frame", "size_mismatch", "bad_intrinsics",
                          "no_depth", "wrong_drone_id", "undecodable", "stale_odometry", "no_odometry",
                          "bad_odometry", "odometry_out_of_order", "odometry_restarts", "backend_failed",
                          "publish_failed"})
      status_.count(c, 0);
  }
  const fact::app::Log& log() const { return log_; }
  fact::app::Status& status() { return status_; }
  AttitudeBuffer& attitudes() { return attitudes_; }

  void on_frame(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    auto m = std::make_shared<fact::frame_t>();
    if (!fact::app::decode(rbuf, channel, m.get(), &status_, log_)) return;
    std::string counter;
    if (std::string e = fact::app::frame_message_error(*m, o_.common.drone_id, &counter); !e.empty()) {
      reject(counter, e);
      return;
    }
    pending_.push_back(Pending{m, fact::app::monotonic_us()});
    while (pending_.size() > 4) {  // never fall behind: the oldest goes with what we have
      run(pending_.front());
      pending_.pop_front();
    }
    flush(false);
  }

  void on_odometry(const lcm::ReceiveBuffer* rbuf, const std::string& channel) {
    fact::odometry_t m;
    if (!fact::app::decode(rbuf, channel, &m, &status_, log_)) return;
    if (m.drone_id != o_.common.drone_id) {
      reject("wrong_drone_id", "odometry from drone " + std::to_string(m.drone_id) + " on " + channel);
      return;
    }
    for (const auto& [field, v] : {std::pair<const char*, double>{"yaw", m.yaw}, {"pitch", m.pitch}, {"roll", m.roll}})
      if (!std::isfinite(v)) {
        reject("bad_odometry", "odometry seq " + std::to_string(m.seq) + ": " + field + " = " + std::to_string(v) +
                                   " (must be finite)");
        return;
      }
    const int64_t newest = attitudes_.newest();
    const std::string at = "odometry seq " + std::to_string(m.seq) + " utime " + std::to_string(m.utime);
    switch (attitudes_.push(Attitude{m.utime, m.yaw, m.pitch, m.roll}, m.seq)) {
      case AttitudeBuffer::Push::accepted: break;
      case AttitudeBuffer::Push::restarted:
        status_.count("odometry_restarts");
        log_.event(at + ": the odometry restarted (seq or clock went back, or a new clock): attitude buffer reset");
        break;
      case AttitudeBuffer::Push::not_later:
        reject("odometry_out_of_order", at + " is not later than the newest sample " + std::to_string(newest));
        return;
      case AttitudeBuffer::Push::too_far_ahead:
        reject("odometry_out_of_order", at + " is more than 10 s after the newest sample " + std::to_string(newest));
        return;
    }
    flush(false);
  }

  // Runs the pending frames whose odometry is there, or whose wait is over (all with force).
  // The wait runs on the monotonic clock (a wall-clock step back held every frame behind it).
  void flush(bool force) {
    const int64_t now = fact::app::monotonic_us();
    while (!pending_.empty()) {
      const Pending& p = pending_.front();
      const bool ready = attitudes_.newest() >= p.frame->utime;
      const bool waited = now - p.arrival >= static_cast<int64_t>(o_.odometry_wait_ms * 1000);
      if (!ready && !waited && !force) break;
      run(p);
      pending_.pop_front();
    }
    status_.tick(fact::app::now_us());
  }

  // One frame from any source, with its attitude (or none).
  void process(const fact::FrameView& view, int64_t seq, const std::optional<Attitude>& att) {
    status_.count("frames");
    if (std::string e = fact::frame_error(view); !e.empty()) {
      reject(e.find("depth_mm: all") != std::string::npos ? "no_depth" : "bad_frame",
             "frame seq " + std::to_string(seq) + ": " + e);
      return;
    }
    fact::detections_t out;
    if (std::string e = pipeline_.process(view, seq, att, &out); !e.empty()) {
      reject("backend_failed", "frame seq " + std::to_string(seq) + ": " + e);
      return;
    }
    if (lcm_->publish(o_.output_channel, &out) != 0) {
      reject("publish_failed", "publish on " + o_.output_channel + " failed");
      return;
    }
    status_.count("published");
    status_.count("detections", out.count);
    if (status_.value("published") == 1) {
      log_.event("first detections published on " + o_.output_channel + " (" + std::to_string(out.count) +
                 " confirmed tracks)");
      status_.set_state("detecting");
    }
    for (const fact::detection_t& d : out.detections)
      if (logged_tracks_.insert(d.track_id).second) {
        std::ostringstream s;
        s << "track " << d.track_id << " confirmed at frame seq " << seq << ": range " << d.range << " m, vector ("
          << d.vector[0] << ", " << d.vector[1] << ", " << d.vector[2] << ")";
        log_.event(s.str());
      }
  }

  void reject(const std::string& counter, const std::string& line) {
    status_.note(line);
    fact::app::count_and_log(status_, log_, counter, line);
  }

  std::string summary() const {
    std::ostringstream s;
    s << "frames " << status_.value("frames") << ", published " << status_.value("published") << ", detections "
      << status_.value("detections");
    for (const char* c : {"bad_frame", "size_mismatch", "bad_intrinsics", "no_depth", "wrong_drone_id", "undecodable",
                          "stale_odometry", "no_odometry", "bad_odometry", "odometry_out_of_order",
                          "odometry_restarts", "backend_failed", "publish_failed"})
      if (status_.value(c) > 0) s << ", " << c << " " << status_.value(c);
    return s.str();
  }

 private:
  struct Pending {
    std::shared_ptr<fact::frame_t> frame;
    int64_t arrival;  // µs (monotonic_us: the odometry wait survives wall-clock steps)
  };

  void run(const Pending& p) {
    const fact::frame_t& m = *p.frame;
    depth_.resize(m.depth_mm.size());
    for (size_t i = 0; i < depth_.size(); ++i)  // int16 on the wire; negative is not a depth
      depth_[i] = m.depth_mm[i] > 0 ? static_cast<uint16_t>(m.depth_mm[i]) : 0;
    fact::FrameView view;
    view.utime = m.utime;
    view.intrinsics = fact::CameraIntrinsics{m.width, m.height, m.fx, m.fy, m.cx, m.cy};
    view.gray = m.gray.data();
    view.depth_mm = depth_.data();
    std::optional<Attitude> att;
    if (attitudes_.empty()) {
      status_.count("no_odometry");
    } else {
      if (attitudes_.newest() < m.utime) status_.count("stale_odometry");
      att = attitudes_.at(m.utime);
    }
    process(view, m.seq, att);
  }

  lcm::LCM* lcm_;
  const Options& o_;
  fact::app::Log log_;
  fact::app::Status status_;
  Pipeline pipeline_;
  AttitudeBuffer attitudes_;
  std::deque<Pending> pending_;
  std::vector<uint16_t> depth_;
  std::set<int> logged_tracks_;
};

// --png-dir: "" or why the directory cannot be used.
struct PngPair {
  int64_t utime;
  fs::path gray, depth;
};
std::string read_png_dir(const std::string& dir, fact::CameraIntrinsics* k, std::vector<PngPair>* pairs,
                         AttitudeBuffer* attitudes, int* odometry_lines) {
  std::error_code ec;
  if (!fs::is_directory(dir, ec)) return "--png-dir " + dir + ": not a directory";
  const fs::path ipath = fs::path(dir) / "intrinsics.json";
  try {
    *k = fact::read_intrinsics_file(ipath.string());
  } catch (const fact::FormatError& e) {
    return e.what();
  }
  std::map<int64_t, PngPair> found;
  for (const auto& entry : fs::directory_iterator(dir, ec)) {
    const std::string name = entry.path().filename().string();
    std::string stem;
    int64_t t = 0;
    const fact::PngFrameName kind = fact::png_frame_name(name, &stem, &t);
    if (kind == fact::PngFrameName::other) continue;
    if (kind == fact::PngFrameName::time_too_large)
      return (fs::path(dir) / name).string() + ": the time " + stem + " µs does not fit in 64 bits";
    found[t] = PngPair{t, entry.path(), fs::path(dir) / (stem + "_depth.png")};
  }
  for (auto& [t, p] : found) pairs->push_back(p);
  const fs::path tum = fs::path(dir) / "odometry.tum";
  std::ifstream odo(tum);
  std::string line;
  *odometry_lines = 0;
  std::optional<double> previous_yaw;
  while (odo && std::getline(odo, line)) {
    fact::PoseLine pl;
    std::string error;
    if (fact::parse_pose_line(line, &pl, &error) != fact::PoseLineKind::sample) continue;
    fact::Attitude a;
    if (!fact::attitude_from_quaternion(pl.qx, pl.qy, pl.qz, pl.qw, &a).empty()) continue;
    // Unwrapped, as the buffer interpolates linearly (a frame between samples at +3.1 and −3.1 rad
    // got a yaw near 0, and its rotation homography lost the track).
    if (previous_yaw) a.yaw = *previous_yaw + std::remainder(a.yaw - *previous_yaw, 2 * M_PI);
    previous_yaw = a.yaw;
    if (attitudes->push_recorded(Attitude{static_cast<int64_t>(std::llround(pl.time * 1e6)), a.yaw, a.pitch, a.roll}))
      ++*odometry_lines;
  }
  return "";
}

int run_png_dir(App& app, const Options& o) {
  fact::CameraIntrinsics k;
  std::vector<PngPair> pairs;
  int odometry_lines = 0;
  if (std::string e = read_png_dir(o.png_dir, &k, &pairs, &app.attitudes(), &odometry_lines); !e.empty()) {
    std::cerr << kApp << ": error: " << e << "\n";
    return 2;
  }
  app.log().event("png dir " + o.png_dir + ": " + std::to_string(pairs.size()) + " gray frames, " +
                  std::to_string(odometry_lines) + " odometry samples, " + std::to_string(k.width) + " x " +
                  std::to_string(k.height) + ", publishing on " + o.output_channel);
  app.status().set_state("reading " + o.png_dir);
  int64_t seq = 0;
  for (const PngPair& p : pairs) {
    if (fact::app::stop_requested()) break;
    const std::string where = "frame " + std::to_string(p.utime);
    cv::Mat gray = cv::imread(p.gray.string(), cv::IMREAD_UNCHANGED);
    cv::Mat depth = cv::imread(p.depth.string(), cv::IMREAD_UNCHANGED);
    app.status().count("frames", 0);
    if (gray.empty() || depth.empty()) {
      app.reject("bad_frame", where + ": cannot read " + (gray.empty() ? p.gray : p.depth).string());
    } else if (gray.type() != CV_8UC1 || depth.type() != CV_16UC1) {
      app.reject("bad_frame", where + ": expected 8-bit gray and 16-bit depth, got types " +
                                  std::to_string(gray.type()) + " and " + std::to_string(depth.type()));
    } else if (gray.size() != depth.size()) {
      app.reject("size_mismatch", where + ": gray " + std::to_string(gray.cols) + " x " + std::to_string(gray.rows) +
                                      ", depth " + std::to_string(depth.cols) + " x " + std::to_string(depth.rows));
    } else if (gray.cols != k.width || gray.rows != k.height) {
      app.reject("bad_frame", where + ": " + std::to_string(gray.cols) + " x " + std::to_string(gray.rows) +
                                  ", intrinsics.json says " + std::to_string(k.width) + " x " + std::to_string(k.height));
    } else {
      fact::FrameView view;
      view.utime = p.utime;
      view.intrinsics = k;
      view.gray = gray.ptr<uint8_t>();
      view.depth_mm = depth.ptr<uint16_t>();
      std::optional<Attitude> att;
      if (!app.attitudes().empty()) att = app.attitudes().at(p.utime);
      app.process(view, seq, att);
    }
    ++seq;
    app.status().tick(fact::app::now_us());
  }
  app.log().event("end of " + o.png_dir + ": " + app.summary());
  app.status().set_state("finished");
  app.status().publish(fact::app::now_us());
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  Options options;
  options.common.drone_id = 0;
  CLI::App cli{"Detects and tracks other drones in gray + depth frames (LCM fact::frame_t, or a directory of\n"
               "PNG pairs) and publishes fact::detections_t with body-frame vectors.",
               kApp};
  add_flags(cli, options);
  cli.get_formatter()->column_width(34);
  if (const int code = fact::app::parse_flags(cli, argc, argv, kApp, [&] { check(options); }); code >= 0) return code;
  const fact::app::Log log(kApp, options.common.drone_id);
  cv::setNumThreads(1);  // one core per detector: N drones' detectors share a machine in simulation
  std::unique_ptr<fact::YoloDetector> yolo;
  if (options.backend == "yolo") {
    fact::YoloOptions yo;
    yo.input_size = options.yolo_size;
    if (std::string e = fact::yolo_options_error(yo); !e.empty()) {
      std::cerr << kApp << ": error: --yolo-size: " << e << "\n";
      return 2;
    }
    std::string error;
    yolo = fact::YoloDetector::load(options.model, yo, &error);
    if (!yolo) {
      std::cerr << kApp << ": error: --model " << options.model << ": " << error << "\n";
      return 2;
    }
    log.event("yolo model " + options.model + " loaded (" + std::to_string(yolo->num_classes()) + " classes)");
  }
  lcm::LCM lcm(options.common.lcm_url);
  if (!fact::app::lcm_opened(lcm, options.common.lcm_url, log)) return 1;
  fact::app::install_stop_handler();
  App app(&lcm, options, std::move(yolo));
  if (!options.png_dir.empty()) return run_png_dir(app, options);
  if (!fact::app::start_clock(lcm, options.common, log)) return 1;
  std::unique_ptr<lcm::LCM> frames_lcm;  // only with --frames-url
  if (!options.frames_url.empty()) {
    frames_lcm = std::make_unique<lcm::LCM>(options.frames_url);
    if (!frames_lcm->good()) {
      log.event("error: cannot open LCM for frames at --frames-url " + options.frames_url);
      return 1;
    }
  }
  (frames_lcm ? *frames_lcm : lcm).subscribe(options.frames_channel, &App::on_frame, &app)->setQueueCapacity(8);
  lcm.subscribe(options.odometry_channel, &App::on_odometry, &app)->setQueueCapacity(1000);
  log.event("backend " + options.backend + ", frames on " + options.frames_channel +
            (frames_lcm ? " at " + options.frames_url : std::string()) + ", odometry on " +
            options.odometry_channel + ", publishing on " + options.output_channel);
  app.status().set_state("waiting for frames on " + options.frames_channel);
  app.status().publish(fact::app::now_us());
  const int code = fact::app::run_loop(lcm, 10, [&](int64_t) { app.flush(false); }, {frames_lcm.get()});
  app.flush(true);
  log.event(std::string(code == 0 ? "stopped: " : "stopped (LCM failed): ") + app.summary());
  app.status().set_state(code == 0 ? "stopped" : "LCM failed");
  app.status().publish(fact::app::now_us());
  return code;
}
