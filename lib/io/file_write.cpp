#include "fact/file_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <climits>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <system_error>

namespace fact {
namespace {

// Writes all of text to fd; "" or the reason.
std::string write_all(int fd, const std::string& text) {
  std::size_t done = 0;
  while (done < text.size()) {
    const ssize_t n = ::write(fd, text.data() + done, text.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) return std::strerror(errno);
    done += static_cast<std::size_t>(n);
  }
  return "";
}

// `stream`: a path into /dev or /proc (/dev/stdout): appended to, as a stream is written, so that
// a file the process's output is redirected to keeps what came before (a regular file is
// truncated first).
std::string write_in_place(const std::string& path, const std::string& text, bool stream) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | (stream ? O_APPEND : O_TRUNC), 0666);
  if (fd < 0) return path + ": cannot open for writing: " + std::strerror(errno);
  std::string e = write_all(fd, text);
  if (::close(fd) != 0 && e.empty()) e = std::strerror(errno);
  return e.empty() ? "" : path + ": write failed: " + e;
}

// The regular file `path` names, following symbolic links; "" when it names something else (a
// device, a pipe), does not resolve, or any link on the way points into /dev or /proc: the
// /dev/stdout of a process whose output goes to a file resolves to that file, and replacing it
// would cut the output off from everything written before and after (review, session 32).
std::string regular_target(const std::string& path, bool* stream) {
  *stream = false;
  std::string hop = path;
  for (int n = 0; n < 40; ++n) {
    struct stat st {};
    if (::lstat(hop.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) break;
    if (hop.rfind("/dev/", 0) == 0 || hop.rfind("/proc/", 0) == 0) {  // /dev/stdout, /proc/self/fd/1
      *stream = true;
      return "";
    }
    char next[PATH_MAX];
    const ssize_t len = ::readlink(hop.c_str(), next, sizeof next - 1);
    if (len < 0) return "";
    next[len] = '\0';
    std::string to = next;
    if (to.rfind("/dev/", 0) == 0 || to.rfind("/proc/", 0) == 0) {
      *stream = true;
      return "";
    }
    if (to.empty() || to[0] != '/') to = std::filesystem::path(hop).parent_path().string() + "/" + to;
    hop = to;
  }
  char real[PATH_MAX];
  if (::realpath(path.c_str(), real) == nullptr) return "";
  struct stat st {};
  if (::stat(real, &st) != 0 || !S_ISREG(st.st_mode)) return "";
  if (std::strncmp(real, "/proc/", 6) == 0 || std::strncmp(real, "/dev/", 5) == 0) return "";
  return real;
}

}  // namespace

int open_partial_file(const std::string& target, std::string* partial) {
  struct stat st {};
  const bool exists = ::stat(target.c_str(), &st) == 0;
  *partial = target + ".partial-XXXXXX";
  const int fd = ::mkstemp(partial->data());
  if (fd < 0) return -1;
  // The file keeps its mode and owner; a new one gets 0666 less the umask, as open() would give.
  if (exists) {
    (void)::fchmod(fd, st.st_mode & 07777);
    (void)::fchown(fd, st.st_uid, st.st_gid);  // (only root may; otherwise the owner is the writer)
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    (void)::fchmod(fd, 0666 & ~mask);
  }
  return fd;
}

std::string write_file_atomically(const std::string& path, const std::string& text) {
  struct stat st {};
  std::string target = path;
  bool stream = false;
  if (::lstat(path.c_str(), &st) == 0) {
    // A symbolic link is followed to its regular file (the link stays a link); /dev/stdout, a
    // device or a pipe is written in place: renaming over it would replace it (as root, for
    // every process of the machine: review, session 32).
    if (S_ISLNK(st.st_mode)) target = regular_target(path, &stream);
    else if (!S_ISREG(st.st_mode)) target = "";
    if (target.empty()) return write_in_place(path, text, stream);
    if (::stat(target.c_str(), &st) != 0) return write_in_place(path, text, false);
  }
  std::string partial;
  const int fd = open_partial_file(target, &partial);
  if (fd < 0) return path + ": cannot create a temporary file beside it: " + std::strerror(errno);
  std::string e = write_all(fd, text);
  if (e.empty() && ::fsync(fd) != 0) e = std::strerror(errno);
  if (::close(fd) != 0 && e.empty()) e = std::strerror(errno);
  if (e.empty() && std::rename(partial.c_str(), target.c_str()) != 0) e = std::string("rename: ") + std::strerror(errno);
  if (e.empty()) return "";
  std::remove(partial.c_str());
  return path + ": write failed (" + e + "); the file is unchanged";
}

bool same_file(const std::string& a, const std::string& b) {
  struct stat sa {}, sb {};
  if (::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0) return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
  // (files not written yet: the same path spelled two ways, "a.json" and "./a.json")
  std::error_code ea, eb;
  const std::filesystem::path ca = std::filesystem::weakly_canonical(std::filesystem::absolute(a, ea), ea),
                              cb = std::filesystem::weakly_canonical(std::filesystem::absolute(b, eb), eb);
  return a == b || (!ea && !eb && ca == cb);
}

}  // namespace fact
