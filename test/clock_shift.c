// LD_PRELOAD shim for tests: the wall clock (CLOCK_REALTIME and its coarse variant) of the process
// it is preloaded into runs shifted by the number of seconds written in the file named by
// FACT_CLOCK_SHIFT_FILE (0 while the file is missing or unreadable; re-read at most every 5 ms of
// the steady clock). The steady clock is not touched. test_planner_app.cpp and test_fc_bridge.cpp
// step an app's wall clock by an hour with it. A test shim only: its statics are not synchronised
// and it reads a file inside clock_gettime, fine for the single-threaded apps it is preloaded into.
#define _GNU_SOURCE
#include <dlfcn.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

static int (*real_clock_gettime)(clockid_t, struct timespec*);

static double shift_seconds(void) {
  static double shift = 0;
  static long long read_at_ns = -1;
  struct timespec now;
  real_clock_gettime(CLOCK_MONOTONIC, &now);
  const long long ns = (long long)now.tv_sec * 1000000000LL + now.tv_nsec;
  if (read_at_ns >= 0 && ns - read_at_ns < 5000000) return shift;
  read_at_ns = ns;
  const char* path = getenv("FACT_CLOCK_SHIFT_FILE");
  FILE* f = path ? fopen(path, "r") : NULL;
  double value = 0;
  if (f) {
    if (fscanf(f, "%lf", &value) != 1) value = 0;
    fclose(f);
  }
  shift = value;
  return shift;
}

int clock_gettime(clockid_t id, struct timespec* ts) {
  if (!real_clock_gettime) real_clock_gettime = (int (*)(clockid_t, struct timespec*))dlsym(RTLD_NEXT, "clock_gettime");
  const int r = real_clock_gettime(id, ts);
  if (r != 0 || (id != CLOCK_REALTIME && id != CLOCK_REALTIME_COARSE)) return r;
  const long long shift_ns = (long long)(shift_seconds() * 1e9);
  long long total = (long long)ts->tv_sec * 1000000000LL + ts->tv_nsec + shift_ns;
  ts->tv_sec = (time_t)(total / 1000000000LL);
  ts->tv_nsec = (long)(total % 1000000000LL);
  if (ts->tv_nsec < 0) {
    ts->tv_nsec += 1000000000L;
    ts->tv_sec -= 1;
  }
  return r;
}
