// YOLOv8 detector backend: an ONNX model run through OpenCV dnn (Debian OpenCV 4.6), its raw head
// decoded in C++. No OpenCV types in this header (the implementation hides cv::dnn::Net).
//
// Input convention (lib/detector/YOLO.md; a model must be trained on the same):
//  - 3 channels in the network's tensor order: 0 = gray, 1 = gray, 2 = depth as 8 bits,
//    depth8 = round(255 · min(z_mm / (1000 · depth_scale_m), 1)), 0 (invalid depth) stays 0.
//  - Letterboxed to a square input_size × input_size: scale r = min(S/width, S/height), resized
//    (bilinear) to round(width·r) × round(height·r), centred with pad (S − new)/2 rounded down on the
//    left/top, pad value 114 in every channel; pixel values / 255 (float, NCHW, batch 1).
//  - Output: the raw head [1, 4 + nc, A] (YOLOv8 export) or [1, A, 4 + nc]: per anchor the box centre
//    and size (cx, cy, w, h) in input pixels, then nc class scores in [0, 1] (no objectness).
#pragma once

#include "fact/frame.h"

#include <memory>
#include <string>
#include <vector>

namespace fact {

struct YoloOptions {
  int input_size = 640;          // side S of the square model input (px); must match the model
  float score_threshold = 0.25f; // keep anchors whose score ≥ this
  float nms_threshold = 0.45f;   // IoU above which the lower-scoring box is suppressed
  int class_id = -1;             // score = this class's score; −1 = the best class's score
  double depth_scale_m = 10.0;   // depth → 8 bit: 255 · min(z / depth_scale_m, 1); > 0
  int max_detections = 300;      // at most this many boxes after NMS (highest scores)
};

// "" when usable, else which field is wrong and its value.
std::string yolo_options_error(const YoloOptions& o);

// The letterbox mapping between image pixels (u, v) and model-input pixels (x, y):
//   x = u · scale + pad_x,  y = v · scale + pad_y.
struct Letterbox {
  double scale = 1.0;
  int pad_x = 0, pad_y = 0;       // left / top padding (input px)
  int resized_w = 0, resized_h = 0;  // size of the resized image inside the input (px)
};
Letterbox letterbox_for(int width, int height, int input_size);

// The 8-bit depth value of z_mm (the rule above).
uint8_t depth_to_8bit(uint16_t z_mm, double depth_scale_m);

class YoloDetector {
 public:
  // Reads the ONNX model at `path` and runs one inference on a blank input to check the output
  // shape. On failure returns nullptr and, if `error` is set, a message with the path and OpenCV's
  // reason. Never throws.
  static std::unique_ptr<YoloDetector> load(const std::string& path, const YoloOptions& options,
                                            std::string* error);
  ~YoloDetector();
  YoloDetector(const YoloDetector&) = delete;
  YoloDetector& operator=(const YoloDetector&) = delete;

  // Boxes in image pixels (clipped to the image), highest score first. The frame's intrinsics give
  // its size; gray and depth_mm must be set. On failure (bad frame, OpenCV error) returns an empty
  // list and sets *error (if given) to the reason; on success *error is cleared.
  std::vector<BoxDetection> detect(const FrameView& frame, std::string* error = nullptr);

  const YoloOptions& options() const;
  int num_classes() const;  // nc of the model's head

 private:
  struct Impl;
  explicit YoloDetector(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace fact
