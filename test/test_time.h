// How long tests wait before giving up: every "wait at most X" deadline of a test is X times
// FACT_TEST_TIME_SCALE (an environment variable, a number >= 1, default 1). Under emulation
// (qemu-aarch64, scripts/cross-build-arm64.sh) programs run far slower, so deadlines set for
// native speed would fail tests whose results are right. ctest sets the variable for every test
// from the CMake cache variable of the same name (test/time_scale.cmake), which also multiplies
// the tests' TIMEOUT properties. Only deadlines scale: no test asserts on how fast anything runs.
#pragma once

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace fact::test {

// FACT_TEST_TIME_SCALE, or 1 when unset; a value that is not a number >= 1 aborts the test.
inline double time_scale() {
  static const double scale = [] {
    const char* text = std::getenv("FACT_TEST_TIME_SCALE");
    if (text == nullptr || *text == '\0') return 1.0;
    char* end = nullptr;
    const double s = std::strtod(text, &end);
    if (*end != '\0' || !std::isfinite(s) || s < 1) {
      std::fprintf(stderr, "FACT_TEST_TIME_SCALE='%s' is not a number >= 1\n", text);
      std::abort();
    }
    return s;
  }();
  return scale;
}

// A deadline of `seconds` at native speed, in seconds here.
inline double scaled_s(double seconds) { return seconds * time_scale(); }

// The same as a steady_clock duration.
inline std::chrono::steady_clock::duration scaled(std::chrono::duration<double> d) {
  return std::chrono::duration_cast<std::chrono::steady_clock::duration>(d * time_scale());
}

}  // namespace fact::test
