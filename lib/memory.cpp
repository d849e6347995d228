#include "fact/memory.h"

// <cstdlib> first: on glibc it includes <features.h>, which defines __GLIBC__. Without it the
// test below was false on every platform and the policy was never set (found in session 21: a
// tight-form N = 100 solve after the call still page-faulted 689 times).
#include <cstdlib>

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace fact {

bool keep_freed_memory() {
#if defined(__GLIBC__)
  constexpr int kNeverTrim = -1;                   // M_TRIM_THRESHOLD < 0: never give the heap's top back
  constexpr int kLargestHeapBlock = 32 << 20;      // glibc's upper limit for M_MMAP_THRESHOLD on 64-bit
  return mallopt(M_TRIM_THRESHOLD, kNeverTrim) == 1 && mallopt(M_MMAP_THRESHOLD, kLargestHeapBlock) == 1;
#else
  return false;
#endif
}

}  // namespace fact
