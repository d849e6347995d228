#include "fact/file_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace fact {

std::string read_small_file(const std::string& path, std::size_t max_bytes, std::string* text) {
  // Opened without blocking (a FIFO's open waits for a writer otherwise), then read blocking.
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return path + ": cannot open: " + std::strerror(errno);
  struct stat st {};
  std::string why;
  if (::fstat(fd, &st) != 0) {
    why = path + ": cannot stat: " + std::strerror(errno);
  } else if (!S_ISREG(st.st_mode) && !S_ISFIFO(st.st_mode) && !S_ISSOCK(st.st_mode)) {
    why = path + (S_ISDIR(st.st_mode) ? ": a directory" : ": a device, not a file");
  } else if (::fcntl(fd, F_SETFL, ::fcntl(fd, F_GETFL) & ~O_NONBLOCK) != 0) {
    why = path + ": cannot read: " + std::strerror(errno);
  } else {
    std::string out;
    char buf[65536];
    for (;;) {
      const ssize_t n = ::read(fd, buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n < 0) {
        why = path + ": read failed: " + std::strerror(errno);
        break;
      }
      if (n == 0) break;
      out.append(buf, static_cast<std::size_t>(n));
      if (out.size() > max_bytes) {
        why = path + ": more than the " + std::to_string(max_bytes) + " bytes expected";
        break;
      }
    }
    if (why.empty()) *text = std::move(out);
  }
  ::close(fd);
  return why;
}

}  // namespace fact
