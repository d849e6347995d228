// UDP and serial links of fact-fc-bridge.
#include "link.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <sys/socket.h>
#include <termios.h>
#include <unistd.h>

#include <cstring>
#include <utility>

namespace fact::bridge {

namespace {

std::string errno_text() { return std::strerror(errno); }

int parse_port(const std::string& text, const std::string& what, const std::string& whole) {
  std::size_t used = 0;
  int port = -1;
  try {
    port = std::stoi(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != text.size() || text.empty() || port < 1 || port > 65535)
    throw LinkSpecError("--udp: " + what + " '" + text + "' in '" + whole + "' is not a port 1..65535");
  return port;
}

class UdpLink : public Link {
 public:
  UdpLink(int fd, sockaddr_in remote, std::string text) : fd_(fd), remote_(remote), text_(std::move(text)) {}
  ~UdpLink() override { ::close(fd_); }
  int fd() const override { return fd_; }
  bool send(const std::vector<uint8_t>& bytes, std::string* error) override {
    const ssize_t n = ::sendto(fd_, bytes.data(), bytes.size(), 0, reinterpret_cast<const sockaddr*>(&remote_), sizeof remote_);
    if (n == static_cast<ssize_t>(bytes.size())) return true;
    *error = n < 0 ? "sendto " + text_ + ": " + errno_text() : "sendto " + text_ + ": short write";
    return false;
  }
  long receive(uint8_t* buf, std::size_t n, std::string* error) override {
    sockaddr_in from{};
    socklen_t length = sizeof from;
    const ssize_t got = ::recvfrom(fd_, buf, n, 0, reinterpret_cast<sockaddr*>(&from), &length);
    if (got >= 0) {
      if (from.sin_addr.s_addr == remote_.sin_addr.s_addr && from.sin_port == remote_.sin_port) return static_cast<long>(got);
      ignored_ = "ignored a " + std::to_string(got) + "-byte datagram from " + address(from) +
                 ", not the flight controller " + address(remote_);
      return 0;
    }
    if (errno == EAGAIN || errno == EWOULDBLOCK || errno == EINTR || errno == ECONNREFUSED) return 0;
    *error = "recv on " + text_ + ": " + errno_text();
    return -1;
  }
  std::string take_ignored() override { return std::exchange(ignored_, std::string()); }
  bool datagrams() const override { return true; }
  std::string describe() const override { return "udp " + text_; }

 private:
  static std::string address(const sockaddr_in& a) {
    char host[INET_ADDRSTRLEN] = "?";
    ::inet_ntop(AF_INET, &a.sin_addr, host, sizeof host);
    return std::string(host) + ":" + std::to_string(ntohs(a.sin_port));
  }
  int fd_;
  sockaddr_in remote_;
  std::string text_;
  std::string ignored_;  // the last dropped datagram's description, until take_ignored()
};

struct BaudEntry {
  int baud;
  speed_t speed;
};
const BaudEntry kBauds[] = {{9600, B9600},     {19200, B19200},     {38400, B38400},     {57600, B57600},
                            {115200, B115200}, {230400, B230400},   {460800, B460800},   {500000, B500000},
                            {576000, B576000}, {921600, B921600},   {1000000, B1000000}, {1500000, B1500000},
                            {2000000, B2000000}, {3000000, B3000000}};

class SerialLink : public Link {
 public:
  SerialLink(int fd, std::string text) : fd_(fd), text_(std::move(text)) {}
  ~SerialLink() override { ::close(fd_); }
  int fd() const override { return fd_; }
  bool send(const std::vector<uint8_t>& bytes, std::string* error) override {
    std::size_t done = 0;
    int spins = 0;
    while (done < bytes.size()) {
      const ssize_t n = ::write(fd_, bytes.data() + done, bytes.size() - done);
      if (n > 0) {
        done += static_cast<std::size_t>(n);
        continue;
      }
      if (n < 0 && errno != EAGAIN && errno != EINTR) {
        *error = "write " + text_ + ": " + errno_text();
        return false;
      }
      if (++spins > 100) {  // the UART is not draining: drop rather than block the loop
        *error = "write " + text_ + ": output buffer full (" + std::to_string(bytes.size() - done) + " bytes dropped)";
        return false;
      }
      ::usleep(100);
    }
    return true;
  }
  long receive(uint8_t* buf, std::size_t n, std::string* error) override {
    const ssize_t got = ::read(fd_, buf, n);
    if (got > 0) return static_cast<long>(got);
    if (got < 0 && (errno == EAGAIN || errno == EINTR)) return 0;
    *error = got == 0 ? "serial device " + text_ + " closed" : "read " + text_ + ": " + errno_text();
    return -1;
  }
  std::string describe() const override { return "serial " + text_; }

 private:
  int fd_;
  std::string text_;
};

}  // namespace

UdpSpec parse_udp_spec(const std::string& text) {
  const auto a = text.find(':');
  const auto b = text.rfind(':');
  if (a == std::string::npos || a == b)
    throw LinkSpecError("--udp: expected LOCAL_PORT:REMOTE_HOST:REMOTE_PORT, got '" + text + "'");
  UdpSpec s;
  s.local_port = parse_port(text.substr(0, a), "local port", text);
  s.remote_host = text.substr(a + 1, b - a - 1);
  if (s.remote_host.empty()) throw LinkSpecError("--udp: empty remote host in '" + text + "'");
  s.remote_port = parse_port(text.substr(b + 1), "remote port", text);
  return s;
}

std::unique_ptr<Link> open_udp(const UdpSpec& spec) {
  sockaddr_in remote{};
  remote.sin_family = AF_INET;
  remote.sin_port = htons(static_cast<uint16_t>(spec.remote_port));
  if (::inet_pton(AF_INET, spec.remote_host.c_str(), &remote.sin_addr) != 1) {
    addrinfo hints{};
    hints.ai_family = AF_INET;
    hints.ai_socktype = SOCK_DGRAM;
    addrinfo* found = nullptr;
    const int rc = ::getaddrinfo(spec.remote_host.c_str(), nullptr, &hints, &found);
    if (rc != 0 || found == nullptr)
      throw LinkError("cannot resolve UDP remote host '" + spec.remote_host + "': " + ::gai_strerror(rc));
    remote.sin_addr = reinterpret_cast<sockaddr_in*>(found->ai_addr)->sin_addr;
    ::freeaddrinfo(found);
  }
  const int fd = ::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) throw LinkError("cannot create a UDP socket: " + errno_text());
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(static_cast<uint16_t>(spec.local_port));
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw LinkError("cannot bind UDP port " + std::to_string(spec.local_port) + ": " + why);
  }
  return std::make_unique<UdpLink>(fd, remote,
                                   std::to_string(spec.local_port) + " -> " + spec.remote_host + ":" + std::to_string(spec.remote_port));
}

std::string supported_bauds() {
  std::string s;
  for (const BaudEntry& e : kBauds) s += (s.empty() ? "" : ", ") + std::to_string(e.baud);
  return s;
}

void check_baud(int baud) {
  for (const BaudEntry& e : kBauds)
    if (e.baud == baud) return;
  throw LinkSpecError("--baud: " + std::to_string(baud) + " is not a supported rate (" + supported_bauds() + ")");
}

std::unique_ptr<Link> open_serial(const std::string& device, int baud) {
  check_baud(baud);
  speed_t speed = B0;
  for (const BaudEntry& e : kBauds)
    if (e.baud == baud) speed = e.speed;
  const int fd = ::open(device.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) throw LinkError("cannot open serial device '" + device + "': " + errno_text());
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw LinkError("'" + device + "' is not a serial device (tcgetattr: " + why + ")");
  }
  ::cfmakeraw(&t);                       // raw bytes: no echo, no line editing, no translation
  t.c_cflag &= ~static_cast<tcflag_t>(CSTOPB | PARENB | CRTSCTS | CSIZE);
  t.c_cflag |= CS8 | CLOCAL | CREAD;     // 8N1, ignore modem lines, enable the receiver
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
  if (::cfsetispeed(&t, speed) != 0 || ::cfsetospeed(&t, speed) != 0 || ::tcsetattr(fd, TCSANOW, &t) != 0) {
    const std::string why = errno_text();
    ::close(fd);
    throw LinkError("cannot configure '" + device + "' for " + std::to_string(baud) + " baud 8N1: " + why);
  }
  ::tcflush(fd, TCIOFLUSH);
  return std::make_unique<SerialLink>(fd, device + " @ " + std::to_string(baud) + " 8N1");
}

}  // namespace fact::bridge
