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

std::string write_in_place(const std::string& path, const std::string& text) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) return path + ": cannot open for writing: " + std::strerror(errno);
  std::string e = write_all(fd, text);
  if (::close(fd) != 0 && e.empty()) e = std::strerror(errno);
  return e.empty() ? "" : path + ": write failed: " + e;
}

// The regular file `path` names, following symbolic links; "" when it names something else (a
// device, a pipe, /proc/self/fd/N of a terminal) or does not resolve.
std::string regular_target(const std::string& path) {
  char real[PATH_MAX];
  if (::realpath(path.c_str(), real) == nullptr) return "";
  struct stat st {};
  if (::stat(real, &st) != 0 || !S_ISREG(st.st_mode)) return "";
  if (std::strncmp(real, "/proc/", 6) == 0 || std::strncmp(real, "/dev/", 5) == 0) return "";
  return real;
}

}  // namespace

std::string write_file_atomically(const std::string& path, const std::string& text) {
  struct stat st {};
  std::string target = path;
  if (::lstat(path.c_str(), &st) == 0) {
    // A symbolic link is followed to its regular file (the link stays a link); /dev/stdout, a
    // device or a pipe is written in place: renaming over it would replace it (as root, for
    // every process of the machine: review, session 32).
    if (S_ISLNK(st.st_mode)) target = regular_target(path);
    else if (!S_ISREG(st.st_mode)) target = "";
    if (target.empty()) return write_in_place(path, text);
    if (::stat(target.c_str(), &st) != 0) return write_in_place(path, text);
  } else {
    st.st_mode = 0;
  }
  // A fresh name in the target's directory (mkstemp: O_EXCL, never an existing file or link).
  std::string partial = target + ".partial-XXXXXX";
  const int fd = ::mkstemp(partial.data());
  if (fd < 0) return path + ": cannot create a temporary file beside it: " + std::strerror(errno);
  // The file keeps its mode and owner; a new one gets 0666 less the umask, as open() would give.
  if (st.st_mode != 0) {
    (void)::fchmod(fd, st.st_mode & 07777);
    (void)::fchown(fd, st.st_uid, st.st_gid);  // (only root may; otherwise the owner is the writer)
  } else {
    const mode_t mask = ::umask(0);
    ::umask(mask);
    (void)::fchmod(fd, 0666 & ~mask);
  }
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
  const std::filesystem::path ca = std::filesystem::weakly_canonical(a, ea), cb = std::filesystem::weakly_canonical(b, eb);
  return a == b || (!ea && !eb && ca == cb);
}

}  // namespace fact
