// YOLO backend (fact/yolo.h) against a tiny synthetic ONNX model written at test time by
// test/make_tiny_yolo.py (Debian's /usr/bin/python3 + python3-onnx). The model's head is a known
// function of its input (see the script): one anchor per 8 × 8 input cell, centred on the cell,
// w = 64·g, h = 32·g (g = gray max / 255 in the cell), class 0 = sigmoid(20·d − 12) (d = 8-bit
// depth max / 255), class 1 = sigmoid(20·g − 18). The scenes paint small uniform patches inside
// single cells; the expected boxes and scores below are worked out by hand from those formulas,
// the letterbox of the scene (written out as literals) and the documented depth rule.
#include "fact/yolo.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iostream>
#include <string>
#include <vector>

namespace {

using fact::BoxDetection;
using fact::YoloDetector;
using fact::YoloOptions;

const char* const kPython = "/usr/bin/python3";

double sigmoid(double x) { return 1.0 / (1.0 + std::exp(-x)); }

// A gray + depth frame with a uniform background (gray 0, depth invalid).
struct Scene {
  fact::CameraIntrinsics k;
  std::vector<uint8_t> gray;
  std::vector<uint16_t> depth;
  Scene(int width, int height) {
    k.width = width;
    k.height = height;
    k.fx = k.fy = 300;
    k.cx = width / 2.0;
    k.cy = height / 2.0;
    gray.assign(size_t(width) * height, 0);
    depth.assign(size_t(width) * height, 0);
  }
  // Fills [u0, u1) × [v0, v1).
  void paint(int u0, int v0, int u1, int v1, uint8_t g, uint16_t z_mm) {
    for (int v = v0; v < v1; ++v)
      for (int u = u0; u < u1; ++u) {
        gray[size_t(v) * k.width + u] = g;
        depth[size_t(v) * k.width + u] = z_mm;
      }
  }
  fact::FrameView view() const {
    fact::FrameView f;
    f.intrinsics = k;
    f.gray = gray.data();
    f.depth_mm = depth.data();
    return f;
  }
};

// The expected image box of the anchor of cell (i, j) for a gray value, under a letterbox with
// scale 1/inv_scale and padding (pad_x, pad_y), clipped to the image.
BoxDetection expected_box(int i, int j, double gray, double score, double inv_scale, int pad_x,
                          int pad_y, int width, int height) {
  const double cx = (8 * j + 4 - pad_x) * inv_scale, cy = (8 * i + 4 - pad_y) * inv_scale;
  const double w = 64 * gray / 255 * inv_scale, h = 32 * gray / 255 * inv_scale;
  const double u0 = std::max(0.0, cx - w / 2), u1 = std::min<double>(width, cx + w / 2);
  const double v0 = std::max(0.0, cy - h / 2), v1 = std::min<double>(height, cy + h / 2);
  BoxDetection b;
  b.u = float(u0);
  b.v = float(v0);
  b.w = float(u1 - u0);
  b.h = float(v1 - v0);
  b.score = float(score);
  return b;
}

void expect_boxes(const std::vector<BoxDetection>& got, const std::vector<BoxDetection>& want) {
  ASSERT_EQ(got.size(), want.size());
  for (size_t n = 0; n < want.size(); ++n) {
    SCOPED_TRACE("box " + std::to_string(n));
    EXPECT_NEAR(got[n].u, want[n].u, 0.01);
    EXPECT_NEAR(got[n].v, want[n].v, 0.01);
    EXPECT_NEAR(got[n].w, want[n].w, 0.01);
    EXPECT_NEAR(got[n].h, want[n].h, 0.01);
    EXPECT_NEAR(got[n].score, want[n].score, 1e-4);
  }
}

// Writes the tiny models once per test process (gtest_discover_tests runs one test per process).
class TinyYolo : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    if (std::system((std::string(kPython) + " -c 'import onnx, numpy' >/dev/null 2>&1").c_str()) != 0)
      return;  // tests skip
    char tmpl[] = "/tmp/fact_yolo_test_XXXXXX";
    if (!mkdtemp(tmpl)) return;
    dir_ = tmpl;
    for (int size : {160, 640}) {
      const std::string cmd = std::string(kPython) + " " + FACT_MAKE_TINY_YOLO + " " + dir_ +
                              " --size " + std::to_string(size) + " >/dev/null";
      if (std::system(cmd.c_str()) != 0) generate_failed_ = true;
    }
  }
  static void TearDownTestSuite() {
    if (!dir_.empty()) std::system(("rm -rf '" + dir_ + "'").c_str());
  }
  void SetUp() override {
    if (dir_.empty()) GTEST_SKIP() << kPython << " cannot import onnx (python3-onnx)";
    ASSERT_FALSE(generate_failed_) << FACT_MAKE_TINY_YOLO << " failed";
  }
  static std::string model(int size, bool transposed = false) {
    return dir_ + "/tiny_yolo_" + std::to_string(size) + (transposed ? "_t" : "") + ".onnx";
  }
  static std::unique_ptr<YoloDetector> load(const std::string& path, const YoloOptions& o) {
    std::string error;
    auto d = YoloDetector::load(path, o, &error);
    EXPECT_TRUE(d) << error;
    return d;
  }
  static YoloOptions options(int size) {
    YoloOptions o;
    o.input_size = size;
    return o;
  }

  static std::string dir_;
  static bool generate_failed_;
};
std::string TinyYolo::dir_;
bool TinyYolo::generate_failed_ = false;

// 640 × 480 into 160: scale 1/4, resized 160 × 120, pad_y = 20. Cell (i, j) covers image
// u ∈ [32j, 32j + 32), v ∈ [32i − 80, 32i − 48); each patch is the 16 × 16 inside it, aligned to
// 4 px so the bilinear 4:1 downscale keeps its value exactly.
Scene five_patches() {
  Scene s(640, 480);
  auto cell_patch = [&](int i, int j, uint8_t g, uint16_t z) {
    s.paint(32 * j + 8, 32 * i - 80 + 8, 32 * j + 24, 32 * i - 80 + 24, g, z);
  };
  cell_patch(5, 3, 200, 8000);    // A: depth8 204 → class 0 = σ(4)
  cell_patch(5, 4, 200, 7500);    // B: depth8 191 (191.25), overlaps A (IoU 0.725)
  cell_patch(10, 15, 100, 6000);  // C: depth8 153 → class 0 = σ(0) = 0.5
  cell_patch(12, 8, 100, 2000);   // D: depth8 51 → σ(−8), below the threshold
  cell_patch(14, 18, 250, 0);     // E: no depth; class 1 = σ(20·250/255 − 18); clipped at u = 640
  return s;
}
const double kScoreA = sigmoid(20.0 * 204 / 255 - 12), kScoreB = sigmoid(20.0 * 191 / 255 - 12);
const double kScoreC = 0.5, kScoreE = sigmoid(20.0 * 250 / 255 - 18);
BoxDetection box640(int i, int j, double gray, double score) {
  return expected_box(i, j, gray, score, 4.0, 0, 20, 640, 480);
}

TEST(YoloGeometry, LetterboxForSizes) {
  struct Case {
    int w, h, s;
    double scale;
    int rw, rh, px, py;
  };
  const Case cases[] = {
      {640, 480, 160, 0.25, 160, 120, 0, 20},
      {640, 480, 640, 1.0, 640, 480, 0, 80},
      {320, 640, 160, 0.25, 80, 160, 40, 0},
      {424, 240, 640, 640.0 / 424, 640, 362, 0, 139},  // 240·1.5094 = 362.3
      {424, 240, 320, 320.0 / 424, 320, 181, 0, 69},   // pad (320 − 181) / 2 = 69.5 → 69
      {100, 100, 64, 0.64, 64, 64, 0, 0},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(std::to_string(c.w) + "x" + std::to_string(c.h) + " → " + std::to_string(c.s));
    const fact::Letterbox lb = fact::letterbox_for(c.w, c.h, c.s);
    EXPECT_NEAR(lb.scale, c.scale, 1e-12);
    EXPECT_EQ(lb.resized_w, c.rw);
    EXPECT_EQ(lb.resized_h, c.rh);
    EXPECT_EQ(lb.pad_x, c.px);
    EXPECT_EQ(lb.pad_y, c.py);
  }
}

TEST(YoloGeometry, DepthTo8BitRule) {
  EXPECT_EQ(fact::depth_to_8bit(0, 10.0), 0);        // invalid stays 0
  EXPECT_EQ(fact::depth_to_8bit(1, 10.0), 0);        // 0.0255 rounds to 0
  EXPECT_EQ(fact::depth_to_8bit(1000, 10.0), 26);    // 25.5 rounds up
  EXPECT_EQ(fact::depth_to_8bit(8000, 10.0), 204);
  EXPECT_EQ(fact::depth_to_8bit(10000, 10.0), 255);
  EXPECT_EQ(fact::depth_to_8bit(25000, 10.0), 255);  // saturates
  EXPECT_EQ(fact::depth_to_8bit(8000, 20.0), 102);
  EXPECT_EQ(fact::depth_to_8bit(65535, 100.0), 167);  // 255 · 65.535 / 100 = 167.1
}

TEST(YoloGeometry, OptionErrorsNameTheField) {
  EXPECT_EQ(fact::yolo_options_error(YoloOptions()), "");
  auto error_of = [](auto change) {
    YoloOptions o;
    change(o);
    return fact::yolo_options_error(o);
  };
  EXPECT_NE(error_of([](YoloOptions& o) { o.input_size = 0; }).find("input_size = 0"), std::string::npos);
  EXPECT_NE(error_of([](YoloOptions& o) { o.score_threshold = NAN; }).find("score_threshold"), std::string::npos);
  EXPECT_NE(error_of([](YoloOptions& o) { o.nms_threshold = 0; }).find("nms_threshold"), std::string::npos);
  EXPECT_NE(error_of([](YoloOptions& o) { o.class_id = -2; }).find("class_id = -2"), std::string::npos);
  EXPECT_NE(error_of([](YoloOptions& o) { o.depth_scale_m = -1; }).find("depth_scale_m"), std::string::npos);
  EXPECT_NE(error_of([](YoloOptions& o) { o.max_detections = 0; }).find("max_detections = 0"), std::string::npos);
}

TEST(YoloLoad, MissingFileNamesPathAndOpenCVReason) {
  const std::string path = "/nonexistent/fact/model.onnx";
  std::string error;
  EXPECT_EQ(YoloDetector::load(path, YoloOptions(), &error), nullptr);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("OpenCV"), std::string::npos) << error;
  EXPECT_EQ(YoloDetector::load(path, YoloOptions(), nullptr), nullptr);  // no error string: fine
}

TEST(YoloLoad, GarbageFileNamesPathAndOpenCVReason) {
  char path[] = "/tmp/fact_yolo_garbage_XXXXXX";
  const int fd = mkstemp(path);
  ASSERT_GE(fd, 0);
  const std::string junk = "this is not an ONNX protobuf \x01\x02\x03\xff\xfe";
  ASSERT_EQ(write(fd, junk.data(), junk.size()), ssize_t(junk.size()));
  close(fd);
  std::string error;
  EXPECT_EQ(YoloDetector::load(path, YoloOptions(), &error), nullptr);
  std::remove(path);
  EXPECT_NE(error.find(path), std::string::npos) << error;
  EXPECT_NE(error.find("OpenCV"), std::string::npos) << error;
}

TEST(YoloLoad, BadOptionsRejectedBeforeReading) {
  YoloOptions o;
  o.depth_scale_m = 0;
  std::string error;
  EXPECT_EQ(YoloDetector::load("/nonexistent/m.onnx", o, &error), nullptr);
  EXPECT_NE(error.find("depth_scale_m"), std::string::npos) << error;
}

TEST_F(TinyYolo, InputSizeMismatchFailsAtLoad) {
  std::string error;
  EXPECT_EQ(YoloDetector::load(model(160), options(320), &error), nullptr);
  EXPECT_NE(error.find(model(160)), std::string::npos) << error;
  EXPECT_NE(error.find("input_size = 320"), std::string::npos) << error;
}

TEST_F(TinyYolo, ClassIdBeyondTheModelFailsAtLoad) {
  YoloOptions o = options(160);
  o.class_id = 2;
  std::string error;
  EXPECT_EQ(YoloDetector::load(model(160), o, &error), nullptr);
  EXPECT_NE(error.find("class_id = 2 but the model has 2 classes"), std::string::npos) << error;
}

TEST_F(TinyYolo, DecodesBoxesScoresAndSuppressesOverlaps) {
  auto det = load(model(160), options(160));
  ASSERT_TRUE(det);
  EXPECT_EQ(det->num_classes(), 2);
  std::string error = "stale";
  const auto boxes = det->detect(five_patches().view(), &error);
  EXPECT_EQ(error, "");
  // B overlaps A with IoU 0.725 > 0.45 and scores lower: suppressed. D is below 0.25.
  expect_boxes(boxes, {box640(5, 3, 200, kScoreA), box640(14, 18, 250, kScoreE),
                       box640(10, 15, 100, kScoreC)});
  // Hand-checked values of the first and the clipped box.
  ASSERT_EQ(boxes.size(), 3u);
  EXPECT_NEAR(boxes[0].u, 112 - 100.392, 0.01);
  EXPECT_NEAR(boxes[0].v, 96 - 50.196, 0.01);
  EXPECT_NEAR(boxes[0].score, 0.98201, 1e-4);
  EXPECT_NEAR(boxes[1].u + boxes[1].w, 640.0, 1e-3);  // clipped at the right edge
}

TEST_F(TinyYolo, TransposedHeadGivesTheSameBoxes) {
  auto a = load(model(160), options(160));
  auto b = load(model(160, true), options(160));
  ASSERT_TRUE(a && b);
  EXPECT_EQ(b->num_classes(), 2);
  const Scene s = five_patches();
  expect_boxes(b->detect(s.view()), a->detect(s.view()));
  EXPECT_EQ(b->detect(s.view()).size(), 3u);
}

TEST_F(TinyYolo, LooseNmsKeepsTheOverlappingBox) {
  YoloOptions o = options(160);
  o.nms_threshold = 0.8f;  // above IoU(A, B) = 168.8 / 232.8 = 0.725
  auto det = load(model(160), o);
  ASSERT_TRUE(det);
  expect_boxes(det->detect(five_patches().view()),
               {box640(5, 3, 200, kScoreA), box640(5, 4, 200, kScoreB),
                box640(14, 18, 250, kScoreE), box640(10, 15, 100, kScoreC)});
}

TEST_F(TinyYolo, ScoreThresholdAndMaxDetections) {
  YoloOptions o = options(160);
  o.score_threshold = 0.9f;  // keeps A only (C 0.5, E 0.83)
  auto det = load(model(160), o);
  ASSERT_TRUE(det);
  expect_boxes(det->detect(five_patches().view()), {box640(5, 3, 200, kScoreA)});

  o = options(160);
  o.max_detections = 2;
  det = load(model(160), o);
  ASSERT_TRUE(det);
  expect_boxes(det->detect(five_patches().view()),
               {box640(5, 3, 200, kScoreA), box640(14, 18, 250, kScoreE)});
}

TEST_F(TinyYolo, ClassIdSelectsThatClassScore) {
  YoloOptions o = options(160);
  o.class_id = 0;  // depth class: A and C; E (gray only) has class-0 score σ(−12)
  auto det = load(model(160), o);
  ASSERT_TRUE(det);
  expect_boxes(det->detect(five_patches().view()),
               {box640(5, 3, 200, kScoreA), box640(10, 15, 100, kScoreC)});
  o.class_id = 1;  // bright-gray class: E only (A: σ(20·200/255 − 18) = 0.09)
  det = load(model(160), o);
  ASSERT_TRUE(det);
  expect_boxes(det->detect(five_patches().view()), {box640(14, 18, 250, kScoreE)});
}

TEST_F(TinyYolo, DepthGoesToChannelTwoWithTheDocumentedScale) {
  YoloOptions o = options(160);
  o.depth_scale_m = 20.0;  // A: depth8 102 → σ(−4); B: 96; C: 77 → all below 0.25; E has no depth
  auto det = load(model(160), o);
  ASSERT_TRUE(det);
  expect_boxes(det->detect(five_patches().view()), {box640(14, 18, 250, kScoreE)});
}

TEST_F(TinyYolo, PortraitImageIsPaddedLeftAndRight) {
  // 320 × 640 into 160: scale 1/4, resized 80 × 160, pad_x = 40. Cell (10, 8) covers input
  // x ∈ [64, 72), y ∈ [80, 88) → image u ∈ [96, 128), v ∈ [320, 352).
  Scene s(320, 640);
  s.paint(104, 328, 120, 344, 150, 9500);  // depth8 242 (242.25)
  auto det = load(model(160), options(160));
  ASSERT_TRUE(det);
  const double score = sigmoid(20.0 * 242 / 255 - 12);
  const auto boxes = det->detect(s.view());
  expect_boxes(boxes, {expected_box(10, 8, 150, score, 4.0, 40, 0, 320, 640)});
  ASSERT_EQ(boxes.size(), 1u);
  EXPECT_NEAR(boxes[0].u + boxes[0].w / 2, 112.0, 0.01);  // (68 − 40) · 4
  EXPECT_NEAR(boxes[0].v + boxes[0].h / 2, 336.0, 0.01);  // 84 · 4
}

TEST_F(TinyYolo, BadFramesGiveErrorsNotBoxes) {
  auto det = load(model(160), options(160));
  ASSERT_TRUE(det);
  Scene s = five_patches();
  fact::FrameView f = s.view();
  f.gray = nullptr;
  std::string error;
  EXPECT_TRUE(det->detect(f, &error).empty());
  EXPECT_NE(error.find("gray is null"), std::string::npos) << error;
  f = s.view();
  f.depth_mm = nullptr;
  EXPECT_TRUE(det->detect(f, &error).empty());
  EXPECT_NE(error.find("depth_mm is null"), std::string::npos) << error;
  f = s.view();
  f.intrinsics.width = 0;
  EXPECT_TRUE(det->detect(f, &error).empty());
  EXPECT_NE(error.find("0x480"), std::string::npos) << error;
  // Still works afterwards.
  EXPECT_EQ(det->detect(s.view(), &error).size(), 3u);
  EXPECT_EQ(error, "");
}

TEST_F(TinyYolo, FullSizeInputWithoutResize) {
  // 640 × 480 into 640: scale 1, pad_y = 80; cell (i, j) covers u ∈ [8j, 8j + 8),
  // v ∈ [8i − 80, 8i − 72). One patch in cell (30, 50): u ∈ [400, 408), v ∈ [160, 168).
  Scene s(640, 480);
  s.paint(402, 162, 406, 166, 180, 7000);  // depth8 178.5 → 179 (round half up)
  auto det = load(model(640), options(640));
  ASSERT_TRUE(det);
  const double score = sigmoid(20.0 * 179 / 255 - 12);
  // The same box on every call (the detector keeps no state between frames).
  for (int run = 0; run < 3; ++run)
    expect_boxes(det->detect(s.view()), {expected_box(30, 50, 180, score, 1.0, 0, 80, 640, 480)});
}

}  // namespace
