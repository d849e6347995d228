// fact-run-report: judges a recorded simulated run (an lcm-logger log of the swarm bus) against
// the simulator's ground truth. Evaluation only: it is the one app that reads FACT_TRUTH.
//
// It takes each drone's first certified result (FACT_RESULT_<id>; the last result when none is
// certified), checks that the drones agree, and compares the result with the true odometry frames
// (evaluate.h: the effective frames of the drifting VIO, averaged over the latest round before
// the result, which is what the estimator describes; also over the whole observation window and
// at the result's time, for reference). Prints a table, writes a top-down PNG and a JSON summary.
// Exit codes: 0 certified, the drones agree and every frame is within the bounds; 3 not
// certified; 4 certified but outside the bounds or the drones disagree (certified-wrong);
// 2 bad flags, an unreadable or damaged log, no truth, or a --json / --png that cannot be written
// (each is written whole or not at all: fact::write_file_atomically keeps an earlier file).
#include "common/cli_checks.h"
#include "common/app.h"
#include "common/log_reader.h"
#include "evaluate.h"
#include "fact/file_write.h"
#include "fact/odometry_t.hpp"
#include "fact/sim_clock_t.hpp"
#include "fact/sim_world.h"
#include "fact/swarm_result_t.hpp"
#include "fact/swarm_rounds_t.hpp"
#include "fact/truth_t.hpp"
#include "fact/world_io.h"

#include <CLI/CLI.hpp>
#include <Eigen/Geometry>
#include <lcm/lcm-cpp.hpp>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <set>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace {

using Eigen::Vector3d;
using fact::report::Frame;
constexpr const char* kApp = "fact-run-report";

struct Options {
  std::string log, world, png, json;
  double yaw_bound = 0.05, position_bound = 0.20;  // rad, m
  double edge_gate = 0.6;                           // m: an observation names the true drone this near
  std::string truth_channel = "FACT_TRUTH", vio_channel = "FACT_VIO_RAW", result_channel = "FACT_RESULT",
              rounds_channel = "FACT_SWARM_ROUNDS", clock_channel = "FACT_SIM_CLOCK";
};

// A result with the simulated time it was published at (the newest clock tick before it).
struct TimedResult {
  fact::swarm_result_t msg;
  int64_t at = 0;  // sim µs
};

// Everything the report needs from the log.
struct RunLog {
  std::vector<fact::truth_t> truth;
  std::map<int, std::vector<fact::odometry_t>> vio;          // drone → raw VIO, in log order
  std::map<int, std::vector<TimedResult>> results;           // publishing drone → its results
  std::optional<fact::swarm_rounds_t> rounds;                // the newest complete rounds seen
  int64_t first_clock = -1, last_clock = -1;                 // sim µs
  std::map<std::string, int> undecodable;                    // channel (or "<channel> (NaN)") → count
};

bool starts_with(const std::string& s, const std::string& p) { return s.rfind(p, 0) == 0; }

bool finite_truth(const fact::truth_t& t) {
  for (int k = 0; k < t.num_drones; ++k) {
    if (!std::isfinite(t.yaw[k])) return false;
    for (int j = 0; j < 3; ++j)
      if (!std::isfinite(t.position[k][j])) return false;
  }
  return true;
}

// Writes the report whole or not at all (fact::write_file_atomically: a failed write keeps an
// earlier report); false, after saying why on stderr, when it cannot.
bool write_json(const std::string& path, const nlohmann::json& j) {
  const std::string why = fact::write_file_atomically(path, j.dump(2) + "\n");
  if (why.empty()) return true;
  std::cerr << kApp << ": error: cannot write the report: " << why << "\n";
  return false;
}

// Reads the log; false (with the reason) when it cannot be read at all.
bool read_log(const Options& o, RunLog* run, std::string* why) {
  fact::app::LogDecoder dec(kApp);
  int64_t clock = -1;
  *why = fact::app::for_each_log_event(o.log, kApp, [&](const lcm::LogEvent& e) {
    const std::string& ch = e.channel;
    if (ch == o.clock_channel) {
      fact::sim_clock_t m;
      if (dec.decode(e, &m)) {
        clock = m.utime;
        if (run->first_clock < 0) run->first_clock = m.utime;
        run->last_clock = m.utime;
      }
    } else if (ch == o.truth_channel) {
      fact::truth_t m;
      if (dec.decode(e, &m)) {
        if (finite_truth(m)) run->truth.push_back(m);
        else dec.reject(ch + " (NaN)", "truth with a NaN field ignored");
      }
    } else if (starts_with(ch, o.vio_channel + "_")) {
      fact::odometry_t m;
      if (dec.decode(e, &m)) {
        if (std::isfinite(m.yaw) && std::isfinite(m.position[0]) && std::isfinite(m.position[1]) &&
            std::isfinite(m.position[2]))
          run->vio[m.drone_id].push_back(m);
        else dec.reject(ch + " (NaN)", "VIO odometry with a NaN position or yaw ignored");
      }
    } else if (starts_with(ch, o.result_channel + "_")) {
      fact::swarm_result_t m;
      if (dec.decode(e, &m)) run->results[m.drone_id].push_back({m, clock >= 0 ? clock : m.utime});
    } else if (starts_with(ch, o.rounds_channel + "_")) {
      fact::swarm_rounds_t m;
      if (dec.decode(e, &m) && (!run->rounds || m.complete_rounds >= run->rounds->complete_rounds)) run->rounds = m;
    }
  });
  run->undecodable = dec.undecodable();
  return why->empty();
}

// The VIO sample of drone `id` nearest to time t (nullptr if none within 50 ms).
const fact::odometry_t* vio_at(const RunLog& run, int id, int64_t t) {
  auto it = run.vio.find(id);
  if (it == run.vio.end() || it->second.empty()) return nullptr;
  const auto& v = it->second;
  auto pos = std::lower_bound(v.begin(), v.end(), t, [](const fact::odometry_t& m, int64_t x) { return m.utime < x; });
  const fact::odometry_t* best = nullptr;
  for (auto c : {pos, pos == v.begin() ? pos : pos - 1})
    if (c != v.end() && (!best || std::llabs(c->utime - t) < std::llabs(best->utime - t))) best = &*c;
  return best && std::llabs(best->utime - t) <= 50000 ? best : nullptr;
}

Vector3d vec(const double* p) { return Vector3d(p[0], p[1], p[2]); }
Vector3d vec(const std::vector<double>& p) { return Vector3d(p[0], p[1], p[2]); }

// Effective frames averaged over truth samples in [t0, t1] (every drone with VIO there).
std::map<int, Frame> effective_frames(const RunLog& run, int64_t t0, int64_t t1) {
  std::map<int, fact::report::FrameAverage> avg;
  for (const fact::truth_t& t : run.truth) {
    if (t.utime < t0 || t.utime > t1) continue;
    for (int k = 0; k < t.num_drones; ++k) {
      const fact::odometry_t* v = vio_at(run, t.drone_ids[k], t.utime);
      if (!v) continue;
      avg[t.drone_ids[k]].add(fact::report::effective_frame(vec(t.position[k]), t.yaw[k], vec(v->position), v->yaw));
    }
  }
  std::map<int, Frame> out;
  for (const auto& [id, a] : avg)
    if (!a.empty()) out[id] = a.mean();
  return out;
}

// The first time (sim µs) a drone is airborne (true z > 0.3 m): the observation window's start.
int64_t first_airborne(const RunLog& run) {
  for (const fact::truth_t& t : run.truth)
    for (int k = 0; k < t.num_drones; ++k)
      if (t.position[k][2] > 0.3) return t.utime;
  return run.truth.empty() ? 0 : run.truth.front().utime;
}

// The latest round complete at time t (sim µs): [the previous round's first close, its last
// close], from the round packets' close times; from the first takeoff for round 0. Gives the
// round number, or −1 (and the whole observation window) when the log has no complete round.
int latest_round_window(const RunLog& run, int64_t t, int64_t* t0, int64_t* t1) {
  *t0 = first_airborne(run);
  *t1 = t;
  if (!run.rounds) return -1;
  struct Closes {
    int64_t first = INT64_MAX, last = INT64_MIN;  // the drones' first and last close time (sim µs)
    int packets = 0;
  };
  std::map<int, Closes> closes;  // by round
  for (const fact::round_packet_t& p : run.rounds->packets) {
    Closes& c = closes[p.round];
    c.first = std::min(c.first, p.utime);
    c.last = std::max(c.last, p.utime);
    ++c.packets;
  }
  int latest = -1;
  for (const auto& [round, c] : closes)
    if (c.packets == run.rounds->num_drones && c.last <= t) latest = round;
  if (latest < 0) return -1;
  if (latest > 0) *t0 = std::max(*t0, closes[latest - 1].first);
  *t1 = closes[latest].last;
  return latest;
}

const fact::truth_t* truth_at(const RunLog& run, int64_t t) {
  const fact::truth_t* best = nullptr;
  for (const fact::truth_t& x : run.truth)
    if (!best || std::llabs(x.utime - t) < std::llabs(best->utime - t)) best = &x;
  return best;
}

// Every observation of the complete rounds, placed in the world through the observer's effective
// frame and named by the nearest true drone at the round's close.
std::vector<fact::report::Sighting> sightings(const RunLog& run, const std::map<int, Frame>& frames, double gate) {
  std::vector<fact::report::Sighting> out;
  if (!run.rounds) return out;
  for (const fact::round_packet_t& p : run.rounds->packets) {
    auto f = frames.find(p.drone_id);
    const fact::truth_t* t = truth_at(run, p.utime);
    if (f == frames.end() || !t) continue;
    std::map<int, Vector3d> positions;
    for (int k = 0; k < t->num_drones; ++k) positions[t->drone_ids[k]] = vec(t->position[k]);
    const Eigen::Matrix3d R = Eigen::AngleAxisd(f->second.yaw, Vector3d::UnitZ()).toRotationMatrix();
    for (const fact::observation_t& ob : p.observations) {
      const Eigen::Matrix3d Ro = Eigen::AngleAxisd(ob.odom_yaw, Vector3d::UnitZ()).toRotationMatrix();
      fact::report::Sighting s;
      s.observer = p.drone_id;
      s.round = p.round;
      s.point = R * (vec(ob.odom_position) + Ro * vec(ob.vector)) + f->second.origin;
      s.target = fact::report::nearest_drone(s.point, p.drone_id, positions, gate, &s.distance);
      out.push_back(s);
    }
  }
  return out;
}

// ---------------------------------------------------------------------------------------------- picture

struct Canvas {
  cv::Mat img;
  double scale = 1;  // px per m
  Vector3d lo = Vector3d::Zero();
  cv::Point px(double x, double y) const {
    return {static_cast<int>(std::lround(40 + (x - lo.x()) * scale)), static_cast<int>(std::lround(img.rows - 40 - (y - lo.y()) * scale))};
  }
};

const std::vector<cv::Scalar> kColours = {{200, 90, 30}, {40, 150, 40},  {30, 60, 210},  {160, 40, 160},
                                          {20, 160, 200}, {120, 120, 0}, {90, 90, 200}, {0, 110, 220}};
cv::Scalar colour(int i) { return kColours[static_cast<size_t>(i) % kColours.size()]; }

void draw_obstacle(Canvas& c, const fact::sim::Obstacle& o) {
  std::vector<cv::Point> poly;
  const cv::Scalar fill(190, 190, 190);
  if (o.kind == fact::sim::ObstacleKind::cylinder) {
    cv::circle(c.img, c.px(o.cylinder.base.x(), o.cylinder.base.y()), static_cast<int>(o.cylinder.radius * c.scale), fill, cv::FILLED);
    return;
  }
  std::vector<cv::Point2f> pts;
  if (o.kind == fact::sim::ObstacleKind::box) {
    const double cy = std::cos(o.yaw), sy = std::sin(o.yaw);
    for (auto [a, b] : {std::pair{-1, -1}, {1, -1}, {1, 1}, {-1, 1}}) {
      const double x = a * o.size.x() / 2, y = b * o.size.y() / 2;
      const cv::Point p = c.px(o.center.x() + cy * x - sy * y, o.center.y() + sy * x + cy * y);
      pts.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    }
  } else {
    for (const Vector3d& v : o.vertices) {
      const cv::Point p = c.px(v.x(), v.y());
      pts.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y));
    }
  }
  std::vector<cv::Point2f> hull;
  cv::convexHull(pts, hull);
  for (const auto& p : hull) poly.emplace_back(static_cast<int>(p.x), static_cast<int>(p.y));
  cv::fillConvexPoly(c.img, poly, fill);
}

void draw_pose(Canvas& c, const Vector3d& p, double yaw, const cv::Scalar& col, bool filled) {
  const cv::Point a = c.px(p.x(), p.y());
  cv::circle(c.img, a, 7, col, filled ? cv::FILLED : 2, cv::LINE_AA);
  cv::line(c.img, a, c.px(p.x() + 0.45 * std::cos(yaw), p.y() + 0.45 * std::sin(yaw)), col, 2, cv::LINE_AA);
}

// Top-down picture: room, obstacles, true trajectories, true and estimated final poses, edges.
bool write_png(const std::string& path, const fact::sim::World& world, const RunLog& run,
               const std::map<int, Frame>& true_frames, const fact::swarm_result_t* result,
               const std::vector<std::pair<int, int>>& edges, const std::string& title) {
  Canvas c;
  c.lo = fact::sim::room_min(world);
  const Vector3d hi = fact::sim::room_max(world);
  c.scale = 820.0 / std::max(hi.x() - c.lo.x(), hi.y() - c.lo.y());
  c.img = cv::Mat(static_cast<int>((hi.y() - c.lo.y()) * c.scale) + 110, static_cast<int>((hi.x() - c.lo.x()) * c.scale) + 80,
                  CV_8UC3, cv::Scalar(255, 255, 255));
  for (double x = std::ceil(c.lo.x()); x <= hi.x(); x += 1) cv::line(c.img, c.px(x, c.lo.y()), c.px(x, hi.y()), {235, 235, 235});
  for (double y = std::ceil(c.lo.y()); y <= hi.y(); y += 1) cv::line(c.img, c.px(c.lo.x(), y), c.px(hi.x(), y), {235, 235, 235});
  cv::rectangle(c.img, c.px(c.lo.x(), c.lo.y()), c.px(hi.x(), hi.y()), {60, 60, 60}, 2);
  for (const auto& o : world.obstacles) draw_obstacle(c, o);
  const fact::truth_t* last = run.truth.empty() ? nullptr : &run.truth.back();
  if (!last) return false;
  std::map<int, int> index;  // id → colour index
  for (int k = 0; k < last->num_drones; ++k) index[last->drone_ids[k]] = k;
  for (int k = 0; k < last->num_drones; ++k) {  // trajectories
    std::vector<cv::Point> line;
    for (const auto& t : run.truth)
      if (k < t.num_drones) line.push_back(c.px(t.position[k][0], t.position[k][1]));
    cv::polylines(c.img, line, false, colour(k), 1, cv::LINE_AA);
  }
  std::map<int, Vector3d> final_pos;
  for (int k = 0; k < last->num_drones; ++k) final_pos[last->drone_ids[k]] = vec(last->position[k]);
  for (const auto& [i, j] : edges)
    if (final_pos.count(i) && final_pos.count(j))
      cv::line(c.img, c.px(final_pos[i].x(), final_pos[i].y()), c.px(final_pos[j].x(), final_pos[j].y()), {150, 150, 150}, 1, cv::LINE_AA);
  for (int k = 0; k < last->num_drones; ++k) {
    const int id = last->drone_ids[k];
    draw_pose(c, final_pos[id], last->yaw[k], colour(k), true);
    cv::putText(c.img, std::to_string(id), c.px(final_pos[id].x() + 0.2, final_pos[id].y() + 0.2), cv::FONT_HERSHEY_SIMPLEX, 0.6,
                colour(k), 2, cv::LINE_AA);
  }
  // Estimated poses: each drone's final VIO pose mapped through its estimated frame, placed in the
  // world through the reference drone's true (window-averaged) frame.
  if (result && true_frames.count(result->reference)) {
    const Frame& ref = true_frames.at(result->reference);
    const Eigen::Matrix3d Rr = Eigen::AngleAxisd(ref.yaw, Vector3d::UnitZ()).toRotationMatrix();
    for (const auto& d : result->drones) {
      if (!d.resolved || !index.count(d.id) || !run.vio.count(d.id) || run.vio.at(d.id).empty()) continue;
      const fact::odometry_t& v = run.vio.at(d.id).back();
      const Eigen::Matrix3d Ri = Eigen::AngleAxisd(d.yaw, Vector3d::UnitZ()).toRotationMatrix();
      const Vector3d in_ref = Ri * vec(v.position) + vec(d.position);
      const Vector3d world_p = Rr * in_ref + ref.origin;
      draw_pose(c, world_p, ref.yaw + d.yaw + v.yaw, colour(index[d.id]), false);
    }
  }
  cv::putText(c.img, title, {10, 22}, cv::FONT_HERSHEY_SIMPLEX, 0.5, {0, 0, 0}, 1, cv::LINE_AA);
  cv::putText(c.img, "filled: true pose, ring: estimated pose, thin: true trajectory, grey: mutual observation, 1 m grid",
              {10, c.img.rows - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.45, {60, 60, 60}, 1, cv::LINE_AA);
  std::vector<uchar> png;  // PNG whatever the file's extension (imwrite chose the format by it)
  if (!cv::imencode(".png", c.img, png)) return false;
  const std::string why = fact::write_file_atomically(path, std::string(png.begin(), png.end()));
  if (!why.empty()) std::cerr << kApp << ": error: " << why << "\n";
  return why.empty();
}

// ---------------------------------------------------------------------------------------------- report

std::string fmt(const char* f, double a, double b = 0, double c = 0) {
  char buf[128];
  std::snprintf(buf, sizeof buf, f, a, b, c);
  return buf;
}

// The run's first simulated time (µs): the first clock tick, else the first truth sample.
double run_start_us(const RunLog& run) {
  return run.first_clock >= 0 ? static_cast<double>(run.first_clock) : static_cast<double>(run.truth.front().utime);
}

// Simulated seconds from the run's start to its last clock tick (NaN without a clock).
double sim_duration_s(const RunLog& run) {
  return run.last_clock >= 0 ? (static_cast<double>(run.last_clock) - run_start_us(run)) * 1e-6 : NAN;
}

// A figure that was not judged (no drone to judge) is null in the JSON, never a zero.
nlohmann::json judged(int drones, double value) { return drones > 0 ? nlohmann::json(value) : nlohmann::json(nullptr); }

// The run published no result at all: not certified (exit 3). The JSON says so, and the picture
// shows the true trajectories only.
int report_no_result(const Options& o, const RunLog& run, const fact::sim::World& world) {
  const std::string verdict = "NOT CERTIFIED: no result on " + o.result_channel + "_<id> in the log";
  std::printf("== %s\n", verdict.c_str());
  if (!o.json.empty()) {
    nlohmann::json j;
    j["format"] = "fact-run-report-v1";
    j["certified"] = false;
    j["correct"] = false;
    j["exit_code"] = 3;
    j["verdict"] = verdict;
    j["status"] = "no_result";
    j["drones_with_results"] = 0;
    j["time_to_certified_s"] = nullptr;
    j["sim_duration_s"] = sim_duration_s(run);  // NaN is written as null
    j["drones"] = nlohmann::json::array();
    j["undecodable"] = run.undecodable;
    if (!write_json(o.json, j)) return 2;
  }
  if (!o.png.empty() && !write_png(o.png, world, run, {}, nullptr, {}, "no result")) {
    std::cerr << kApp << ": error: cannot write the picture " << o.png << "\n";
    return 2;
  }
  return 3;
}

int run_report(const Options& o) {
  RunLog run;
  std::string why;
  if (!read_log(o, &run, &why)) {
    std::cerr << kApp << ": error: " << why << "\n";
    return 2;
  }
  if (run.truth.empty()) {
    std::cerr << kApp << ": error: no ground truth on " << o.truth_channel << " in " << o.log << "\n";
    return 2;
  }
  fact::sim::World world = fact::sim::default_world(4, 1);
  if (!o.world.empty()) {
    try {
      world = fact::read_world_file(o.world);
    } catch (const std::exception& e) {
      std::cerr << kApp << ": error: --world: " << e.what() << "\n";
      return 2;
    }
  }
  if (run.results.empty()) {
    // Results that are there but cannot be decoded are a damaged log (2), not a run that
    // published nothing (3).
    for (const auto& [channel, count] : run.undecodable)
      if (starts_with(channel, o.result_channel + "_")) {
        std::cerr << kApp << ": error: damaged log: " << count << " undecodable result(s) on " << channel
                  << " and no decodable result in " << o.log << "\n";
        return 2;
      }
    return report_no_result(o, run, world);
  }
  // Each drone's first certified result, else its last. Every drone's solver gets the same
  // complete rounds and publishes the same bytes, so the run is certified when a drone published a
  // certified result (the log may have missed another drone's copy under load) and no two
  // certified results disagree; the run's result is the last certified copy to arrive.
  std::map<int, const TimedResult*> chosen;
  int certified_drones = 0;
  for (const auto& [id, list] : run.results) {
    const TimedResult* pick = &list.back();
    for (const TimedResult& r : list)
      if (r.msg.status == "certified") {
        pick = &r;
        break;
      }
    chosen[id] = pick;
    certified_drones += pick->msg.status == "certified";
  }
  const TimedResult* result = nullptr;
  for (const auto& [id, r] : chosen)
    if (!result || (r->msg.status == "certified") > (result->msg.status == "certified") ||
        ((r->msg.status == "certified") == (result->msg.status == "certified") && r->at > result->at))
      result = r;
  const bool all_certified = certified_drones > 0;
  std::string disagreement;
  for (const auto& [id, r] : chosen) {
    if (r == result || r->msg.status != "certified" || result->msg.status != "certified") continue;
    if (r->msg.drones.size() != result->msg.drones.size() || r->msg.reference != result->msg.reference)
      disagreement = "drone " + std::to_string(id) + "'s certified result has " + std::to_string(r->msg.drones.size()) +
                     " drones and reference " + std::to_string(r->msg.reference) + ", drone " +
                     std::to_string(result->msg.drone_id) + "'s " + std::to_string(result->msg.drones.size()) +
                     " and reference " + std::to_string(result->msg.reference);
    for (size_t k = 0; k < r->msg.drones.size() && k < result->msg.drones.size(); ++k) {
      const auto &a = r->msg.drones[k], &b = result->msg.drones[k];
      if (a.id != b.id || a.resolved != b.resolved || !(std::abs(fact::report::wrap(a.yaw - b.yaw)) <= 1e-6) ||
          !((vec(a.position) - vec(b.position)).norm() <= 1e-6))
        disagreement = "drone " + std::to_string(id) + "'s certified result differs from drone " +
                       std::to_string(result->msg.drone_id) + "'s for drone " + std::to_string(a.id);
    }
  }
  const fact::swarm_result_t& res = result->msg;
  const int64_t t_result = res.utime;
  const int64_t t_window = first_airborne(run);
  const std::map<int, Frame> window = effective_frames(run, t_window, t_result);
  int64_t t_round0 = 0, t_round1 = 0;
  const int latest_round = latest_round_window(run, t_result, &t_round0, &t_round1);
  const std::map<int, Frame> in_round = effective_frames(run, t_round0, t_round1);
  const std::map<int, Frame> at_result = effective_frames(run, t_result - 60000, t_result + 60000);
  if (!window.count(res.reference) || !in_round.count(res.reference) || !at_result.count(res.reference)) {
    std::cerr << kApp << ": error: no truth and VIO of the reference drone " << res.reference << " around the result\n";
    return 2;
  }
  // errors: against the frames during the latest round (judged); errors_all: over the whole
  // observation window; errors_now: at the result's time.
  std::vector<fact::report::DroneError> errors, errors_all, errors_now;
  const auto compare_with = [&](const std::map<int, Frame>& frames, const Frame& est, int id) {
    return fact::report::compare(id, est, fact::report::relative(frames.at(res.reference), frames.at(id)));
  };
  for (const auto& d : res.drones) {
    if (!d.resolved || !window.count(d.id) || !in_round.count(d.id) || !at_result.count(d.id)) continue;
    Frame est;
    est.yaw = d.yaw;
    est.origin = vec(d.position);
    errors.push_back(compare_with(in_round, est, d.id));
    errors_all.push_back(compare_with(window, est, d.id));
    errors_now.push_back(compare_with(at_result, est, d.id));
  }
  const fact::report::ErrorSummary sum = fact::report::summarize(errors, res.reference);
  const fact::report::ErrorSummary sum_all = fact::report::summarize(errors_all, res.reference);
  const fact::report::ErrorSummary sum_now = fact::report::summarize(errors_now, res.reference);
  const auto sights = sightings(run, window, o.edge_gate);
  const auto edges = fact::report::mutual_edges(sights);
  const double t0 = run_start_us(run);
  const double time_to_result = (static_cast<double>(result->at) - t0) * 1e-6;
  const double sim_duration = sim_duration_s(run);
  // Every drone of the truth in the result, resolved and judged, each error finite and within the
  // bounds (a NaN error used to count as 0 through std::max, and a result holding only the
  // reference drone passed).
  std::set<int> truth_ids, result_ids;
  if (!run.truth.empty()) truth_ids.insert(run.truth.back().drone_ids.begin(), run.truth.back().drone_ids.end());
  for (const auto& d : res.drones) result_ids.insert(d.id);
  std::string missing;
  for (int id : truth_ids)
    if (!result_ids.count(id)) missing += (missing.empty() ? "" : ", ") + std::to_string(id);
  bool every_within = errors.size() == res.drones.size() && missing.empty();
  for (const auto& e : errors)
    every_within = every_within && e.yaw_error <= o.yaw_bound && e.position_error <= o.position_bound;  // (false for NaN)
  const bool within = every_within;
  const bool certified = all_certified && res.status == "certified";
  int code = 0;
  std::string verdict;
  if (!certified) {
    code = 3;
    verdict = "NOT CERTIFIED: " + (res.reason.empty() ? res.status : res.reason);
  } else if (!disagreement.empty()) {
    code = 4;
    verdict = "CERTIFIED BUT THE DRONES DISAGREE: " + disagreement;
  } else if (!within) {
    code = 4;
    verdict = !missing.empty()
                  ? "CERTIFIED BUT INCOMPLETE: the result leaves out drone(s) " + missing + " of the truth"
              : errors.size() != res.drones.size()
                  ? "CERTIFIED BUT WRONG: " + std::to_string(res.drones.size() - errors.size()) +
                        " drone(s) unresolved or without truth to judge them"
                  : "CERTIFIED BUT WRONG: " +
                        fmt("max yaw error %.4f rad (bound %.3f), max position error %.3f m", sum.yaw_max, o.yaw_bound,
                            sum.position_max) +
                        fmt(" (bound %.2f)", o.position_bound) +
                        (std::isfinite(sum.yaw_max) && std::isfinite(sum.position_max) ? "" : " (an error is not finite)");
  } else {
    verdict = "certified and correct (every frame within " + fmt("%.3f rad and %.2f m)", o.yaw_bound, o.position_bound);
  }

  std::printf("== result of drone %d: %s, mode %s, reference %d, rounds used %d, at %.2f s of simulated time "
              "(certified copies in the log: %d of %zu drones)\n",
              res.drone_id, res.status.c_str(), res.mode.c_str(), res.reference, res.rounds_used, time_to_result,
              certified_drones, chosen.size());
  if (latest_round >= 0)
    std::printf("   truth: the drifting VIO frames averaged over round %d, the latest before the result (%.2f to %.2f s)\n",
                latest_round, (static_cast<double>(t_round0) - t0) * 1e-6, (static_cast<double>(t_round1) - t0) * 1e-6);
  else
    std::printf("   truth: no complete round in the log; the drifting VIO frames averaged from the first takeoff (%.2f s) to the result\n",
                (static_cast<double>(t_window) - t0) * 1e-6);
  std::printf("  drone   est yaw  true yaw   yaw err (rad / deg)   est x      y      z     true x      y      z    pos err (m)\n");
  for (size_t k = 0; k < errors.size(); ++k) {
    const auto& e = errors[k];
    std::printf("  %5d  %8.4f  %8.4f   %8.4f / %6.3f   %7.3f %6.3f %6.3f   %7.3f %6.3f %6.3f   %7.3f\n", e.id, e.estimate.yaw,
                e.truth.yaw, e.yaw_error, e.yaw_error * 180 / M_PI, e.estimate.origin.x(), e.estimate.origin.y(),
                e.estimate.origin.z(), e.truth.origin.x(), e.truth.origin.y(), e.truth.origin.z(), e.position_error);
  }
  if (sum.drones == 0) {
    std::printf("   no non-reference drone resolved: errors not judged\n");
  } else {
    std::printf("   yaw MAE %.4f rad (max %.4f), position error median %.3f m (max %.3f) over the %d non-reference drones\n",
                sum.yaw_mae, sum.yaw_max, sum.position_median, sum.position_max, sum.drones);
    std::printf("   against the frames averaged from the first takeoff: yaw MAE %.4f rad, position median %.3f m\n",
                sum_all.yaw_mae, sum_all.position_median);
    std::printf("   against the frames at the result's time only: yaw MAE %.4f rad, position median %.3f m\n", sum_now.yaw_mae,
                sum_now.position_median);
  }
  std::printf("   mutual-observation edges: %zu; simulated time %.1f s\n", edges.size(), sim_duration);
  std::printf("== %s\n", verdict.c_str());

  if (!o.json.empty()) {
    nlohmann::json j;
    j["format"] = "fact-run-report-v1";
    j["certified"] = certified;
    j["correct"] = code == 0;
    j["exit_code"] = code;
    j["verdict"] = verdict;
    j["status"] = res.status;
    j["reason"] = res.reason;
    j["mode"] = res.mode;
    j["certified_copies"] = certified_drones;
    j["drones_with_results"] = chosen.size();
    j["reference"] = res.reference;
    j["rounds_used"] = res.rounds_used;
    j["time_to_certified_s"] = certified ? nlohmann::json(time_to_result) : nlohmann::json(nullptr);
    j["sim_duration_s"] = sim_duration;
    j["drones_judged"] = sum.drones;
    j["yaw_mae_rad"] = judged(sum.drones, sum.yaw_mae);
    j["yaw_max_rad"] = judged(sum.drones, sum.yaw_max);
    j["position_median_m"] = judged(sum.drones, sum.position_median);
    j["position_max_m"] = judged(sum.drones, sum.position_max);
    const auto summary_json = [&](const fact::report::ErrorSummary& x) {
      return nlohmann::json{{"yaw_mae_rad", judged(x.drones, x.yaw_mae)},
                            {"yaw_max_rad", judged(x.drones, x.yaw_max)},
                            {"position_median_m", judged(x.drones, x.position_median)},
                            {"position_max_m", judged(x.drones, x.position_max)}};
    };
    j["truth_round"] = latest_round >= 0 ? nlohmann::json(latest_round) : nlohmann::json(nullptr);
    j["whole_window"] = summary_json(sum_all);
    j["at_result"] = summary_json(sum_now);
    j["mutual_edges"] = edges;
    for (const auto& e : errors)
      j["drones"].push_back({{"id", e.id},
                             {"estimate", {{"yaw", e.estimate.yaw}, {"position", {e.estimate.origin.x(), e.estimate.origin.y(), e.estimate.origin.z()}}}},
                             {"truth", {{"yaw", e.truth.yaw}, {"position", {e.truth.origin.x(), e.truth.origin.y(), e.truth.origin.z()}}}},
                             {"yaw_error_rad", e.yaw_error},
                             {"position_error_m", e.position_error}});
    j["undecodable"] = run.undecodable;
    if (!write_json(o.json, j)) return 2;
  }
  if (!o.png.empty()) {
    const std::string title = res.status + " (" + res.mode + ")" + fmt(", %.0f rounds, %.1f s of simulated time", res.rounds_used, time_to_result) +
                              fmt(", yaw MAE %.4f rad, position median %.3f m", sum.yaw_mae, sum.position_median);
    if (!write_png(o.png, world, run, window, &res, edges, title)) {
      std::cerr << kApp << ": error: cannot write the picture " << o.png << "\n";
      return 2;
    }
  }
  return code;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App cli{"fact-run-report: judges a recorded simulated run (LCM log) against the simulator's ground truth:\n"
               "a table of estimated and true frames, a top-down PNG and a JSON summary.",
               kApp};
  cli.add_option("--log", o.log, "LCM log of the run (lcm-logger)")->required()->type_name("FILE");
  cli.add_option("--world", o.world, "fact-world-v1 world for the picture (default: the built-in world)")->type_name("FILE");
  cli.add_option("--png", o.png, "Write the top-down picture here")->type_name("FILE");
  cli.add_option("--json", o.json, "Write the summary (fact-run-report-v1) here")->type_name("FILE");
  cli.add_option("--yaw-bound", o.yaw_bound, "rad: a certified frame farther off than this is wrong")->capture_default_str();
  cli.add_option("--position-bound", o.position_bound, "m: a certified frame farther off than this is wrong")->capture_default_str();
  cli.add_option("--edge-gate", o.edge_gate, "m: an observation names the true drone this near (picture edges)")->capture_default_str();
  cli.add_option("--truth-channel", o.truth_channel)->capture_default_str();
  cli.add_option("--vio-channel", o.vio_channel, "Raw VIO channel base (+ _<id>)")->capture_default_str();
  cli.add_option("--result-channel", o.result_channel, "Result channel base (+ _<id>)")->capture_default_str();
  cli.add_option("--rounds-channel", o.rounds_channel, "Complete-rounds channel base (+ _<id>)")->capture_default_str();
  cli.add_option("--clock-channel", o.clock_channel)->capture_default_str();
  cli.footer("Exit codes: 0 certified, the drones agree and every frame within the bounds; 3 not certified;\n"
             "4 certified but outside the bounds, leaving out a drone, or the drones disagree; 2 bad flags,\n"
             "an unreadable or damaged log, no truth, or a --json / --png that cannot be written.\n"
             "A log with no result at all is not certified (3); one whose results cannot be decoded is damaged (2).");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  for (auto [name, v] : {std::pair{"--yaw-bound", o.yaw_bound}, {"--position-bound", o.position_bound}, {"--edge-gate", o.edge_gate}})
    if (!(std::isfinite(v) && v > 0)) {
      std::cerr << kApp << ": error: " << name << ": expected a number > 0, got " << v << "\n";
      return 2;
    }
  return run_report(o);
}
