// Process-wide memory policy for the apps and benchmarks that run solves repeatedly.
#pragma once

namespace fact {

// Keeps the memory the process frees for its own reuse instead of returning it to the kernel
// (glibc: no heap trimming, allocations up to 32 MB from the heap rather than fresh mappings), so
// a solve does not page-fault its workspace in again each time. An SDP solve of the tight form at
// N = 100 allocates a few MB; handing it back and faulting it in cost a third of the solve's time
// on the development machine (BENCHMARKS.md, session 15). The heap then keeps its high-water mark.
// Call once at the start of main(). Returns false where the C library has no such settings.
bool keep_freed_memory();

}  // namespace fact
