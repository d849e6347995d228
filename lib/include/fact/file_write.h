// Writing a whole file or nothing: the offline tools' results and scenarios.
#pragma once

#include <string>

namespace fact {

// Writes `text` to `path` as a whole: into "<path>.partial-<pid>" in the same directory, flushed
// to the disk (fsync), then renamed over `path`. A failed write (a full disk, an unwritable
// directory) leaves `path` as it was (an earlier result is not lost) and removes the partial file.
// A path that exists and is not a regular file (/dev/stdout, /dev/null, a FIFO) is written in
// place: renaming over a device would replace it. Returns "" or the reason, naming the path.
std::string write_file_atomically(const std::string& path, const std::string& text);

// Whether two paths name the same existing file (same device and inode), or are the same text.
bool same_file(const std::string& a, const std::string& b);

}  // namespace fact
