// fact-gossip's wire format: the authenticated envelope (fact::gossip_packet_t on FACT_GOSSIP)
// and the conversions between lib/'s gossip data (fact/gossip.h) and the LCM messages.
//
// Envelope: payload = the LCM encoding of a round_packet_t (kind ROUND = 1), gossip_summary_t
// (SUMMARY = 2), gossip_request_t (REQUEST = 3) or gossip_challenge_t (CHALLENGE = 4, RESPONSE =
// 5). seq: per sender, +1 per packet, starting at the sender's start time in µs, so a restarted
// sender's numbers exceed the old ones and receivers (which remember a window of numbers per
// sender) do not take its new packets for replays. A sender restarted with its clock set back
// numbers below its old ones: a receiver then sends it a CHALLENGE (a random nonce, peer_id = the
// sender), the sender answers with a RESPONSE carrying the nonce (peer_id = the challenger), and
// the challenger takes the sender's new numbers (fact::gossip::Gossip::answer_challenge).
// mac = crypto_auth (libsodium, HMAC-SHA512-256, 32 bytes) with the 32-byte swarm key over
//   kind (1 byte) | sender_id (4 bytes, big-endian two's complement) | seq (8 bytes, big-endian)
//   | payload (payload_size bytes)
// Every field has a fixed width, so the concatenation is unambiguous. utime is not covered (it is
// informative only). With --insecure the mac is all zero and receivers check nothing.
//
// Session (--session S, with a key): the key becomes crypto_auth("fact-gossip session " + S, key),
// so envelopes of another session (a recording of an earlier flight played on the swarm's bus)
// fail authentication. Without --session the key is used as it is, and envelopes of earlier
// flights with the same key are accepted by a process that has not heard the sender yet.
//
// Key file (--key-file F): either exactly 32 bytes (raw key) or 64 hexadecimal digits (upper or
// lower case; whitespace and line breaks anywhere are ignored). An all-zero key is refused.
// Make one with: head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > swarm.key
#pragma once

#include "fact/gossip.h"
#include "fact/gossip_challenge_t.hpp"
#include "fact/gossip_packet_t.hpp"
#include "fact/gossip_request_t.hpp"
#include "fact/gossip_summary_t.hpp"
#include "fact/round_packet_t.hpp"

#include <array>
#include <cstdint>
#include <string>
#include <vector>

namespace fact::app {

struct SwarmKey {
  std::array<unsigned char, 32> bytes{};
  bool insecure = true;  // no key: packets are sent with a zero mac and not checked
};

// Must be called once before sealing or verifying; "" or why libsodium cannot start.
std::string init_crypto();

// Parses a key file's contents (see the header comment); "" or the reason.
std::string parse_key(const std::string& contents, SwarmKey* key);
// Reads and parses the file; "" or the reason (unreadable, wrong size, not hex, all zero).
std::string load_key(const std::string& path, SwarmKey* key);
// Derives the session's key (see the header comment); "" or why the session name is unusable
// (1 … 64 characters of A–Z a–z 0–9 . _ : -, and a real key).
std::string apply_session(const std::string& session, SwarmKey* key);

// The bytes the mac covers.
std::vector<unsigned char> mac_input(const fact::gossip_packet_t& m);
// Builds an envelope (payload_size, seq, kind, sender, utime) and its mac.
fact::gossip_packet_t make_envelope(int sender, int64_t seq, int8_t kind, std::vector<uint8_t> payload,
                                    int64_t utime, const SwarmKey& key);
// Recomputes the mac (after editing a field, e.g. in tests).
void seal(fact::gossip_packet_t* m, const SwarmKey& key);
// true when the mac matches (always true with an insecure key).
bool verify(const fact::gossip_packet_t& m, const SwarmKey& key);

// LCM encoding of any message to bytes.
template <class T>
std::vector<uint8_t> encode_bytes(const T& msg) {
  std::vector<uint8_t> out(static_cast<size_t>(msg.getEncodedSize()));
  msg.encode(out.data(), 0, static_cast<int>(out.size()));
  return out;
}

// Conversions. from_* return "" or the field and value that is wrong (counts ≠ sizes, NaN, …).
fact::round_packet_t packet_to_message(const gossip::Packet& p);
std::string packet_from_message(const fact::round_packet_t& m, gossip::Packet* out);
fact::gossip_summary_t summary_to_message(const gossip::Summary& s, int64_t utime);
std::string summary_from_message(const fact::gossip_summary_t& m, gossip::Summary* out);
fact::gossip_request_t request_to_message(const gossip::Request& r, int64_t utime);
std::string request_from_message(const fact::gossip_request_t& m, gossip::Request* out);
// A challenge or its response (peer: see fact_gossip_challenge_t.lcm).
fact::gossip_challenge_t challenge_to_message(int peer, const gossip::Nonce& nonce, int64_t utime);
// A fresh random nonce (libsodium; init_crypto first).
gossip::Nonce random_nonce();

}  // namespace fact::app
