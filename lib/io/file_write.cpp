#include "fact/file_write.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

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
  const int fd = ::open(path.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
  if (fd < 0) return path + ": cannot open for writing: " + std::strerror(errno);
  const std::string e = write_all(fd, text);
  ::close(fd);
  return e.empty() ? "" : path + ": write failed: " + e;
}

}  // namespace

std::string write_file_atomically(const std::string& path, const std::string& text) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && !S_ISREG(st.st_mode)) return write_in_place(path, text);
  const std::string partial = path + ".partial-" + std::to_string(::getpid());
  const int fd = ::open(partial.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) return path + ": cannot open " + partial + " for writing: " + std::strerror(errno);
  std::string e = write_all(fd, text);
  if (e.empty() && ::fsync(fd) != 0) e = std::strerror(errno);
  if (::close(fd) != 0 && e.empty()) e = std::strerror(errno);
  if (e.empty() && std::rename(partial.c_str(), path.c_str()) != 0) e = std::string("rename: ") + std::strerror(errno);
  if (e.empty()) return "";
  std::remove(partial.c_str());
  return path + ": write failed (" + e + "); the file is unchanged";
}

bool same_file(const std::string& a, const std::string& b) {
  if (a == b) return true;
  struct stat sa {}, sb {};
  return ::stat(a.c_str(), &sa) == 0 && ::stat(b.c_str(), &sb) == 0 && sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
}

}  // namespace fact
