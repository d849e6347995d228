// YOLOv8 backend through OpenCV dnn: gray + depth → letterboxed 3-channel blob → raw head →
// C++ decoding, score threshold, cv::dnn::NMSBoxes, un-letterboxing (conventions in fact/yolo.h and
// lib/detector/YOLO.md).
#include "fact/yolo.h"

#include <opencv2/core.hpp>
#include <opencv2/dnn.hpp>
#include <opencv2/imgproc.hpp>

#include <algorithm>
#include <cmath>
#include <exception>
#include <numeric>

namespace fact {
namespace {

constexpr int kPadValue = 114;  // letterbox padding, every channel (as ultralytics trains)

void set_error(std::string* error, const std::string& message) {
  if (error) *error = message;
}

// OpenCV's exception text on one line (its messages end with, and may contain, newlines).
std::string one_line(const std::string& text) {
  std::string s = text;
  std::replace(s.begin(), s.end(), '\n', ' ');
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

std::string shape_string(const cv::Mat& m) {
  std::string s;
  for (int d = 0; d < m.dims; ++d) s += (d ? "x" : "") + std::to_string(m.size[d]);
  return s;
}

// How the head [1, d1, d2] is laid out.
struct HeadLayout {
  bool channels_first = true;  // [1, 4 + nc, A] (true) or [1, A, 4 + nc]
  int anchors = 0;             // A
  int channels = 0;            // 4 + nc
};

// "" and the layout, or why the output is not a YOLOv8 raw head. [1, C, A] when C < A (the export's
// 84 × 8400), [1, A, C] when A < C; a square head is read as [1, C, A].
std::string head_layout(const cv::Mat& out, HeadLayout* layout) {
  const bool batch_one = out.dims == 3 && out.size[0] == 1;
  if (!batch_one && out.dims != 2)
    return "output shape " + shape_string(out) + " is not [1, 4+nc, A] or [1, A, 4+nc]";
  const int d1 = out.size[out.dims - 2], d2 = out.size[out.dims - 1];
  layout->channels_first = d1 <= d2;
  layout->channels = layout->channels_first ? d1 : d2;
  layout->anchors = layout->channels_first ? d2 : d1;
  if (layout->channels < 5)
    return "output shape " + shape_string(out) + " has fewer than 4 + 1 channels per anchor";
  return "";
}

// 8-bit depth for every 16-bit value (0 stays 0): the rule of depth_to_8bit as a table.
std::vector<uint8_t> depth_table(double depth_scale_m) {
  std::vector<uint8_t> t(65536);
  for (int z = 0; z < 65536; ++z) t[z] = depth_to_8bit(static_cast<uint16_t>(z), depth_scale_m);
  return t;
}

// A candidate box in model-input pixels.
struct Candidate {
  cv::Rect2d box;
  float score = 0;
};

}  // namespace

std::string yolo_options_error(const YoloOptions& o) {
  if (o.input_size < 32 || o.input_size > 4096)
    return "input_size = " + std::to_string(o.input_size) + " (expected 32..4096)";
  if (!(o.score_threshold >= 0.f && o.score_threshold <= 1.f))
    return "score_threshold = " + std::to_string(o.score_threshold) + " (expected 0..1)";
  if (!(o.nms_threshold > 0.f && o.nms_threshold <= 1.f))
    return "nms_threshold = " + std::to_string(o.nms_threshold) + " (expected (0, 1])";
  if (o.class_id < -1) return "class_id = " + std::to_string(o.class_id) + " (expected ≥ −1)";
  if (!(o.depth_scale_m > 0 && std::isfinite(o.depth_scale_m)))
    return "depth_scale_m = " + std::to_string(o.depth_scale_m) + " (expected > 0 m)";
  if (o.max_detections < 1)
    return "max_detections = " + std::to_string(o.max_detections) + " (expected ≥ 1)";
  return "";
}

Letterbox letterbox_for(int width, int height, int input_size) {
  Letterbox lb;
  if (width <= 0 || height <= 0 || input_size <= 0) return lb;
  lb.scale = std::min(double(input_size) / width, double(input_size) / height);
  lb.resized_w = std::min(input_size, int(std::lround(width * lb.scale)));
  lb.resized_h = std::min(input_size, int(std::lround(height * lb.scale)));
  lb.pad_x = (input_size - lb.resized_w) / 2;
  lb.pad_y = (input_size - lb.resized_h) / 2;
  return lb;
}

uint8_t depth_to_8bit(uint16_t z_mm, double depth_scale_m) {
  if (z_mm == 0) return 0;
  const double v = 255.0 * std::min(z_mm / (1000.0 * depth_scale_m), 1.0);
  return static_cast<uint8_t>(std::lround(v));
}

struct YoloDetector::Impl {
  YoloOptions options;
  std::string path;
  cv::dnn::Net net;
  HeadLayout layout;
  std::vector<uint8_t> depth8_table;  // 65536 entries
  cv::Mat depth8, merged, resized, input, blob;  // buffers reused across frames

  // The letterboxed S × S 8-bit 3-channel input (gray, gray, depth8) of a frame.
  const cv::Mat& letterboxed(const FrameView& f, const Letterbox& lb);
  // Candidates above the score threshold from the head (input pixels).
  std::vector<Candidate> decode(const cv::Mat& out) const;
};

const cv::Mat& YoloDetector::Impl::letterboxed(const FrameView& f, const Letterbox& lb) {
  const int w = f.intrinsics.width, h = f.intrinsics.height;
  const cv::Mat gray(h, w, CV_8UC1, const_cast<uint8_t*>(f.gray));
  depth8.create(h, w, CV_8UC1);
  const uint16_t* z = f.depth_mm;
  uint8_t* d = depth8.ptr<uint8_t>();
  for (size_t i = 0, n = size_t(w) * size_t(h); i < n; ++i) d[i] = depth8_table[z[i]];
  const cv::Mat channels[3] = {gray, gray, depth8};
  cv::merge(channels, 3, merged);
  const cv::Mat* src = &merged;
  if (lb.resized_w != w || lb.resized_h != h) {
    cv::resize(merged, resized, cv::Size(lb.resized_w, lb.resized_h), 0, 0, cv::INTER_LINEAR);
    src = &resized;
  }
  const int S = options.input_size;
  cv::copyMakeBorder(*src, input, lb.pad_y, S - lb.resized_h - lb.pad_y, lb.pad_x,
                     S - lb.resized_w - lb.pad_x, cv::BORDER_CONSTANT,
                     cv::Scalar(kPadValue, kPadValue, kPadValue));
  return input;
}

std::vector<Candidate> YoloDetector::Impl::decode(const cv::Mat& out) const {
  // Element (channel c, anchor a) of the head, either layout; data is contiguous float.
  const float* data = out.ptr<float>();
  const int A = layout.anchors, C = layout.channels;
  const bool cf = layout.channels_first;
  auto at = [&](int c, int a) { return cf ? data[size_t(c) * A + a] : data[size_t(a) * C + c]; };
  std::vector<Candidate> candidates;
  for (int a = 0; a < A; ++a) {
    float score = 0;
    if (options.class_id >= 0) {
      score = at(4 + options.class_id, a);
    } else {
      for (int c = 4; c < C; ++c) score = std::max(score, at(c, a));
    }
    if (!(score >= options.score_threshold)) continue;
    const double cx = at(0, a), cy = at(1, a), bw = at(2, a), bh = at(3, a);
    if (!(bw > 0 && bh > 0)) continue;
    candidates.push_back({cv::Rect2d(cx - bw / 2, cy - bh / 2, bw, bh), score});
  }
  return candidates;
}

YoloDetector::YoloDetector(std::unique_ptr<Impl> impl) : impl_(std::move(impl)) {}
YoloDetector::~YoloDetector() = default;

const YoloOptions& YoloDetector::options() const { return impl_->options; }
int YoloDetector::num_classes() const { return impl_->layout.channels - 4; }

std::unique_ptr<YoloDetector> YoloDetector::load(const std::string& path,
                                                 const YoloOptions& options, std::string* error) {
  const std::string prefix = "cannot load YOLO model '" + path + "': ";
  const std::string bad_options = yolo_options_error(options);
  if (!bad_options.empty()) {
    set_error(error, prefix + "bad option " + bad_options);
    return nullptr;
  }
  auto impl = std::make_unique<Impl>();
  impl->options = options;
  impl->path = path;
  try {
    impl->net = cv::dnn::readNetFromONNX(path);
    if (impl->net.empty()) {
      set_error(error, prefix + "OpenCV read an empty network");
      return nullptr;
    }
    impl->net.setPreferableBackend(cv::dnn::DNN_BACKEND_OPENCV);
    impl->net.setPreferableTarget(cv::dnn::DNN_TARGET_CPU);
    // One inference on a blank input: checks the input size and the head's shape now, not on
    // the first frame.
    const int S = options.input_size;
    const int blob_size[4] = {1, 3, S, S};
    impl->net.setInput(cv::Mat(4, blob_size, CV_32F, cv::Scalar(0)));
    const cv::Mat out = impl->net.forward();
    const std::string bad_head = head_layout(out, &impl->layout);
    if (!bad_head.empty()) {
      set_error(error, prefix + bad_head);
      return nullptr;
    }
  } catch (const cv::Exception& e) {
    set_error(error, prefix + "OpenCV: " + one_line(e.what()) +
                         " (input_size = " + std::to_string(options.input_size) + ")");
    return nullptr;
  } catch (const std::exception& e) {
    set_error(error, prefix + one_line(e.what()));
    return nullptr;
  }
  if (options.class_id >= impl->layout.channels - 4) {
    set_error(error, prefix + "class_id = " + std::to_string(options.class_id) + " but the model has " +
                         std::to_string(impl->layout.channels - 4) + " classes");
    return nullptr;
  }
  impl->depth8_table = depth_table(options.depth_scale_m);
  return std::unique_ptr<YoloDetector>(new YoloDetector(std::move(impl)));
}

std::vector<BoxDetection> YoloDetector::detect(const FrameView& frame, std::string* error) {
  set_error(error, "");
  const int w = frame.intrinsics.width, h = frame.intrinsics.height;
  if (w <= 0 || h <= 0) {
    set_error(error, "frame size " + std::to_string(w) + "x" + std::to_string(h) +
                         " (intrinsics.width/height must be > 0)");
    return {};
  }
  if (!frame.gray || !frame.depth_mm) {
    set_error(error, std::string(!frame.gray ? "gray" : "depth_mm") + " is null");
    return {};
  }
  Impl& m = *impl_;
  const Letterbox lb = letterbox_for(w, h, m.options.input_size);
  std::vector<Candidate> candidates;
  try {
    cv::dnn::blobFromImage(m.letterboxed(frame, lb), m.blob, 1.0 / 255.0, cv::Size(), cv::Scalar(),
                           /*swapRB=*/false, /*crop=*/false, CV_32F);
    m.net.setInput(m.blob);
    const cv::Mat out = m.net.forward();
    HeadLayout layout;
    const std::string bad_head = head_layout(out, &layout);
    if (!bad_head.empty() || layout.anchors != m.layout.anchors ||
        layout.channels != m.layout.channels) {
      set_error(error, "YOLO output shape " + shape_string(out) + " differs from the one at load");
      return {};
    }
    candidates = m.decode(out.isContinuous() ? out : out.clone());
  } catch (const cv::Exception& e) {
    set_error(error, "YOLO inference failed: OpenCV: " + one_line(e.what()));
    return {};
  }

  std::vector<cv::Rect2d> boxes;
  std::vector<float> scores;
  for (const Candidate& c : candidates) {
    boxes.push_back(c.box);
    scores.push_back(c.score);
  }
  std::vector<int> keep;
  // top_k = 0: NMS over every candidate (OpenCV's top_k cuts candidates before NMS); the
  // max_detections cut comes after.
  cv::dnn::NMSBoxes(boxes, scores, m.options.score_threshold, m.options.nms_threshold, keep, 1.f, 0);
  std::stable_sort(keep.begin(), keep.end(), [&](int a, int b) { return scores[a] > scores[b]; });
  if (int(keep.size()) > m.options.max_detections) keep.resize(m.options.max_detections);

  // Input pixels → image pixels (x = u·scale + pad_x), clipped to the image.
  std::vector<BoxDetection> result;
  for (int i : keep) {
    const cv::Rect2d& b = boxes[i];
    const double u0 = std::clamp((b.x - lb.pad_x) / lb.scale, 0.0, double(w));
    const double v0 = std::clamp((b.y - lb.pad_y) / lb.scale, 0.0, double(h));
    const double u1 = std::clamp((b.x + b.width - lb.pad_x) / lb.scale, 0.0, double(w));
    const double v1 = std::clamp((b.y + b.height - lb.pad_y) / lb.scale, 0.0, double(h));
    if (u1 <= u0 || v1 <= v0) continue;
    BoxDetection d;
    d.u = float(u0);
    d.v = float(v0);
    d.w = float(u1 - u0);
    d.h = float(v1 - v0);
    d.score = scores[i];
    result.push_back(d);
  }
  return result;
}

}  // namespace fact
