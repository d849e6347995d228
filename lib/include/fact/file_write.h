// Writing a whole file or nothing: the offline tools' results and scenarios.
#pragma once

#include <string>

namespace fact {

// Writes `text` to `path` as a whole: into a fresh "<file>.partial-XXXXXX" (mkstemp) beside the
// file, flushed to the disk (fsync), given the old file's mode and owner, then renamed over it.
// A failed write (a full disk, an unwritable directory) leaves the file as it was (an earlier
// result is not lost) and removes the partial file. A symbolic link is followed to its regular
// file (the link stays); a path that is not a regular file (/dev/null, a pipe) is written in
// place, since renaming over it would replace it, and a path into /dev or /proc (/dev/stdout, or a
// link that leads there) is appended to, as a stream: a file the output is redirected to keeps
// what was written before. A hard link to the old file keeps
// the old contents. Returns "" or the reason, naming the path.
std::string write_file_atomically(const std::string& path, const std::string& text);

// The partial file write_file_atomically writes into, for a writer that streams (fact-log-merge):
// a fresh "<target>.partial-XXXXXX" beside `target` (mkstemp: O_EXCL, never an existing file or
// link), with target's mode and owner when it exists, else 0666 less the umask, as open() gives.
// Returns its descriptor, with its name in *partial, or −1 (errno set).
int open_partial_file(const std::string& target, std::string* partial);

// Whether two paths name the same file: the same device and inode when both exist, else the same
// path once made absolute and normalised ("a.json" and "./a.json").
bool same_file(const std::string& a, const std::string& b);

}  // namespace fact
