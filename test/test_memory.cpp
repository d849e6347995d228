// fact::keep_freed_memory (lib/memory.cpp): on glibc a large block comes from the heap and the
// heap keeps it after free, so the next solve reuses the memory instead of faulting it in.
#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "fact/memory.h"

#if defined(__GLIBC__)
#include <malloc.h>
#endif

namespace {

TEST(KeepFreedMemory, LargeBlocksComeFromTheHeapAndStayThere) {
#if defined(__GLIBC__)
  ASSERT_TRUE(fact::keep_freed_memory());
  constexpr std::size_t kBlock = 16 << 20;  // far above glibc's default mapping threshold (128 KiB)
  const struct mallinfo2 before = mallinfo2();
  void* block = std::malloc(kBlock);
  ASSERT_NE(block, nullptr);
  std::memset(block, 1, kBlock);
  const struct mallinfo2 held = mallinfo2();
  EXPECT_EQ(held.hblkhd, before.hblkhd) << "the block was mapped, not taken from the heap";
  EXPECT_GE(held.arena, kBlock) << "the heap is smaller than the block it holds";
  std::free(block);
  const struct mallinfo2 after = mallinfo2();
  EXPECT_EQ(after.arena, held.arena) << "free gave the heap's top back to the kernel";
#else
  GTEST_SKIP() << "keep_freed_memory only has a policy to set on glibc";
#endif
}

}  // namespace
