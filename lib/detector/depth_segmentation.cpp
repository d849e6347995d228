// The depth-segmentation backend (fact/detector.h): depth discontinuities split the image into
// surfaces, connected components of the surfaces are candidate parts, parts of one drone at one
// depth are merged, and a merged blob is a drone when its physical size fits and it stands nearer
// than most of its surroundings.
#include "fact/detector.h"

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <vector>

namespace fact {
namespace {

// A connected component (or a merged group of them): its pixel box, pixel count and mean depth.
struct Blob {
  int u0, v0, u1, v1;  // inclusive pixel bounds
  int area;            // pixels
  double depth_sum;    // mm, over the pixels
  double z() const { return depth_sum / area / 1000.0; }  // mean depth (m)
};

// Discontinuity threshold per depth (mm → mm): edge_min + edge_sigmas·√2·scale·σ_z(z), σ_z the raw
// depth's noise (fx of the full-resolution frame), scale the working image's noise relative to it
// (see SegmentationOptions). Kept per thread and rebuilt only when its inputs change (65536 entries).
const std::vector<uint16_t>& edge_table(const SegmentationOptions& o, double fx, double scale) {
  thread_local std::vector<uint16_t> table;
  thread_local std::vector<double> key;
  const std::vector<double> now = {o.edge_min, o.edge_sigmas, o.noise.baseline, o.noise.disparity_rms, fx, scale};
  if (now == key && !table.empty()) return table;
  key = now;
  table.resize(65536);
  const double a = o.edge_sigmas * std::sqrt(2.0) * scale * depth_sigma(o.noise, fx, 1.0);  // × z² (m)
  for (int mm = 0; mm < 65536; ++mm) {
    const double z = mm / 1000.0;
    table[static_cast<size_t>(mm)] = static_cast<uint16_t>(std::min(65535.0, (o.edge_min + a * z * z) * 1000.0 + 0.5));
  }
  return table;
}

// 255 where a pixel has usable depth and no 4-neighbour is nearer than it by more than the edge
// threshold (the far side of every discontinuity is cut away, so near objects keep their pixels).
// Only the nearest neighbour of at least lo_mm needs testing: z − n grows and edge[n] shrinks as
// n gets nearer. Neighbours below lo_mm (and 0, invalid) are moved to 0xFFFF by n − lo_mm
// wrapping around, so one unsigned min finds the nearest usable one.
void surface_mask(const cv::Mat& depth, const std::vector<uint16_t>& edge, int lo_mm, int hi_mm, cv::Mat& mask) {
  const int w = depth.cols, h = depth.rows;
  mask.create(h, w, CV_8U);
  const uint16_t lo = static_cast<uint16_t>(lo_mm);
  std::vector<uint16_t> nearest(static_cast<size_t>(w));  // per column: nearest usable neighbour − lo_mm
  auto shifted = [lo](uint16_t z) { return static_cast<uint16_t>(z - lo); };
  for (int v = 0; v < h; ++v) {
    const uint16_t* row = depth.ptr<uint16_t>(v);
    const uint16_t* up = depth.ptr<uint16_t>(v > 0 ? v - 1 : v);
    const uint16_t* down = depth.ptr<uint16_t>(v + 1 < h ? v + 1 : v);
    for (int u = 0; u < w; ++u) {
      const uint16_t left = u > 0 ? row[u - 1] : row[u], right = u + 1 < w ? row[u + 1] : row[u];
      nearest[u] = std::min(std::min(shifted(up[u]), shifted(down[u])), std::min(shifted(left), shifted(right)));
    }
    uint8_t* out = mask.ptr<uint8_t>(v);
    for (int u = 0; u < w; ++u) {
      const uint16_t z = row[u];
      const int n = nearest[u] + lo_mm;  // the nearest usable neighbour (≥ 65536 when none)
      const bool cut = n < z && z - n > edge[static_cast<size_t>(n)];
      out[u] = (z >= lo_mm && z <= hi_mm && !cut) ? 255 : 0;
    }
  }
}

int find(std::vector<int>& parent, int i) {
  while (parent[i] != i) i = parent[i] = parent[parent[i]];
  return i;
}

// Merges parts whose mean depths differ by less than merge_depth or the edge threshold and whose
// boxes are closer than merge_gap (m, at their depth). Returns the groups.
std::vector<Blob> merge_parts(const std::vector<Blob>& parts, const SegmentationOptions& o,
                              const std::vector<uint16_t>& edge, double fx) {
  const int n = static_cast<int>(parts.size());
  std::vector<int> parent(n);
  std::iota(parent.begin(), parent.end(), 0);
  // Pairs are swept in order of u0, and a's sweep stops at the first part that starts more than
  // the largest possible gap (at the nearest part's depth) right of a's box: every pair that can
  // merge is still tested, but a speckled frame's thousands of parts no longer cost n² tests
  // (1.1 s a frame at 1280 × 720). The groups do not depend on the order of the unions.
  double z_min = std::numeric_limits<double>::infinity();
  for (const Blob& b : parts) z_min = std::min(z_min, b.z());
  const double max_gap_px = o.merge_gap * fx / z_min;
  std::vector<int> by_u0(n);
  std::iota(by_u0.begin(), by_u0.end(), 0);
  std::sort(by_u0.begin(), by_u0.end(), [&](int x, int y) { return parts[x].u0 < parts[y].u0; });
  for (int x = 0; x < n; ++x)
    for (int y = x + 1; y < n; ++y) {
      const int i = by_u0[x], j = by_u0[y];
      const Blob& a = parts[i];
      const Blob& b = parts[j];
      if (b.u0 - a.u1 - 1 > max_gap_px) break;  // so are all later parts (their u0 is larger)
      const double za = a.z(), zb = b.z(), zn = std::min(za, zb);
      const double edge_mm = edge[static_cast<size_t>(std::min<double>(zn * 1000.0, edge.size() - 1))];
      if (std::abs(za - zb) * 1000.0 > std::max(o.merge_depth * 1000.0, edge_mm)) continue;
      const double gap_px = o.merge_gap * fx / zn;
      const int du = std::max({0, a.u0 - b.u1 - 1, b.u0 - a.u1 - 1});
      const int dv = std::max({0, a.v0 - b.v1 - 1, b.v0 - a.v1 - 1});
      if (du > gap_px || dv > gap_px) continue;
      parent[find(parent, i)] = find(parent, j);
    }
  std::vector<int> group_of(n, -1);
  std::vector<Blob> groups;
  for (int i = 0; i < n; ++i) {
    const int r = find(parent, i);
    if (group_of[r] < 0) {
      group_of[r] = static_cast<int>(groups.size());
      groups.push_back(parts[i]);
      continue;
    }
    Blob& g = groups[static_cast<size_t>(group_of[r])];
    g.u0 = std::min(g.u0, parts[i].u0);
    g.v0 = std::min(g.v0, parts[i].v0);
    g.u1 = std::max(g.u1, parts[i].u1);
    g.v1 = std::max(g.v1, parts[i].v1);
    g.area += parts[i].area;
    g.depth_sum += parts[i].depth_sum;
  }
  return groups;
}

// Fraction of the ring around the blob's box (ring_px wide, clipped to the image) whose depth is
// invalid or farther than the blob by more than gap_mm; 0 when the ring is empty.
double far_fraction(const cv::Mat& depth, const Blob& b, int ring_px, double gap_mm) {
  const int u0 = std::max(0, b.u0 - ring_px), u1 = std::min(depth.cols - 1, b.u1 + ring_px);
  const int v0 = std::max(0, b.v0 - ring_px), v1 = std::min(depth.rows - 1, b.v1 + ring_px);
  const double limit = b.depth_sum / b.area + gap_mm;
  int total = 0, far = 0;
  for (int v = v0; v <= v1; ++v) {
    const uint16_t* row = depth.ptr<uint16_t>(v);
    const bool inside_rows = v >= b.v0 && v <= b.v1;
    for (int u = u0; u <= u1; ++u) {
      if (inside_rows && u >= b.u0 && u <= b.u1) {
        u = b.u1;  // skip the box itself
        continue;
      }
      ++total;
      if (row[u] == 0 || row[u] > limit) ++far;
    }
  }
  return total > 0 ? static_cast<double>(far) / total : 0.0;
}

// The f × f blocks of `raw` → their nearest valid depth (0 when none is valid). Invalid 0 becomes
// 0xFFFF by z − 1 wrapping around, so a plain min skips it, and + 1 turns it back into 0.
void decimate_nearest(const cv::Mat& raw, int f, cv::Mat& out) {
  const int w = raw.cols / f, h = raw.rows / f;
  out.create(h, w, CV_16U);
  std::vector<uint16_t> cols(static_cast<size_t>(raw.cols));  // per full-resolution column: min over the block's rows, − 1
  for (int v = 0; v < h; ++v) {
    std::fill(cols.begin(), cols.end(), static_cast<uint16_t>(0xFFFF));
    for (int dv = 0; dv < f; ++dv) {
      const uint16_t* row = raw.ptr<uint16_t>(v * f + dv);
      for (int u = 0; u < raw.cols; ++u) cols[u] = std::min(cols[u], static_cast<uint16_t>(row[u] - 1));
    }
    uint16_t* o = out.ptr<uint16_t>(v);
    for (int u = 0; u < w; ++u) {
      uint16_t m = cols[static_cast<size_t>(u * f)];
      for (int du = 1; du < f; ++du) m = std::min(m, cols[static_cast<size_t>(u * f + du)]);
      o[u] = static_cast<uint16_t>(m + 1);
    }
  }
}

// Box, area and depth sum of every label (one pass; runs of one label accumulate locally).
std::vector<Blob> label_stats(const cv::Mat& labels, const cv::Mat& depth, int count) {
  std::vector<Blob> blobs(static_cast<size_t>(count), Blob{1 << 30, 1 << 30, -1, -1, 0, 0.0});
  for (int v = 0; v < labels.rows; ++v) {
    const int* lab = labels.ptr<int>(v);
    const uint16_t* z = depth.ptr<uint16_t>(v);
    int u = 0;
    while (u < labels.cols) {
      const int l = lab[u];
      const int first = u;
      int64_t sum = 0;
      for (; u < labels.cols && lab[u] == l; ++u) sum += z[u];
      if (l == 0) continue;
      Blob& b = blobs[static_cast<size_t>(l)];
      b.u0 = std::min(b.u0, first);
      b.u1 = std::max(b.u1, u - 1);
      b.v0 = std::min(b.v0, v);
      b.v1 = std::max(b.v1, v);
      b.area += u - first;
      b.depth_sum += static_cast<double>(sum);
    }
  }
  return blobs;
}

// Whether a blob w_m wide and h_m high (m) whose centre is at image row v (work pixels) is flat
// enough: no higher than a drone seen at that elevation, and no more than flat_height higher than
// wide (a rotor disc is never seen higher than wide; slivers cut from a slanted surface are).
bool flat_enough(double w_m, double h_m, double v, const CameraIntrinsics& k, const SegmentationOptions& o) {
  const double elevation = std::abs(std::atan2(k.cy - v, k.fy));
  const double a = std::min(1.5707963267948966, elevation + o.tilt_slack);
  return h_m <= o.flat_height + o.diameter * std::sin(a) && h_m <= w_m + o.flat_height;
}

}  // namespace

std::vector<BoxDetection> detect_depth(const FrameView& frame, const SegmentationOptions& o) {
  std::vector<BoxDetection> out;
  const CameraIntrinsics& full = frame.intrinsics;
  if (!frame_error(frame).empty()) return out;
  int f = o.decimation > 0 ? o.decimation : (full.width > 480 ? 2 : 1);
  if (full.width / f < 1 || full.height / f < 1) f = 1;  // a 481 × 1 frame decimated to 0 rows aborted OpenCV
  const cv::Mat raw(full.height, full.width, CV_16U, const_cast<uint16_t*>(frame.depth_mm));
  // Buffers reused across calls (never aliasing the caller's pixels); reduced and work are views.
  thread_local cv::Mat reduced_buffer, median_buffer, mask, labels;
  cv::Mat reduced = raw, work;
  // The working image and its intrinsics (pixel centres: u_full = f·u_work + (f − 1)/2).
  CameraIntrinsics k = full;
  if (f > 1) {
    decimate_nearest(raw, f, reduced_buffer);
    reduced = reduced_buffer;
    k.width = reduced.cols;
    k.height = reduced.rows;
    k.fx = full.fx / f;
    k.fy = full.fy / f;
    k.cx = (full.cx - (f - 1) * 0.5) / f;
    k.cy = (full.cy - (f - 1) * 0.5) / f;
  }
  if (o.median_filter) {
    cv::medianBlur(reduced, median_buffer, 3);
    work = median_buffer;
  } else {
    work = reduced;
  }
  const int lo_mm = static_cast<int>(std::lround(o.min_depth * 1000.0));
  const int hi_mm = static_cast<int>(std::min(65535L, std::lround(o.max_depth * 1000.0)));
  const double noise_scale = (f > 1 ? 0.7 : 1.0) * (o.median_filter ? 0.5 : 1.0);
  // Every valid depth takes part in the segmentation (a cut at max_depth would make noise islands
  // of a far wall look like near blobs); blobs beyond max_depth are dropped afterwards.
  const std::vector<uint16_t>& edge = edge_table(o, full.fx, noise_scale);
  surface_mask(work, edge, lo_mm, 65535, mask);
  const int count = cv::connectedComponents(mask, labels, 4, CV_32S);
  const std::vector<Blob> blobs = label_stats(labels, work, count);

  // Parts: components no larger than a drone at their depth.
  std::vector<Blob> parts;
  for (int i = 1; i < count; ++i) {
    const Blob& b = blobs[static_cast<size_t>(i)];
    if (b.area < o.min_part_pixels) continue;
    const double z = b.z();
    if (z * 1000.0 > hi_mm) continue;
    if ((b.u1 - b.u0 + 1) * z / k.fx > o.max_size || (b.v1 - b.v0 + 1) * z / k.fy > o.max_size) continue;
    parts.push_back(b);
  }
  if (o.max_parts >= 0 && parts.size() > static_cast<size_t>(o.max_parts)) {
    // The largest by area (ties: the first found), kept in the order found.
    std::vector<size_t> order(parts.size());
    std::iota(order.begin(), order.end(), size_t{0});
    std::stable_sort(order.begin(), order.end(), [&](size_t x, size_t y) { return parts[x].area > parts[y].area; });
    order.resize(static_cast<size_t>(o.max_parts));
    std::sort(order.begin(), order.end());
    std::vector<Blob> kept;
    kept.reserve(order.size());
    for (size_t i : order) kept.push_back(parts[i]);
    parts.swap(kept);
  }
  for (const Blob& g : merge_parts(parts, o, edge, k.fx)) {
    const double z = g.z();
    const int w = g.u1 - g.u0 + 1, h = g.v1 - g.v0 + 1;
    const double wm = w * z / k.fx, hm = h * z / k.fy;
    if (g.area * f * f < o.min_pixels || std::max(wm, hm) < o.min_size || wm < o.min_width || wm > o.max_size ||
        hm > o.max_size)
      continue;
    if (!flat_enough(wm, hm, 0.5 * (g.v0 + g.v1), k, o)) continue;
    const int ring_px = std::max(2, static_cast<int>(std::lround(o.ring * k.fx / z)));
    const double far = far_fraction(work, g, ring_px, o.background_gap * 1000.0);
    const bool border = g.u0 == 0 || g.v0 == 0 || g.u1 == k.width - 1 || g.v1 == k.height - 1;
    const double score = border ? far * o.border_factor : far;
    if (score < o.min_far_fraction || score <= 0) continue;
    BoxDetection d;  // full-resolution box enclosing the blob's blocks
    d.u = static_cast<float>(g.u0 * f - 0.5);
    d.v = static_cast<float>(g.v0 * f - 0.5);
    d.w = static_cast<float>(w * f);
    d.h = static_cast<float>(h * f);
    d.score = static_cast<float>(score);
    out.push_back(d);
  }
  return out;
}

}  // namespace fact
