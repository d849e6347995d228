// Reading a small input file whole: a world, a camera's intrinsics.
#pragma once

#include <cstddef>
#include <string>

namespace fact {

// Reads the regular file at `path` (symbolic links followed) into *text, at most max_bytes.
// Returns "" or the reason, naming the path: it cannot be opened, it is not a regular file (a FIFO
// with no writer hung the reader, /dev/zero grew it without end), or it is larger than max_bytes.
// The file is opened without blocking, so a FIFO is refused rather than waited on.
std::string read_regular_file(const std::string& path, std::size_t max_bytes, std::string* text);

}  // namespace fact
