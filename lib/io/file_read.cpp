#include "fact/file_read.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

namespace fact {

std::string read_regular_file(const std::string& path, std::size_t max_bytes, std::string* text) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) return path + ": cannot open: " + std::strerror(errno);
  struct stat st {};
  std::string why;
  if (::fstat(fd, &st) != 0) {
    why = path + ": cannot stat: " + std::strerror(errno);
  } else if (!S_ISREG(st.st_mode)) {
    why = path + ": not a regular file";
  } else if (static_cast<std::size_t>(st.st_size) > max_bytes) {
    why = path + ": " + std::to_string(st.st_size) + " bytes, more than the " + std::to_string(max_bytes) + " expected";
  } else {
    text->assign(static_cast<std::size_t>(st.st_size), '\0');
    std::size_t got = 0;
    while (got < text->size()) {
      const ssize_t n = ::read(fd, text->data() + got, text->size() - got);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) {
        why = path + ": read failed" + (n < 0 ? std::string(": ") + std::strerror(errno) : std::string(" (shorter than its size)"));
        break;
      }
      got += static_cast<std::size_t>(n);
    }
  }
  ::close(fd);
  return why;
}

}  // namespace fact
