// fact-bench-detector: the detector and tracker against the simulator's ground truth.
//
// Episodes: a world (the built-in default world, or --world) with --drones drones hovering at the
// world's random takeoff spots, each at a random height, spinning in place at --spin-rate with a
// random phase, with a small roll/pitch wobble (as a hovering drone has). Every drone's camera is
// rendered by fact_sim at --camera-rate for one full turn; every frame goes through the detector
// (fact::detect_depth), the range/vector step (fact::target_vector) and one tracker per viewer
// (fact::Tracker, rotation-compensated with the true attitude change, as VIO would give it).
//
// Ground truth comes from fact::sim::ground_truth (the renderer's object ids) and is read here only.
//   - Eligible target ("unoccluded, within R"): centre in the image, the centre-to-centre line of
//     sight clear of obstacles and other drones, at least one visible pixel, range ≤ --eligible-range,
//     and not truncated (its visible pixels do not touch the image border: a drone partly out of
//     view has no knowable size, so the detector scores it low; such targets are reported apart).
//   - A detection matches a target when the boxes (grown to at least 8 px a side) overlap with
//     IoU ≥ 0.2, one-to-one by our Hungarian; it is true when it matches any visible target (also
//     occluded or far ones), false otherwise.
//   - Operating point: detections scoring at least --min-score (the tracker's high_score) count;
//     the precision at every score is reported too.
//   - Recall per range bin: matched eligible targets / eligible targets. Precision per bin (by the
//     detection's estimated range): true / all detections. Range error |r̂ − r|/r and bearing error
//     ∠(v̂, v) on matched eligible targets (v in the gravity-aligned body frame).
//   - Tracking (CLEAR MOT, IDF1) over the confirmed tracks matched in each frame against the
//     eligible targets; predictions matching a visible non-eligible target are ignored.
//     MOTA = 1 − (FN + FP + IDSW)/GT; IDF1 = 2·IDTP/(GT + predictions), IDTP from the best
//     one-to-one track ↔ target assignment over each viewer's sequence.
//   - Timing: detector and tracker per 640×480 frame (one core), and renderer frames per second
//     at 424×240 with 4 drones.
//
// Writes <out>/detector.csv (per range bin) and <out>/detector_summary.txt; prints both.
#include "fact/camera.h"
#include "fact/detector.h"
#include "fact/hungarian.h"
#include "fact/sim_render.h"
#include "fact/sim_world.h"
#include "fact/tracker.h"
#include "fact/world_io.h"
#include "common/cli_checks.h"
#include "results_file.h"
#include "stats.h"

#include <CLI/CLI.hpp>
#include <Eigen/Core>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

struct Options {
  int episodes = 12;
  int drones = 4;
  uint64_t seed = 1;
  std::string world_file;       // "" = the built-in default world
  double spin_rate = 0.8;       // rad/s
  double camera_rate = 15;      // Hz
  double wobble = 0.04;         // rad, amplitude of the roll/pitch wobble
  double eligible_range = 6.0;  // m
  double bin = 1.0;             // m, range bin width
  double max_range = 10.0;      // m, last bin edge
  int render_frames = 240;      // frames timed for the renderer figure
  std::string out_dir = "bench/results";
  bool list_false = false;      // print every false detection (episode, viewer, frame, box, range)
  // Operating point: detections scoring at least this count (the tracker's high_score: what can
  // start a track); lower-scoring ones only continue tracks (ByteTrack's second stage).
  float min_score = fact::TrackerOptions{}.high_score;
};

using fact::bench::median;
// (the table's p90 and p95 are the order statistics nearest to q·(n − 1))
double percentile(std::vector<double> v, double p) { return fact::bench::nearest_order_statistic(std::move(v), p); }

// A box grown about its centre to at least `side` px per side (far drones are a few px tall).
fact::BoxDetection grown(fact::BoxDetection b, float side) {
  if (b.w < side) b.u -= (side - b.w) / 2, b.w = side;
  if (b.h < side) b.v -= (side - b.h) / 2, b.h = side;
  return b;
}

// One-to-one matching of boxes a[i] to b[j] with IoU ≥ min_iou: match[i] = j or −1.
std::vector<int> match_boxes(const std::vector<fact::BoxDetection>& a, const std::vector<fact::BoxDetection>& b,
                             double min_iou = 0.2) {
  std::vector<int> match(a.size(), -1);
  if (a.empty() || b.empty()) return match;
  Eigen::MatrixXd cost(a.size(), b.size());  // 1 − IoU, rows a, columns b
  for (size_t i = 0; i < a.size(); ++i)
    for (size_t j = 0; j < b.size(); ++j) cost(i, j) = 1.0 - fact::box_iou(grown(a[i], 8), grown(b[j], 8));
  const fact::Assignment r = fact::solve_assignment(cost, 1.0 - min_iou);
  for (size_t i = 0; i < a.size(); ++i) match[i] = r.row_to_col[i];
  return match;
}

struct Bin {
  int eligible = 0, found = 0;       // recall
  int detections = 0, truthful = 0;  // precision (by estimated range)
  std::vector<double> range_err, bearing_err;
};

struct Tracking {
  long gt = 0, fn = 0, fp = 0, idsw = 0, predictions = 0, idtp = 0;
};

struct Counts {
  std::vector<Bin> bins;
  // Within --eligible-range, counted as each target or detection is seen: recall and errors by the
  // true range, precision by the estimated range. (Summing the 1 m bins whose upper edge was within
  // the range dropped the last part bin: --eligible-range 7.5 gave the recall within 7 m.)
  Bin within;
  long all_detections = 0, all_true = 0;  // every score, eligible range (by estimated range)
  long truncated = 0, truncated_found = 0;  // unoccluded targets cut by the image border, any score
  Tracking mot;
  std::vector<double> detect_ms, track_ms;
  long frames = 0;
};

int bin_of(double r, const Options& o) {
  const int b = static_cast<int>(std::floor(r / o.bin));
  const int n = static_cast<int>(std::ceil(o.max_range / o.bin));
  return std::clamp(b, 0, n - 1);
}

// Best one-to-one assignment total of a (targets × tracks) co-occurrence count table.
long best_assignment_total(const std::map<std::pair<int, int>, long>& counts) {
  if (counts.empty()) return 0;
  std::map<int, int> rows, cols;
  for (const auto& [k, n] : counts) {
    rows.emplace(k.first, static_cast<int>(rows.size()));
    cols.emplace(k.second, static_cast<int>(cols.size()));
  }
  long top = 0;
  for (const auto& [k, n] : counts) top = std::max(top, n);
  Eigen::MatrixXd cost = Eigen::MatrixXd::Constant(rows.size(), cols.size(), static_cast<double>(top));
  for (const auto& [k, n] : counts) cost(rows[k.first], cols[k.second]) = static_cast<double>(top - n);
  const fact::Assignment r = fact::solve_assignment(cost, static_cast<double>(top));
  long total = 0;
  for (const auto& [k, n] : counts)
    if (r.row_to_col[rows[k.first]] == cols[k.second]) total += n;
  return total;
}

fact::sim::World episode_world(const Options& o, int episode) {
  const uint64_t seed = o.seed * 1000003ULL + static_cast<uint64_t>(episode);
  if (o.world_file.empty()) return fact::sim::default_world(o.drones, seed);
  fact::sim::World w = fact::read_world_file(o.world_file);
  if (w.drone_config.random_start) {
    w.drone_config.count = o.drones;
    if (std::string e = fact::sim::place_random_starts(&w, seed); !e.empty()) throw std::runtime_error(e);
  }
  return w;
}

// One episode: every drone spins once; each viewer has its own tracker.
void run_episode(const Options& o, int episode, const fact::DepthNoise& noise, Counts* c) {
  const fact::sim::World world = episode_world(o, episode);
  const int n = static_cast<int>(world.starts.size());
  std::mt19937_64 rng(o.seed * 7919ULL + static_cast<uint64_t>(episode));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::vector<fact::sim::DronePose> base(n);
  std::vector<double> phase(n), wobble_phase(n);
  for (int i = 0; i < n; ++i) {
    base[i].position = world.starts[i].position;
    base[i].position.z() = world.drone_config.height_min +
                           unit(rng) * (world.drone_config.height_max - world.drone_config.height_min);
    phase[i] = 2 * M_PI * unit(rng);
    wobble_phase[i] = 2 * M_PI * unit(rng);
  }
  const fact::CameraIntrinsics k = fact::d430_640x480();
  const fact::CameraExtrinsics extrinsics;
  fact::sim::RenderOptions ro;
  ro.noise = noise;
  fact::sim::Renderer renderer(world, k, extrinsics, ro, o.seed + static_cast<uint64_t>(episode));
  fact::SegmentationOptions so;
  so.noise = noise;
  const fact::RangeOptions range_options;
  std::vector<fact::Tracker> trackers(n);
  std::vector<std::map<int, int>> last_track(n);             // per viewer: target → last matched track id
  std::vector<std::map<std::pair<int, int>, long>> pairs(n);  // per viewer: (target, track) → frames
  const int frames = static_cast<int>(std::ceil(2 * M_PI / o.spin_rate * o.camera_rate));
  std::vector<fact::sim::DronePose> poses(n), previous(n);
  fact::sim::RenderedFrame frame;
  for (int f = 0; f < frames; ++f) {
    const double t = f / o.camera_rate;
    for (int i = 0; i < n; ++i) {
      poses[i] = base[i];
      poses[i].yaw = std::remainder(phase[i] + o.spin_rate * t, 2 * M_PI);
      poses[i].roll = o.wobble * std::sin(2.1 * t + wobble_phase[i]);
      poses[i].pitch = o.wobble * std::cos(1.7 * t + wobble_phase[i]);
    }
    for (int v = 0; v < n; ++v) {
      renderer.render(poses, v, &frame);
      const fact::FrameView view = frame.view(static_cast<int64_t>(t * 1e6));
      const std::vector<fact::sim::TargetTruth> truth =
          fact::sim::ground_truth(world, renderer.body(), k, extrinsics, poses, v, &frame);

      auto t0 = Clock::now();
      const std::vector<fact::BoxDetection> dets = fact::detect_depth(view, so);
      c->detect_ms.push_back(ms_since(t0));
      Eigen::Matrix3d H = Eigen::Matrix3d::Identity();
      if (f > 0)
        H = fact::rotation_homography(k, fact::camera_rotation(previous[v].yaw, previous[v].pitch, previous[v].roll,
                                                               poses[v].yaw, poses[v].pitch, poses[v].roll,
                                                               extrinsics));
      t0 = Clock::now();
      trackers[v].update(dets, H);
      c->track_ms.push_back(ms_since(t0));
      ++c->frames;

      // Detection quality.
      std::vector<fact::BoxDetection> visible;  // visible targets' boxes, and which truth each is
      std::vector<int> visible_truth;
      for (size_t j = 0; j < truth.size(); ++j)
        if (truth[j].visible_pixels > 0) visible.push_back(truth[j].visible_box), visible_truth.push_back(static_cast<int>(j));
      // Truncated: the drone's visible pixels touch the image border (part of it is out of view).
      auto truncated = [&](const fact::sim::TargetTruth& tt) {
        return tt.u_min <= 0 || tt.v_min <= 0 || tt.u_max >= k.width - 1 || tt.v_max >= k.height - 1;
      };
      // Unoccluded and in full view, at any range (the per-bin curves); eligible: also within range.
      auto unoccluded = [&](const fact::sim::TargetTruth& tt) {
        return tt.center_in_image && tt.line_of_sight && tt.visible_pixels > 0 && !truncated(tt);
      };
      auto eligible = [&](const fact::sim::TargetTruth& tt) { return unoccluded(tt) && tt.range <= o.eligible_range; };
      const std::vector<int> m = match_boxes(dets, visible);
      std::vector<bool> found(truth.size(), false), found_any(truth.size(), false);
      for (size_t d = 0; d < dets.size(); ++d) {
        const fact::TargetVector tv =
            fact::target_vector(view, dets[d], extrinsics, poses[v].roll, poses[v].pitch, range_options);
        const double r_hat = tv.valid ? tv.range : o.max_range;
        if (r_hat <= o.eligible_range) ++c->all_detections, c->all_true += m[d] >= 0;
        if (m[d] >= 0) found_any[visible_truth[m[d]]] = true;
        if (dets[d].score < o.min_score) continue;
        Bin& b = c->bins[bin_of(r_hat, o)];
        ++b.detections;
        const bool within_range = r_hat <= o.eligible_range;
        c->within.detections += within_range;
        if (m[d] < 0) {
          if (o.list_false) {
            std::ostringstream fp;
            fp << "false detection: episode " << episode << " viewer " << v << " frame " << f << " box ("
               << dets[d].u << ", " << dets[d].v << ", " << dets[d].w << " x " << dets[d].h << ") score "
               << dets[d].score << " range " << r_hat << " m;";
            for (const fact::sim::TargetTruth& tt : truth)
              if (tt.visible_pixels > 0)
                fp << " drone " << tt.index << " at (" << tt.visible_box.u << ", " << tt.visible_box.v << ", "
                   << tt.visible_box.w << " x " << tt.visible_box.h << ") " << tt.range << " m";
            std::cerr << fp.str() << "\n";
          }
          continue;
        }
        ++b.truthful;
        c->within.truthful += within_range;
        const fact::sim::TargetTruth& tt = truth[visible_truth[m[d]]];
        found[visible_truth[m[d]]] = true;
        if (!unoccluded(tt) || !tv.valid) continue;
        Bin& tb = c->bins[bin_of(tt.range, o)];
        const double range_err = std::abs(tv.range - tt.range) / tt.range;
        const double cosang = tv.vector_g.normalized().dot(tt.vector_g.normalized());
        const double bearing_err = std::acos(std::clamp(cosang, -1.0, 1.0)) * 180 / M_PI;
        tb.range_err.push_back(range_err);
        tb.bearing_err.push_back(bearing_err);
        if (tt.range <= o.eligible_range) {
          c->within.range_err.push_back(range_err);
          c->within.bearing_err.push_back(bearing_err);
        }
      }
      for (size_t j = 0; j < truth.size(); ++j) {
        const fact::sim::TargetTruth& tt = truth[j];
        if (tt.center_in_image && tt.line_of_sight && tt.visible_pixels > 0 && tt.range <= o.eligible_range &&
            truncated(tt))
          ++c->truncated, c->truncated_found += found_any[j];
        if (!unoccluded(truth[j])) continue;
        Bin& b = c->bins[bin_of(truth[j].range, o)];
        ++b.eligible;
        if (found[j]) ++b.found;
        if (eligible(truth[j])) ++c->within.eligible, c->within.found += found[j];
      }

      // Tracking quality (confirmed tracks matched this frame).
      std::vector<fact::BoxDetection> preds;
      std::vector<int> pred_ids;
      for (const fact::Track* tr : trackers[v].confirmed_matched()) preds.push_back(tr->box), pred_ids.push_back(tr->id);
      const std::vector<int> pm = match_boxes(preds, visible);
      for (size_t j = 0; j < truth.size(); ++j)
        if (eligible(truth[j])) ++c->mot.gt;
      std::vector<bool> gt_matched(truth.size(), false);
      for (size_t p = 0; p < preds.size(); ++p) {
        if (pm[p] < 0) {
          ++c->mot.fp, ++c->mot.predictions;
          continue;
        }
        const int j = visible_truth[pm[p]];
        if (!eligible(truth[j])) continue;  // a visible but occluded or far drone: ignored
        ++c->mot.predictions;
        gt_matched[j] = true;
        const int target = truth[j].index;
        auto it = last_track[v].find(target);
        if (it != last_track[v].end() && it->second != pred_ids[p]) ++c->mot.idsw;
        last_track[v][target] = pred_ids[p];
        ++pairs[v][{target, pred_ids[p]}];
      }
      for (size_t j = 0; j < truth.size(); ++j)
        if (eligible(truth[j]) && !gt_matched[j]) ++c->mot.fn;
    }
    previous = poses;
  }
  for (int v = 0; v < n; ++v) c->mot.idtp += best_assignment_total(pairs[v]);
}

// Renderer speed: 424×240, 4 drones, every drone's camera in turn, one core.
double renderer_fps(const Options& o, const fact::DepthNoise& noise) {
  const fact::sim::World world = fact::sim::default_world(4, o.seed);
  fact::sim::RenderOptions ro;
  ro.noise = noise;
  fact::sim::Renderer renderer(world, fact::d430_424x240(), fact::CameraExtrinsics(), ro, o.seed);
  std::vector<fact::sim::DronePose> poses(4);
  for (int i = 0; i < 4; ++i) poses[i].position = world.starts[i].position + Eigen::Vector3d(0, 0, 1.5);
  fact::sim::RenderedFrame frame;
  const auto t0 = Clock::now();
  for (int f = 0; f < o.render_frames; ++f) {
    for (int i = 0; i < 4; ++i) poses[i].yaw = 0.05 * f + i;
    renderer.render(poses, f % 4, &frame);
  }
  return o.render_frames / (ms_since(t0) / 1000.0);
}

std::string fmt(double v, int digits = 3) {
  if (!std::isfinite(v)) return "nan";
  std::ostringstream s;
  s.setf(std::ios::fixed);
  s.precision(digits);
  s << v;
  return s.str();
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App cli{"fact-bench-detector: the depth detector and tracker against the simulator's ground truth"};
  cli.add_option("--episodes", o.episodes, "Episodes (one full spin of every drone each)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--drones", o.drones, "Drones per episode (>= 2)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--seed", o.seed, "Seed of the worlds, heights and phases")->capture_default_str()
      ->check(fact::app::uint64_text());
  cli.add_option("--world", o.world_file, "A fact-world-v1 file (default: the built-in default world)");
  cli.add_option("--spin-rate", o.spin_rate, "rad/s")->capture_default_str();
  cli.add_option("--camera-rate", o.camera_rate, "Hz")->capture_default_str();
  cli.add_option("--wobble", o.wobble, "rad, roll/pitch wobble amplitude")->capture_default_str();
  cli.add_option("--eligible-range", o.eligible_range, "m, eligible targets are at most this far")->capture_default_str();
  cli.add_option("--render-frames", o.render_frames, "Frames timed for the renderer figure")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--out-dir", o.out_dir, "Where detector.csv and detector_summary.txt go")->capture_default_str();
  cli.add_option("--min-score", o.min_score, "Operating point: detections scoring at least this count")
      ->capture_default_str();
  cli.add_flag("--list-false", o.list_false, "Print every false detection with the visible drones' boxes");
  bool quick = false;
  cli.add_flag("--quick", quick, "2 episodes, 60 renderer frames (a smoke run)");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  if (quick) o.episodes = 2, o.render_frames = 60;
  if (o.episodes < 1 || o.drones < 2 || o.render_frames < 1 || !(o.spin_rate > 0) || !(o.camera_rate > 0) ||
      !(o.eligible_range > 0)) {
    std::cerr << "fact-bench-detector: --episodes >= 1, --drones >= 2, --spin-rate, --camera-rate and "
                 "--eligible-range > 0 are required\n";
    return 2;
  }
  const fact::DepthNoise noise;
  Counts c;
  c.bins.resize(static_cast<size_t>(std::ceil(o.max_range / o.bin)));
  const auto start = Clock::now();
  try {
    for (int e = 0; e < o.episodes; ++e) {
      run_episode(o, e, noise, &c);
      std::cerr << "episode " << e + 1 << "/" << o.episodes << ": " << c.frames << " frames so far ("
                << fmt(ms_since(start) / 1000, 1) << " s)\n";
    }
  } catch (const std::exception& ex) {
    std::cerr << "fact-bench-detector: " << ex.what() << "\n";
    return 2;
  }
  const double fps = renderer_fps(o, noise);

  std::ostringstream csv;
  csv << "range_lo_m,range_hi_m,eligible,found,recall,detections,true_detections,precision,"
         "median_range_error_pct,median_bearing_error_deg\n";
  const Bin& within = c.within;
  for (size_t b = 0; b < c.bins.size(); ++b) {
    const Bin& x = c.bins[b];
    const double lo = b * o.bin, hi = (b + 1) * o.bin;
    csv << fmt(lo, 1) << "," << fmt(hi, 1) << "," << x.eligible << "," << x.found << ","
        << fmt(x.eligible ? double(x.found) / x.eligible : NAN, 4) << "," << x.detections << "," << x.truthful << ","
        << fmt(x.detections ? double(x.truthful) / x.detections : NAN, 4) << "," << fmt(100 * median(x.range_err), 3)
        << "," << fmt(median(x.bearing_err), 3) << "\n";
  }
  const Tracking& t = c.mot;
  const double mota = t.gt ? 1.0 - double(t.fn + t.fp + t.idsw) / t.gt : NAN;
  const double idf1 = (t.gt + t.predictions) ? 2.0 * t.idtp / double(t.gt + t.predictions) : NAN;
  std::ostringstream s;
  s << "fact-bench-detector: " << o.episodes << " episodes x " << o.drones << " drones, " << c.frames
    << " frames at 640x480, seed " << o.seed << "\n"
    << "within " << fmt(o.eligible_range, 1) << " m, unoccluded: recall " << fmt(double(within.found) / within.eligible, 4)
    << " (" << within.found << "/" << within.eligible << "), precision "
    << fmt(double(within.truthful) / within.detections, 4) << " (" << within.truthful << "/" << within.detections
    << ") at scores >= " << fmt(o.min_score, 2) << "; precision at every score "
    << fmt(double(c.all_true) / c.all_detections, 4) << " (" << c.all_true << "/" << c.all_detections << ")\n"
    << "truncated by the image border (not in the recall above): found at any score "
    << fmt(double(c.truncated_found) / c.truncated, 4) << " (" << c.truncated_found << "/" << c.truncated << ")\n"
    << "range error: median " << fmt(100 * median(within.range_err), 2) << " % of range (p90 "
    << fmt(100 * percentile(within.range_err, 0.9), 2) << " %)\n"
    << "bearing error: median " << fmt(median(within.bearing_err), 3) << " deg (p90 "
    << fmt(percentile(within.bearing_err, 0.9), 3) << " deg)\n"
    << "tracking: MOTA " << fmt(mota, 4) << ", IDF1 " << fmt(idf1, 4) << " (GT " << t.gt << ", FN " << t.fn << ", FP "
    << t.fp << ", ID switches " << t.idsw << ")\n"
    << "time per 640x480 frame: detector median " << fmt(median(c.detect_ms), 3) << " ms (p95 "
    << fmt(percentile(c.detect_ms, 0.95), 3) << "), tracker median " << fmt(median(c.track_ms), 4) << " ms (p95 "
    << fmt(percentile(c.track_ms, 0.95), 4) << ")\n"
    << "renderer: " << fmt(fps, 1) << " frames/s at 424x240 with 4 drones (one core)\n";
  try {
    fact::bench::write_results_file(o.out_dir + "/detector.csv", csv.str());
    fact::bench::write_results_file(o.out_dir + "/detector_summary.txt", s.str());
  } catch (const std::exception& ex) {
    std::cerr << "fact-bench-detector: " << ex.what() << "\n";
    return 1;
  }
  std::cout << s.str();
  std::cout << "wrote " << o.out_dir << "/detector.csv and " << o.out_dir << "/detector_summary.txt\n";
  return 0;
}
