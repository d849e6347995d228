// JSON encodings of the estimator's data (library fact_io; fact_core itself has no I/O):
//   fact-rounds-v1   observation rounds (fact::Rounds)
//   fact-result-v1   an estimate (fact::Estimate)
//   fact-truth-v1    a generated scenario's ground truth (fact::Truth), for evaluation only
// Decoders never guess: anything malformed throws FormatError whose message names the JSON
// path and the value, e.g. `rounds[1].drones["3"].observations[0].vector: expected 3 numbers, got 2`.
//
// Common rules (all three formats):
//   - The document is an object whose "format" is exactly the format's name. Unknown top-level
//     keys are accepted (a producer may add metadata); every nested object is closed: an
//     unknown key there is an error naming it.
//   - A key repeated within one object is an error (JSON parsers differ on which value wins).
//   - Numbers are finite (a number too large for a double, e.g. 1e999, is an error). Doubles are
//     written with the shortest text that reads back to the same bits, so encode → decode is exact.
//   - Drone ids are integers >= 0 (−1 means "none" elsewhere). As object keys they are written in
//     canonical decimal ("7", never "07"). A vector is an array of exactly 3 numbers.
//   - Encoders write 2-space indented JSON with a trailing newline, a flat value (a vector, an
//     observation, a drone's pose) on one line. They throw FormatError (naming the field) rather
//     than write something their decoder would reject (NaN, duplicate ids, …).
//
// fact-rounds-v1:
//   {"format": "fact-rounds-v1",
//    "drones": [ids...],                 unique; decoded and encoded in ascending order
//    "rounds": [{"index": k,
//                "drones": {"<id>": {"position": [x,y,z], "yaw": r,
//                                    "observations": [{"odom_position": [x,y,z], "odom_yaw": r,
//                                                      "vector": [x,y,z]}, ...]}}}]}
//   Every key of a round's "drones" must be listed in "drones"; "observations" may be empty.
//   The semantics (2 … kMaxDrones drones, non-zero vectors, "index" strictly increasing: the
//   last round is the latest, …) are validate_rounds' job. Every reader refuses a document
//   nested deeper than 64 levels and a key repeated within one object.
//
// fact-result-v1:
//   {"format": "fact-result-v1", "mode": "paper|complex|associated|auto",
//    "status": "certified|ambiguous|invalid_input", "reason": "...",
//    "reference": id (or -1), "rounds_used": K,
//    "drones": [{"id": i, "yaw": r, "position": [x,y,z], "resolved": bool}],   Estimate order
//    "unresolved": [ids],
//    "certificate": {"objective": v, "dual_objective": v, "bound_error": v, "gap": v, "min_eig": v,
//                    "rank": n},
//    "timing_us": {"<stage>": microseconds, ...}}                          Estimate order
//   Values that do not exist are null and read back as NaN: the certificate's five numbers
//   (e.g. an invalid_input result has none), and the yaw and position components of a drone
//   with "resolved": false. A resolved drone's pose must be finite. "bound_error" (what
//   rounding can have raised dual_objective by) may be absent, as in files written before it
//   was added, and then reads as NaN.
//
// fact-truth-v1:
//   {"format": "fact-truth-v1",
//    "drones": [{"id": i, "frame_yaw": r, "frame_origin": [x,y,z]}, ...],   Truth::ids order
//    "rounds": [{"drones": {"<id>": {"position": [x,y,z], "targets": [t, ...],
//                                    "frame_yaw": r, "frame_origin": [x,y,z]}}}, ...],
//    "obstacles": [{"center": [x,y,z], "radius": r, "height": h}, ...]}
//   frame_yaw / frame_origin: the yaw and origin of the drone's odometry frame in the world.
//   rounds[k].drones["<id>"]: that drone's world centre in round k, and for each of its
//   observations in round k of the matching fact-rounds-v1 file (same k, same id, same order)
//   the id it detected, or -1 for a false positive. Every round lists every drone. Its optional
//   frame_yaw / frame_origin are the drone's drifted odometry frame in that round (Truth::
//   drifted_yaw / drifted_origin, what an estimate from the rounds up to k describes: a drifting
//   scenario's result is checked against them); given for every drone of every round or for none
//   (files written before them have none). Obstacles
//   are vertical cylinders standing on z = 0 (world, metres).
#pragma once

#include "fact/camera.h"
#include "fact/estimator.h"
#include "fact/rounds.h"
#include "fact/simgen.h"

#include <cstdint>
#include <stdexcept>
#include <string>

namespace fact {

struct FormatError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

Rounds rounds_from_json(const std::string& text);
std::string rounds_to_json(const Rounds& rounds);

Estimate estimate_from_json(const std::string& text);
std::string estimate_to_json(const Estimate& estimate);

Truth truth_from_json(const std::string& text);
std::string truth_to_json(const Truth& truth);

// fact-simgen's input files, read with the same checks (paths in errors, duplicate keys, depth):
// a JSON array of [x, y, z] positions (m), and a JSON array of obstacles as in the truth file
// ({"center": [x, y, z], "radius": r, "height": h}, m).
std::vector<Eigen::Vector3d> positions_from_json(const std::string& text);
std::vector<Obstacle> obstacles_from_json(const std::string& text);

// A camera's intrinsics.json (fact-detector's and fact-preflight's --png-dir): an object with
// "width" and "height" (whole numbers 1 … 8192, px) and "fx", "fy", "cx", "cy" (px), usable by
// intrinsics_error's checks; other keys are ignored. Throws FormatError naming the key and value.
CameraIntrinsics intrinsics_from_json(const std::string& text);
// The same from the file at `path` (a regular file of at most 1 MiB); FormatErrors name the path.
CameraIntrinsics read_intrinsics_file(const std::string& path);

// A file name in such a --png-dir: "<utime>_gray.png" (utime in µs, decimal digits) is a frame's
// gray image, its depth image "<utime>_depth.png" beside it; any other name is no frame. A time
// that does not fit in 64 bits makes the directory unusable (fact-detector refuses it, and
// fact-preflight fails it).
enum class PngFrameName { other, frame, time_too_large };
PngFrameName png_frame_name(const std::string& filename, std::string* stem, int64_t* utime);

}  // namespace fact
