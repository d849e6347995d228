// Reading a small input file whole: a world, a camera's intrinsics.
#pragma once

#include <cstddef>
#include <string>

namespace fact {

// Reads the file at `path` (symbolic links followed) into *text, at most max_bytes, to its end: a
// regular file (its size is not trusted: /proc files report 0), or a pipe or FIFO (a shell's
// <(...)); a FIFO that no process has open for writing reads as empty rather than blocking (one a
// writer holds open is read until it closes, as cat would). Returns "" or the reason, naming the
// path: it cannot be opened, it is a device or a directory (/dev/zero grew the reader without
// end), or it holds more than max_bytes.
std::string read_small_file(const std::string& path, std::size_t max_bytes, std::string* text);

}  // namespace fact
