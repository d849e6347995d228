#include "fact_gossip/wire.h"

#include "common/convert.h"

#include <sodium.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <utility>

namespace fact::app {

static_assert(crypto_auth_KEYBYTES == 32, "the swarm key is 32 bytes");
static_assert(crypto_auth_BYTES == 32, "the mac field is 32 bytes");

std::string init_crypto() {
  if (sodium_init() < 0) return "libsodium failed to initialise";
  return "";
}

std::string parse_key(const std::string& contents, SwarmKey* key) {
  SwarmKey k;
  if (contents.size() == 32) {
    std::memcpy(k.bytes.data(), contents.data(), 32);
  } else {
    std::string hex;
    for (char c : contents) {
      if (std::isspace(static_cast<unsigned char>(c))) continue;
      if (!std::isxdigit(static_cast<unsigned char>(c)))
        return std::string("not a key: the character '") + (std::isprint(static_cast<unsigned char>(c)) ? std::string(1, c) : "?") +
               "' is not a hexadecimal digit (expected 32 raw bytes or 64 hex digits)";
      hex.push_back(c);
    }
    if (hex.size() != 64)
      return "not a key: " + std::to_string(hex.size()) + " hex digits, expected 64 (or exactly 32 raw bytes; the file has " +
             std::to_string(contents.size()) + " bytes)";
    for (size_t i = 0; i < 32; ++i) k.bytes[i] = static_cast<unsigned char>(std::stoi(hex.substr(2 * i, 2), nullptr, 16));
  }
  bool zero = true;
  for (unsigned char b : k.bytes) zero = zero && b == 0;
  if (zero) return "the key is all zero";
  k.insecure = false;
  *key = k;
  return "";
}

std::string load_key(const std::string& path, SwarmKey* key) {
  std::ifstream f(path, std::ios::binary);
  if (!f) return path + ": cannot open: " + std::strerror(errno);
  // At most 4097 bytes: /dev/zero (or any endless stream) as a key file grew without end.
  std::string contents(4097, '\0');
  f.read(contents.data(), static_cast<std::streamsize>(contents.size()));
  if (f.bad()) return path + ": read failed";
  contents.resize(static_cast<std::size_t>(f.gcount()));
  if (contents.size() > 4096) return path + ": more than 4096 bytes, too large for a key file";
  std::string e = parse_key(contents, key);
  return e.empty() ? "" : path + ": " + e;
}

std::string apply_session(const std::string& session, SwarmKey* key) {
  if (key->insecure) return "a session needs a swarm key (--key-file), not --insecure";
  if (session.empty() || session.size() > 64)
    return "session \"" + session + "\" has " + std::to_string(session.size()) + " characters (1 … 64)";
  for (char c : session)
    if (!std::isalnum(static_cast<unsigned char>(c)) && c != '.' && c != '_' && c != ':' && c != '-')
      return "session \"" + session + "\": the character '" + std::string(1, std::isprint(static_cast<unsigned char>(c)) ? c : '?') +
             "' is not one of A-Z a-z 0-9 . _ : -";
  const std::string label = "fact-gossip session " + session;
  std::array<unsigned char, crypto_auth_BYTES> derived{};
  crypto_auth(derived.data(), reinterpret_cast<const unsigned char*>(label.data()), label.size(), key->bytes.data());
  std::copy(derived.begin(), derived.end(), key->bytes.begin());
  return "";
}

std::vector<unsigned char> mac_input(const fact::gossip_packet_t& m) {
  std::vector<unsigned char> in;
  in.reserve(13 + m.payload.size());
  in.push_back(static_cast<unsigned char>(m.kind));
  const uint32_t s = static_cast<uint32_t>(m.sender_id);
  for (int i = 3; i >= 0; --i) in.push_back(static_cast<unsigned char>(s >> (8 * i)));
  const uint64_t q = static_cast<uint64_t>(m.seq);
  for (int i = 7; i >= 0; --i) in.push_back(static_cast<unsigned char>(q >> (8 * i)));
  in.insert(in.end(), m.payload.begin(), m.payload.end());
  return in;
}

void seal(fact::gossip_packet_t* m, const SwarmKey& key) {
  std::memset(m->mac, 0, sizeof m->mac);
  if (key.insecure) return;
  const std::vector<unsigned char> in = mac_input(*m);
  unsigned char mac[crypto_auth_BYTES];
  crypto_auth(mac, in.data(), in.size(), key.bytes.data());
  std::memcpy(m->mac, mac, sizeof m->mac);
}

bool verify(const fact::gossip_packet_t& m, const SwarmKey& key) {
  if (key.insecure) return true;
  const std::vector<unsigned char> in = mac_input(m);
  unsigned char mac[crypto_auth_BYTES];
  std::memcpy(mac, m.mac, sizeof mac);
  return crypto_auth_verify(mac, in.data(), in.size(), key.bytes.data()) == 0;
}

fact::gossip_packet_t make_envelope(int sender, int64_t seq, int8_t kind, std::vector<uint8_t> payload, int64_t utime,
                                    const SwarmKey& key) {
  fact::gossip_packet_t m;
  m.utime = utime;
  m.sender_id = sender;
  m.seq = seq;
  m.kind = kind;
  m.payload_size = static_cast<int32_t>(payload.size());
  m.payload = std::move(payload);
  seal(&m, key);
  return m;
}

fact::round_packet_t packet_to_message(const gossip::Packet& p) {
  return to_message(p.origin, p.round, p.data, p.utime);
}

std::string packet_from_message(const fact::round_packet_t& m, gossip::Packet* out) {
  gossip::Packet p;
  std::string e = from_message(m, &p.data);
  if (!e.empty()) return e;
  p.origin = m.drone_id;
  p.round = m.round;
  p.utime = m.utime;
  *out = std::move(p);
  return "";
}

fact::gossip_summary_t summary_to_message(const gossip::Summary& s, int64_t utime) {
  fact::gossip_summary_t m;
  m.utime = utime;
  m.drone_id = s.sender;
  m.count = static_cast<int32_t>(s.entries.size());
  for (const gossip::SummaryEntry& e : s.entries) {
    m.origins.push_back(e.origin);
    m.rounds_held.push_back(e.rounds_held);
    m.digests.push_back(static_cast<int64_t>(e.digest));
  }
  return m;
}

std::string summary_from_message(const fact::gossip_summary_t& m, gossip::Summary* out) {
  const std::string at = "summary from drone " + std::to_string(m.drone_id) + ": ";
  if (m.count < 0 || static_cast<size_t>(m.count) != m.origins.size() || m.origins.size() != m.rounds_held.size() ||
      m.origins.size() != m.digests.size())
    return at + "count is " + std::to_string(m.count) + " but the arrays have " + std::to_string(m.origins.size()) + ", " +
           std::to_string(m.rounds_held.size()) + ", " + std::to_string(m.digests.size()) + " entries";
  gossip::Summary s;
  s.sender = m.drone_id;
  for (size_t i = 0; i < m.origins.size(); ++i)
    s.entries.push_back({m.origins[i], m.rounds_held[i], static_cast<uint64_t>(m.digests[i])});
  *out = std::move(s);
  return "";
}

fact::gossip_request_t request_to_message(const gossip::Request& r, int64_t utime) {
  fact::gossip_request_t m;
  m.utime = utime;
  m.drone_id = r.requester;
  m.origin = r.origin;
  m.count = static_cast<int32_t>(r.rounds.size());
  m.rounds.assign(r.rounds.begin(), r.rounds.end());
  return m;
}

std::string request_from_message(const fact::gossip_request_t& m, gossip::Request* out) {
  if (m.count < 0 || static_cast<size_t>(m.count) != m.rounds.size())
    return "request from drone " + std::to_string(m.drone_id) + ": count is " + std::to_string(m.count) + " but rounds has " +
           std::to_string(m.rounds.size());
  gossip::Request r;
  r.requester = m.drone_id;
  r.origin = m.origin;
  r.rounds.assign(m.rounds.begin(), m.rounds.end());
  *out = std::move(r);
  return "";
}

fact::gossip_challenge_t challenge_to_message(int peer, const gossip::Nonce& nonce, int64_t utime) {
  fact::gossip_challenge_t m;
  m.utime = utime;
  m.peer_id = peer;
  std::copy(nonce.begin(), nonce.end(), m.nonce);
  return m;
}

gossip::Nonce random_nonce() {
  gossip::Nonce n;
  randombytes_buf(n.data(), n.size());
  return n;
}

}  // namespace fact::app
