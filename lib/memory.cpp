#include "fact/memory.h"

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
