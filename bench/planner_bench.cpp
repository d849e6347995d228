// fact-bench-planner: the planner's safety in randomized simulated planning episodes, and its cost.
//
// One episode: a world (fact::sim::default_world: 10 × 10 × 4 m room, a box, a cylinder and a
// polytope, plus 0–3 random boxes/cylinders kept clear of the takeoff spots) with 4–8 drones at
// random takeoff spots. Every drone
//   1. takes off by the takeoff rule (plan_takeoff: a random height in [takeoff_min, takeoff_max]);
//   2. spins in place: --frames frames of its own depth camera (424 × 240, fact::sim::Renderer,
//      stereo noise on), every other drone hovering at its own takeoff height and drawn;
//   3. builds its own LocalMap from those frames, in its own odometry frame f_i, with the pixels
//      of the drones it detected removed;
//   4. plans one step (plan_step) from what it observed.
// Then all drones fly their trajectories at the same time.
//
// What the planner is given, and what is simulated:
//   - Detections: fact::sim::ground_truth's visible targets (≥ --min-pixels visible pixels within
//     --detect-range), their boxes as the detector's boxes and their vectors with noise (range
//     σ = --range-noise × range, bearing σ = --bearing-noise rad). The detector itself is
//     benchmarked elsewhere (fact-bench-detector); here it is replaced by this model, so the
//     figures are the planner's. Undetected drones stay in the depth image: obstacles of the map.
//   - Odometry: exact (no VIO drift) — the drone's pose in f_i is the simulated one.
//   - Result status per episode: none 15 %, ambiguous 35 %, not certified 40 %, certified 10 %;
//     in half of the not-certified episodes the solver's result is also given ("known": the
//     others' true positions in f_i with 3 cm noise).
//   The planner never sees the world: obstacles come only from its own map.
//
// Checks along the time-synchronised trajectories (every --dt s, takeoff and move):
//   - every pair of drones ≥ min_separation apart (centre to centre);
//   - every drone centre ≥ drone_radius from every TRUE obstacle (fact::sim::distance; for
//     polytopes a lower bound, so conservative);
//   - every drone centre inside the room shrunk by drone_radius.
//   Violations must be 0.
// Timing (one core): plan_step per call (median, p99, max), LocalMap::add_frame per 424 × 240 frame,
// LocalMap::pieces per plan, the renderer per frame.
//
// Writes <out>/planner.csv (one row per episode) and <out>/planner_summary.txt; prints the summary.
#include "fact/local_map.h"
#include "fact/planner.h"
#include "fact/sim_render.h"
#include "fact/sim_world.h"
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
#include <limits>
#include <random>
#include <sstream>
#include <string>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;
using Eigen::Vector3d;
namespace sim = fact::sim;

double ms_since(Clock::time_point t0) { return std::chrono::duration<double, std::milli>(Clock::now() - t0).count(); }

struct Options {
  int episodes = 1000;
  uint64_t seed = 1;
  int frames = 6;
  int min_pixels = 20;
  double detect_range = 7.0;
  double range_noise = 0.02;
  double bearing_noise = 0.01;
  double dt = 0.01;
  std::string out_dir = "bench/results";
  int first_episode = 0;
  bool verbose = false;
};

// (linear between order statistics)
double percentile(std::vector<double> v, double q) { return fact::bench::quantile(std::move(v), q); }

// Adds 0–3 random obstacles clear of every takeoff spot's vertical line (by `clear` m).
void add_random_obstacles(sim::World* w, std::mt19937_64& gen, double clear) {
  std::uniform_int_distribution<int> count(0, 3);
  std::uniform_real_distribution<double> u01(0, 1);
  const Vector3d lo = sim::room_min(*w), hi = sim::room_max(*w);
  const int n = count(gen);
  for (int k = 0, tries = 0; k < n && tries < 200; ++tries) {
    const Vector3d c(lo.x() + 0.5 + u01(gen) * (hi.x() - lo.x() - 1), lo.y() + 0.5 + u01(gen) * (hi.y() - lo.y() - 1), 0);
    sim::Obstacle o;
    if (u01(gen) < 0.5) {
      const Vector3d size(0.3 + u01(gen) * 1.2, 0.3 + u01(gen) * 1.2, 0.8 + u01(gen) * 2.5);
      o = sim::make_box(Vector3d(c.x(), c.y(), size.z() / 2), size, u01(gen) * M_PI);
    } else {
      o = sim::make_cylinder(c, 0.15 + u01(gen) * 0.4, 0.8 + u01(gen) * 2.5);
    }
    bool ok = true;
    for (const sim::DroneStart& s : w->starts)
      for (double z = 0; z <= 3.0 && ok; z += 0.1) ok = sim::distance(o, s.position + Vector3d(0, 0, z)) >= clear;
    if (!ok) continue;
    w->obstacles.push_back(o);
    ++k;
  }
}

struct EpisodeResult {
  int drones = 0, obstacles = 0;
  fact::ResultStatus status = fact::ResultStatus::none;
  int moves = 0, holds = 0, fallbacks = 0, rejected = 0;
  int sep_violations = 0, obstacle_violations = 0, room_violations = 0;
  double min_pair = std::numeric_limits<double>::infinity();
  double min_pair_move = std::numeric_limits<double>::infinity();  // move phase only
  double min_obstacle = std::numeric_limits<double>::infinity();
  double min_wall = std::numeric_limits<double>::infinity();
  double mean_move = 0;
  int observed_total = 0, pieces_total = 0;
  std::string first_violation;
};

}  // namespace

int main(int argc, char** argv) {
  Options o;
  CLI::App cli{"fact-bench-planner: safety of the planner in randomized simulated planning episodes"};
  cli.add_option("--episodes", o.episodes, "Episodes (4-8 drones each)")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--seed", o.seed, "Seed of the worlds, statuses and noise")->capture_default_str()
      ->check(fact::app::uint64_text());
  cli.add_option("--frames", o.frames, "Frames per spin (424x240) for each drone's map")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--min-pixels", o.min_pixels, "Visible pixels for a drone to count as detected")->capture_default_str()
      ->check(fact::app::decimal_integer());
  cli.add_option("--detect-range", o.detect_range, "m, farther drones are not detected")->capture_default_str();
  cli.add_option("--range-noise", o.range_noise, "Detection range noise, fraction of the range (1 sigma)")->capture_default_str();
  cli.add_option("--bearing-noise", o.bearing_noise, "Detection bearing noise, rad (1 sigma)")->capture_default_str();
  cli.add_option("--dt", o.dt, "s, time step of the synchronised flight check")->capture_default_str();
  cli.add_option("--out-dir", o.out_dir, "Where planner.csv and planner_summary.txt go")->capture_default_str();
  // (a negative index ran episodes of 3 … 0 drones: n = 4 + ep % 5)
  cli.add_option("--first-episode", o.first_episode, "Index of the first episode (to rerun one; the CSV's episode column)")
      ->capture_default_str()->check(fact::app::decimal_integer())->check(CLI::Range(0, 1 << 30));
  cli.add_flag("--verbose", o.verbose, "Print every drone's pose, detections and plan");
  bool quick = false;
  cli.add_flag("--quick", quick, "50 episodes (a smoke run)");
  if (const int code = fact::app::parse_command_line(cli, argc, argv); code >= 0) return code;
  if (quick) o.episodes = 50;
  if (o.episodes < 1 || o.frames < 1 || !(o.dt > 0)) {
    std::cerr << "fact-bench-planner: --episodes, --frames must be >= 1 and --dt > 0\n";
    return 2;
  }
  const fact::PlannerParams params;
  const fact::CameraIntrinsics K = fact::d430_424x240();
  const fact::CameraExtrinsics E;
  const sim::DroneBody body;
  std::vector<double> step_ms, map_ms, pieces_ms, render_ms;
  std::vector<EpisodeResult> results;
  results.reserve(o.episodes);
  const auto t_start = Clock::now();

  for (int ep = o.first_episode; ep < o.first_episode + o.episodes; ++ep) {
    const uint64_t ep_seed = o.seed * 1000003ULL + static_cast<uint64_t>(ep);
    std::mt19937_64 gen(ep_seed * 7919ULL + 13);
    std::uniform_real_distribution<double> u01(0, 1);
    std::normal_distribution<double> n01(0, 1);
    const int n = 4 + ep % 5;
    sim::World world = sim::default_world(n, ep_seed);
    add_random_obstacles(&world, gen, params.drone_radius + 0.3);
    EpisodeResult res;
    res.drones = n;
    res.obstacles = static_cast<int>(world.obstacles.size());
    const double r_status = u01(gen);
    res.status = r_status < 0.15   ? fact::ResultStatus::none
                 : r_status < 0.50 ? fact::ResultStatus::ambiguous
                 : r_status < 0.90 ? fact::ResultStatus::not_certified
                                   : fact::ResultStatus::certified;
    const bool give_known = res.status == fact::ResultStatus::not_certified && u01(gen) < 0.5;

    // f_i ↔ world: p_w = start_i + R_i · p_f (R_i = R_z(start yaw)).
    std::vector<Eigen::Matrix3d> R(n);
    std::vector<Vector3d> S(n);
    for (int i = 0; i < n; ++i) {
      R[i] = fact::body_attitude(world.starts[i].yaw, 0, 0);
      S[i] = world.starts[i].position;
    }
    auto to_world = [&](int i, const Vector3d& p_f) { return Vector3d(S[i] + R[i] * p_f); };

    // 1. Takeoff.
    std::vector<fact::Plan> takeoff(n);
    std::vector<fact::PlannerRng> rng(n);
    for (int i = 0; i < n; ++i) {
      takeoff[i] = fact::plan_takeoff(Vector3d::Zero(), 0.0, params, fact::PlannerRng{ep_seed * 131 + i + 1});
      rng[i] = takeoff[i].rng;
    }
    std::vector<Vector3d> hover_f(n);
    for (int i = 0; i < n; ++i) hover_f[i] = takeoff[i].target;

    // 2–3. Spin: frames of every drone's camera, the others hovering; own map, own detections.
    sim::Renderer renderer(world, K, E, {}, ep_seed + 99, body);
    sim::RenderedFrame frame;
    std::vector<fact::PlannerInput> inputs(n);
    std::vector<std::vector<fact::ObstacleBox>> pieces(n);
    for (int i = 0; i < n; ++i) {
      fact::LocalMap map;
      std::vector<sim::DronePose> poses(n);
      for (int j = 0; j < n; ++j) {
        poses[j].position = to_world(j, hover_f[j]);
        poses[j].yaw = world.starts[j].yaw;
      }
      fact::PlannerInput& in = inputs[i];
      in.position = hover_f[i];
      in.yaw = 0;
      for (int k = 0; k < o.frames; ++k) {
        const double yaw_f = 2 * M_PI * k / o.frames;
        poses[i].yaw = world.starts[i].yaw + yaw_f;
        auto t0 = Clock::now();
        renderer.render(poses, i, &frame);
        render_ms.push_back(ms_since(t0));
        const auto truth = sim::ground_truth(world, body, K, E, poses, i, &frame);
        std::vector<fact::BoxDetection> boxes;
        for (const sim::TargetTruth& t : truth) {
          if (t.visible_pixels < o.min_pixels || t.range > o.detect_range) continue;
          boxes.push_back(t.visible_box);
          // The detection's vector with range and bearing noise (gravity-aligned body frame).
          const double r = t.range * (1 + o.range_noise * n01(gen));
          Vector3d dir = t.vector_g.normalized();
          Vector3d a = dir.unitOrthogonal(), b = dir.cross(a);
          dir = (dir + o.bearing_noise * (n01(gen) * a + n01(gen) * b)).normalized();
          in.observed.push_back(fact::observed_position(hover_f[i], yaw_f, r * dir));
        }
        fact::MapPose mp;
        mp.position = hover_f[i];
        mp.yaw = yaw_f;
        t0 = Clock::now();
        const std::string err = map.add_frame(frame.view(k), E, mp, boxes);
        map_ms.push_back(ms_since(t0));
        if (!err.empty()) {
          std::cerr << "add_frame: " << err << "\n";
          return 1;
        }
      }
      in.yaw = 2 * M_PI * (o.frames - 1) / o.frames;  // where the spin's last frame left it
      in.status = res.status;
      in.rng = rng[i];
      if (give_known)
        for (int j = 0; j < n; ++j)
          if (j != i) {
            const Vector3d p_w = poses[j].position + Vector3d(0.03 * n01(gen), 0.03 * n01(gen), 0.03 * n01(gen));
            in.known.push_back(R[i].transpose() * (p_w - S[i]));
          }
      const auto t0 = Clock::now();
      pieces[i] = map.pieces();
      pieces_ms.push_back(ms_since(t0));
      res.observed_total += static_cast<int>(in.observed.size());
      res.pieces_total += static_cast<int>(pieces[i].size());
    }

    // 4. Plan.
    std::vector<fact::Plan> plans(n);
    for (int i = 0; i < n; ++i) {
      const auto t0 = Clock::now();
      plans[i] = fact::plan_step(inputs[i], pieces[i], params);
      step_ms.push_back(ms_since(t0));
      switch (plans[i].kind) {
        case fact::PlanKind::move: ++res.moves; res.mean_move += (plans[i].target - inputs[i].position).norm(); break;
        case fact::PlanKind::hold: ++res.holds; break;
        case fact::PlanKind::hover_fallback: ++res.fallbacks; break;
        case fact::PlanKind::rejected: ++res.rejected; break;
      }
    }
    if (res.moves) res.mean_move /= res.moves;
    if (o.verbose)
      for (int i = 0; i < n; ++i) {
        const Vector3d pw = to_world(i, hover_f[i]);
        std::fprintf(stderr, "drone %d at (%.2f, %.2f, %.2f): %zu observed, %s: %s\n", i, pw.x(), pw.y(), pw.z(),
                     inputs[i].observed.size(), fact::to_string(plans[i].kind), plans[i].reason.c_str());
        for (const Vector3d& q : inputs[i].observed) {
          const Vector3d qw = to_world(i, q);
          std::fprintf(stderr, "    sees (%.2f, %.2f, %.2f)\n", qw.x(), qw.y(), qw.z());
        }
      }

    // 5. Fly everything at once (takeoff phase, then the move phase) and check against the truth.
    const Vector3d room_lo = sim::room_min(world), room_hi = sim::room_max(world);
    // The takeoff starts on the floor, so its room check leaves the floor out.
    auto check_phase = [&](const std::vector<const fact::Trajectory*>& trs, const char* phase, bool floor_ok) {
      double T = 0;
      for (const auto* tr : trs) T = std::max(T, tr->duration());
      std::vector<Vector3d> q(n);
      for (double t = 0;; t += o.dt) {
        const double tt = std::min(t, T);
        for (int i = 0; i < n; ++i) q[i] = to_world(i, trs[i]->sample(tt).position);
        for (int i = 0; i < n; ++i) {
          for (int j = i + 1; j < n; ++j) {
            const double d = (q[i] - q[j]).norm();
            res.min_pair = std::min(res.min_pair, d);
            if (!floor_ok) res.min_pair_move = std::min(res.min_pair_move, d);
            if (d < params.min_separation) {
              ++res.sep_violations;
              if (res.first_violation.empty()) {
                std::ostringstream s;
                s << phase << " t=" << tt << " drones " << i << "," << j << " d=" << d << " (" << to_string(plans[i].kind)
                  << ": " << plans[i].reason << " | " << to_string(plans[j].kind) << ": " << plans[j].reason << ")";
                res.first_violation = s.str();
              }
            }
          }
          for (size_t k = 0; k < world.obstacles.size(); ++k) {
            const double d = sim::distance(world.obstacles[k], q[i]);
            res.min_obstacle = std::min(res.min_obstacle, d);
            if (d < params.drone_radius) {
              ++res.obstacle_violations;
              if (res.first_violation.empty()) {
                std::ostringstream s;
                s << phase << " t=" << tt << " drone " << i << " obstacle " << k << " d=" << d << " (" << plans[i].reason << ")";
                res.first_violation = s.str();
              }
            }
          }
          const double wall = std::min({q[i].x() - room_lo.x(), room_hi.x() - q[i].x(), q[i].y() - room_lo.y(),
                                        room_hi.y() - q[i].y(), floor_ok ? 1e9 : q[i].z() - room_lo.z(), room_hi.z() - q[i].z()});
          res.min_wall = std::min(res.min_wall, wall);
          if (wall < params.drone_radius) {
            ++res.room_violations;
            if (res.first_violation.empty())
              res.first_violation = std::string(phase) + " drone " + std::to_string(i) + " leaves the room (" + plans[i].reason + ")";
          }
        }
        if (t >= T) break;
      }
    };
    std::vector<const fact::Trajectory*> trs(n);
    for (int i = 0; i < n; ++i) trs[i] = &takeoff[i].trajectory;
    check_phase(trs, "takeoff", true);
    for (int i = 0; i < n; ++i) trs[i] = &plans[i].trajectory;
    check_phase(trs, "move", false);
    if (!res.first_violation.empty()) std::cerr << "episode " << ep << ": " << res.first_violation << "\n";
    results.push_back(res);
    if ((ep + 1) % 100 == 0)
      std::cerr << "  " << (ep + 1) << " / " << o.episodes << " episodes, " << static_cast<int>(ms_since(t_start) / 1000) << " s\n";
  }

  // Outputs.
  std::ostringstream csv;
  csv << "episode,drones,obstacles,status,moves,holds,fallbacks,rejected,observed,pieces,mean_move_m,"
         "min_pair_distance_m,min_pair_distance_move_m,min_obstacle_distance_m,min_wall_distance_m,separation_violations,"
         "obstacle_violations,room_violations\n";
  int moves = 0, holds = 0, fallbacks = 0, rejected = 0, sep = 0, obst = 0, room = 0, plans_total = 0;
  int episodes_with_violation = 0;
  double min_pair = 1e9, min_pair_move = 1e9, min_obst = 1e9, min_wall = 1e9, move_sum = 0;
  for (size_t e = 0; e < results.size(); ++e) {
    const EpisodeResult& r = results[e];
    char buf[512];
    // episode: the index the run used (--first-episode + e), which reruns it alone
    std::snprintf(buf, sizeof buf, "%d,%d,%d,%s,%d,%d,%d,%d,%d,%d,%.3f,%.4f,%.4f,%.4f,%.4f,%d,%d,%d\n",
                  o.first_episode + static_cast<int>(e), r.drones, r.obstacles,
                  fact::to_string(r.status), r.moves, r.holds, r.fallbacks, r.rejected, r.observed_total, r.pieces_total,
                  r.mean_move, r.min_pair, r.min_pair_move, r.min_obstacle, r.min_wall, r.sep_violations, r.obstacle_violations,
                  r.room_violations);
    csv << buf;
    moves += r.moves;
    holds += r.holds;
    fallbacks += r.fallbacks;
    rejected += r.rejected;
    plans_total += r.drones;
    sep += r.sep_violations;
    obst += r.obstacle_violations;
    room += r.room_violations;
    episodes_with_violation += (r.sep_violations + r.obstacle_violations + r.room_violations) > 0;
    min_pair = std::min(min_pair, r.min_pair);
    min_pair_move = std::min(min_pair_move, r.min_pair_move);
    min_obst = std::min(min_obst, r.min_obstacle);
    min_wall = std::min(min_wall, r.min_wall);
    move_sum += r.mean_move * r.moves;
  }
  std::ostringstream s;
  char line[256];
  s << "fact-bench-planner: " << o.episodes << " episodes (4-8 drones, default_world + 0-3 random obstacles), seed "
    << o.seed << ", " << o.frames << " frames 424x240 per spin\n";
  s << "  detections: fact_sim ground truth (>= " << o.min_pixels << " visible px, <= " << o.detect_range
    << " m), range noise " << o.range_noise * 100 << " %, bearing noise " << o.bearing_noise
    << " rad; odometry exact; the detector is benchmarked separately\n";
  s << "safety (checked every " << o.dt << " s along the synchronised takeoff and move trajectories):\n";
  std::snprintf(line, sizeof line, "  separation violations (< %.2f m)      %d\n", params.min_separation, sep);
  s << line;
  std::snprintf(line, sizeof line, "  obstacle violations (< %.2f m, true)  %d\n", params.drone_radius, obst);
  s << line;
  std::snprintf(line, sizeof line, "  room violations                       %d\n", room);
  s << line;
  std::snprintf(line, sizeof line, "  episodes with any violation           %d / %d\n", episodes_with_violation, o.episodes);
  s << line;
  std::snprintf(line, sizeof line,
                "  closest pair %.3f m (move phase %.3f m; takeoff spots are placed >= min_separation apart),\n"
                "  closest obstacle %.3f m, closest wall %.3f m\n",
                min_pair, min_pair_move, min_obst, min_wall);
  s << line;
  std::snprintf(line, sizeof line, "plans: %d (moves %d, holds %d, hover fallbacks %d, rejected %d); mean move %.2f m\n",
                plans_total, moves, holds, fallbacks, rejected, moves ? move_sum / moves : 0.0);
  s << line;
  std::snprintf(line, sizeof line, "planner step (plan_step): median %.3f ms, p99 %.3f ms, max %.3f ms\n",
                percentile(step_ms, 0.5), percentile(step_ms, 0.99), percentile(step_ms, 1.0));
  s << line;
  std::snprintf(line, sizeof line, "map update (add_frame, 424x240): median %.3f ms, p99 %.3f ms per frame\n",
                percentile(map_ms, 0.5), percentile(map_ms, 0.99));
  s << line;
  std::snprintf(line, sizeof line, "map pieces (pieces()): median %.3f ms, p99 %.3f ms per plan\n", percentile(pieces_ms, 0.5),
                percentile(pieces_ms, 0.99));
  s << line;
  std::snprintf(line, sizeof line, "renderer (context): median %.2f ms per frame; total %.1f s\n", percentile(render_ms, 0.5),
                ms_since(t_start) / 1000);
  s << line;
  try {
    fact::bench::write_results_file(o.out_dir + "/planner.csv", csv.str());
    fact::bench::write_results_file(o.out_dir + "/planner_summary.txt", s.str());
  } catch (const std::exception& e) {
    std::cerr << "fact-bench-planner: " << e.what() << "\n";
    return 1;
  }
  std::cout << s.str();
  std::cout << "wrote " << o.out_dir << "/planner.csv and " << o.out_dir << "/planner_summary.txt\n";
  return (sep + obst + room) == 0 ? 0 : 3;
}
