// The fact-world-v1 world file (library fact_io): a room, obstacles, drone starts and VIO drift,
// parsed into fact::sim::World. Errors throw fact::FormatError (fact/json_io.h) naming the JSON
// path and the value, e.g. `obstacles[1].radius: expected a number > 0, got -0.3`.
//
//   {"format": "fact-world-v1",
//    "room": {"size": [sx, sy, sz]},                     m; x ∈ [−sx/2, sx/2], y likewise, z ∈ [0, sz]
//    "obstacles": [{"type": "box", "center": [x,y,z], "size": [a,b,c], "yaw": 0},   yaw optional
//                  {"type": "cylinder", "base": [x,y,z], "radius": r, "height": h}, vertical
//                  {"type": "polytope", "vertices": [[x,y,z], ...]}],               convex hull
//    "drones": {"count": 4, "ids": [0,1,2,3],           ids optional (default 0 … count−1)
//               "start": "random" | [{"position": [x,y,z], "yaw": θ}, ...],
//               "seed": 7, "height": [1.0, 2.5], "min_separation": 1.0, "clearance": 0.4},
//    "vio": {"drift_position": 0.01, "drift_yaw": 0.002}}                           optional
//
// Rules: "format" and "room" are required; "obstacles" (default none), "drones" (default 4 at
// random starts), "vio" (default drift) and a top-level "comment" (ignored) are optional; any
// other key anywhere is an error naming it; a key repeated in one object is an error; numbers
// are finite; sizes, radius, height > 0; every obstacle point and start inside the room; "count"
// 1 … 64; with an explicit start list its length is the count ("count" and "ids", when given,
// must match it); ids unique and >= 0; "height" [min, max] with 0 < min <= max <= room height.
// A "random" start is not placed here: call fact::sim::place_random_starts (fact_sim).
#pragma once

#include "fact/json_io.h"
#include "fact/sim_world.h"

#include <string>

namespace fact {

sim::World world_from_json(const std::string& text);
// Reads and parses a file; an unreadable file throws FormatError naming the path.
sim::World read_world_file(const std::string& path);

}  // namespace fact
