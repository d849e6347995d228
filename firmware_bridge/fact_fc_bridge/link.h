// The byte links of fact-fc-bridge to the flight controller: UDP (e.g. PX4 SITL) or a serial port
// (termios raw 8N1). Both are non-blocking; the app polls fd().
#pragma once

#include <netinet/in.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace fact::bridge {

// A link that cannot be set up (bad address, device that cannot be opened): exit 1.
struct LinkError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
// A link description that is wrong as written (a flag value): exit 2.
struct LinkSpecError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Link {
 public:
  virtual ~Link() = default;
  virtual int fd() const = 0;
  // Sends one frame (or several, concatenated). False with *error set when the bytes could not go out.
  virtual bool send(const std::vector<uint8_t>& bytes, std::string* error) = 0;
  // Reads what is available into buf: > 0 bytes read, 0 nothing now, -1 the link failed (*error set).
  virtual long receive(uint8_t* buf, std::size_t n, std::string* error) = 0;
  // What the last receive() dropped instead of returning ("" when nothing), then "": the UDP link
  // takes datagrams only from the flight controller's address and port.
  virtual std::string take_ignored() { return ""; }
  // Whether receive() returns whole datagrams (UDP) rather than a byte stream (serial).
  virtual bool datagrams() const { return false; }
  virtual std::string describe() const = 0;
};

// "LOCAL_PORT:REMOTE_HOST:REMOTE_PORT": binds UDP LOCAL_PORT on all addresses, sends to the remote
// and takes datagrams only from it (a flight controller replies from the port it listens on, as
// PX4 does; another host or process could otherwise keep "FC connected" alive: review, session 30).
struct UdpSpec {
  int local_port = 0;
  std::string remote_host;
  int remote_port = 0;
};
UdpSpec parse_udp_spec(const std::string& text);  // throws LinkSpecError naming the bad part
std::unique_ptr<Link> open_udp(const UdpSpec& spec);  // throws LinkError

// Standard termios rates. Throws LinkSpecError for any other rate ("--baud: 12345 is not one of ...").
void check_baud(int baud);
std::string supported_bauds();
std::unique_ptr<Link> open_serial(const std::string& device, int baud);  // throws LinkError

}  // namespace fact::bridge
